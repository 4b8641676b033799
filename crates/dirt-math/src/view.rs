//! Views: perspective and orthographic views with a square grid of tiles, the
//! cubemap view set of 004 §3.2 with its face adjacency, a single-view set,
//! and the orthographic sets of 000 §5.3 (one view over the bounds, or two
//! split by a plane).
//!
//! View space: `x = (p - apex)·right`, `y = (p - apex)·up`, `z = (p - apex)·forward`
//! (the depth). A point's *image coordinates* are `x/w`, `y/w`, where `w` is
//! the depth `z` in a perspective view and 1 in an orthographic one
//! ([`View::w`]). A view sees `|x| <= tan·w`, `|y| <= tan·w`, `near <= z <= far`.
//! Tile `(i, j)` of a view with `tiles` tiles per side covers the image
//! coordinates `x/w ∈ [s(i), s(i+1)]`, `y/w ∈ [s(j), s(j+1)]` with
//! `s(k) = k·step − tan`, `step = 2·tan/tiles`. Row `j` grows with `+y`.
//! In a perspective view these are slopes and `tan` is the tangent of the
//! half field of view; in an orthographic view they are distances and `tan`
//! is the half width of the image.
//!
//! Every frustum used for a decision is *dilated* by the view's `eps` (an
//! absolute view-space distance), and every ray's by a per-ray `eps`; see
//! [`crate::clip`]. The dilation is what makes coverage conservative in
//! floating point.

use crate::clip::HalfSpace;
use crate::num::{fmax, fmin};
use crate::types::{Aabb, Ray};
use glam::Vec3;

/// Relative size of the conservative dilation: 2^-16 of the scale of the
/// coordinates involved, far above the few-ulp (2^-24) rounding of each step.
pub const EPS_REL: f32 = 1.0 / 65536.0;

/// Relative size of a ray's dilation: 2^-12 of the scale of its coordinates.
/// Larger than the build's, because it must also cover how far a reported hit
/// point may lie from its triangle (`2^-15 · max|vertex − origin|`, see
/// `triangle::intersect`): that is at most `2^-14 · (|origin| + scale)` in view
/// space, a quarter of this dilation.
pub const EPS_RAY_REL: f32 = 1.0 / 4096.0;

/// One view (perspective, or orthographic when [`View::ortho`]) with its tile grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub apex: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    /// tan of the half field of view (1 for a cube face); the half width of
    /// the image in an orthographic view.
    pub tan: f32,
    pub near: f32,
    pub far: f32,
    /// Tiles per side.
    pub tiles: u32,
    /// Slope width of one tile: `2·tan/tiles`.
    pub step: f32,
    /// Absolute dilation of this view's frusta for building (view-space units).
    pub eps: f32,
    /// Largest |view coordinate| of the scene bounds' corners: the scale of build coordinates.
    pub scale: f32,
    /// False when the view can see no geometry: no part of the scene bounds
    /// is in front of its near plane, or (after [`ViewSet::leave_out_empty`])
    /// no triangle reaches any of its tiles. Such a view gets no build passes,
    /// no memory, and rays skip it.
    pub has_content: bool,
    /// Index of this view's block in the stored per-tile arrays (depth bounds,
    /// Hi-Z levels, list offsets): views with content are numbered densely in
    /// view order; [`NO_SLOT`] for a view without content.
    pub slot: u32,
    /// Orthographic: tile boundaries are the planes `x = s`, `y = s`, not
    /// `x = s·z`, `y = s·z` (module docs).
    pub ortho: bool,
}

/// [`View::slot`] of a view without content.
pub const NO_SLOT: u32 = u32::MAX;

/// A ray expressed in one view's space, with its own dilation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewRay {
    pub o: [f32; 3],
    pub d: [f32; 3],
    pub eps: f32,
}

impl View {
    /// Builds a view and fits `near`, `far`, `eps` to `bounds`.
    /// `near` is a lower bound; `far` is fitted to the bounds' corners.
    pub fn new(
        apex: Vec3,
        right: Vec3,
        up: Vec3,
        forward: Vec3,
        tan: f32,
        near: f32,
        tiles: u32,
        bounds: &Aabb,
    ) -> View {
        let mut v = View {
            apex,
            right,
            up,
            forward,
            tan,
            near,
            far: near,
            tiles,
            step: 2.0 * tan / tiles as f32,
            eps: 0.0,
            scale: near,
            has_content: false,
            slot: NO_SLOT,
            ortho: false,
        };
        let mut far = f32::NEG_INFINITY;
        let mut scale = near;
        for c in corners(bounds) {
            let p = v.to_view(c);
            far = far.max(p[2]);
            scale = scale.max(p[0].abs()).max(p[1].abs()).max(p[2].abs());
        }
        v.has_content = far > near;
        v.scale = scale;
        v.eps = EPS_REL * scale;
        // Fitted far plane, pushed out a little so geometry on the box face is inside.
        v.far = if v.has_content {
            far + 2.0 * v.eps
        } else {
            near
        };
        v
    }

    /// [`View::new`] for an orthographic view of half width `half`.
    #[allow(clippy::too_many_arguments)]
    pub fn orthographic(
        apex: Vec3,
        right: Vec3,
        up: Vec3,
        forward: Vec3,
        half: f32,
        near: f32,
        tiles: u32,
        bounds: &Aabb,
    ) -> View {
        View {
            ortho: true,
            ..View::new(apex, right, up, forward, half, near, tiles, bounds)
        }
    }

    /// The divisor of image coordinates at depth `z`: `z`, clamped to at
    /// least `near/2` (so it stays positive, and bounded where the ray passes
    /// the apex), in a perspective view; exactly 1 in an orthographic one,
    /// where dividing by it changes no bit.
    #[inline]
    pub fn w(&self, z: f32) -> f32 {
        if self.ortho {
            1.0
        } else {
            fmax(z, self.near * 0.5)
        }
    }

    /// The half-space above tile boundary `s` on `axis` (0: x, 1: y).
    #[inline]
    pub fn lo(&self, axis: usize, s: f32) -> HalfSpace {
        if self.ortho {
            HalfSpace::OrthoLo { axis, s }
        } else {
            HalfSpace::Lo { axis, s }
        }
    }

    /// The half-space below tile boundary `s` on `axis` (0: x, 1: y).
    #[inline]
    pub fn hi(&self, axis: usize, s: f32) -> HalfSpace {
        if self.ortho {
            HalfSpace::OrthoHi { axis, s }
        } else {
            HalfSpace::Hi { axis, s }
        }
    }

    /// World point to view space. Written out (no fused operations) so WGSL can mirror it.
    #[inline]
    pub fn to_view(&self, p: Vec3) -> [f32; 3] {
        let q = [p.x - self.apex.x, p.y - self.apex.y, p.z - self.apex.z];
        [dot3(q, self.right), dot3(q, self.up), dot3(q, self.forward)]
    }

    /// World direction to view space.
    #[inline]
    pub fn dir_to_view(&self, d: Vec3) -> [f32; 3] {
        let q = d.to_array();
        [dot3(q, self.right), dot3(q, self.up), dot3(q, self.forward)]
    }

    /// The ray in this view's space, with a dilation that covers the rounding
    /// of its coordinates (which grow with the origin's distance from the apex).
    #[inline]
    pub fn ray(&self, ray: &Ray) -> ViewRay {
        let o = self.to_view(ray.origin());
        let d = self.dir_to_view(ray.dir());
        let m = fmax(fmax(o[0].abs(), o[1].abs()), o[2].abs());
        ViewRay {
            o,
            d,
            eps: EPS_RAY_REL * (m + 2.0 * self.scale),
        }
    }

    /// Slope of tile boundary `k` (0..=tiles).
    #[inline]
    pub fn boundary(&self, k: u32) -> f32 {
        k as f32 * self.step - self.tan
    }

    /// Continuous tile coordinate of slope `s`.
    #[inline]
    pub fn tile_coord(&self, s: f32) -> f32 {
        (s + self.tan) / self.step
    }

    pub fn tile_count(&self) -> usize {
        (self.tiles * self.tiles) as usize
    }
}

#[inline]
pub fn dot3(a: [f32; 3], b: Vec3) -> f32 {
    a[0] * b.x + a[1] * b.y + a[2] * b.z
}

/// The eight corners of a box.
pub fn corners(b: &Aabb) -> [Vec3; 8] {
    let (l, h) = (b.min, b.max);
    [
        Vec3::new(l.x, l.y, l.z),
        Vec3::new(h.x, l.y, l.z),
        Vec3::new(l.x, h.y, l.z),
        Vec3::new(h.x, h.y, l.z),
        Vec3::new(l.x, l.y, h.z),
        Vec3::new(h.x, l.y, h.z),
        Vec3::new(l.x, h.y, h.z),
        Vec3::new(h.x, h.y, h.z),
    ]
}

/// Which set of views covers the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ViewsKind {
    /// Six 90° perspective views around a centre (004 §3.2). Exact for every ray.
    #[default]
    Cube,
    /// One perspective view. Exact for every ray when the whole scene is in
    /// its frustum (the default placement); otherwise hits outside it are not found.
    Single,
    /// One orthographic view over the scene bounds (000 §5.3). Exact for every ray.
    Ortho,
    /// Two orthographic views over the scene bounds, split by a plane across
    /// the axis they look along (000 §5.3, §6.3). Exact for every ray.
    #[cfg_attr(feature = "clap", value(name = "ortho2"))]
    OrthoSplit,
}

/// A world axis: the one orthographic views look along.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// 0, 1, 2.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The unit vector.
    pub fn unit(self) -> Vec3 {
        [Vec3::X, Vec3::Y, Vec3::Z][self.index()]
    }

    /// The name used on command lines and in reports: `x`, `y` or `z`.
    pub fn name(self) -> &'static str {
        ["x", "y", "z"][self.index()]
    }

    /// The axis of the smallest extent (ties go to z, then y): what
    /// [`single_axis`] and the orthographic views look along by default.
    pub fn thinnest(extent: Vec3) -> Axis {
        if extent.x < extent.y && extent.x < extent.z {
            Axis::X
        } else if extent.y < extent.z {
            Axis::Y
        } else {
            Axis::Z
        }
    }
}

impl ViewsKind {
    /// Every kind, in declaration order.
    pub const ALL: [ViewsKind; 4] = [
        ViewsKind::Cube,
        ViewsKind::Single,
        ViewsKind::Ortho,
        ViewsKind::OrthoSplit,
    ];

    /// The name used on command lines and in reports: `cube`, `single`,
    /// `ortho` or `ortho2`.
    pub fn name(self) -> &'static str {
        match self {
            ViewsKind::Cube => "cube",
            ViewsKind::Single => "single",
            ViewsKind::Ortho => "ortho",
            ViewsKind::OrthoSplit => "ortho2",
        }
    }

    /// How many views the set has (before any is left out).
    pub fn view_count(self) -> usize {
        match self {
            ViewsKind::Cube => 6,
            ViewsKind::Single | ViewsKind::Ortho => 1,
            ViewsKind::OrthoSplit => 2,
        }
    }

    /// Orthographic views.
    pub fn is_ortho(self) -> bool {
        matches!(self, ViewsKind::Ortho | ViewsKind::OrthoSplit)
    }
}

impl std::fmt::Display for ViewsKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Edges of a view's image, in adjacency order.
pub const EDGE_LEFT: usize = 0; // x = -tan·z
pub const EDGE_RIGHT: usize = 1; // x = +tan·z
pub const EDGE_BOTTOM: usize = 2; // y = -tan·z
pub const EDGE_TOP: usize = 3; // y = +tan·z

/// The direction a [`ViewSet::single`] without an eye looks along: the unit
/// axis of the smallest extent (ties go to z, then y). Seen along it, a flat
/// scene (a terrain, a floor) spreads over the most tiles, so each tile lists
/// the fewest triangles; seen edge-on, one tile can list a whole row of them.
/// The `views` stage (`views.wgsl`) makes the same choice on the GPU.
pub fn single_axis(extent: Vec3) -> Vec3 {
    Axis::thinnest(extent).unit()
}

/// Cube faces: +X, -X, +Y, -Y, +Z, -Z (forward, right, up).
const CUBE_AXES: [[Vec3; 3]; 6] = [
    [Vec3::X, Vec3::NEG_Z, Vec3::Y],
    [Vec3::NEG_X, Vec3::Z, Vec3::Y],
    [Vec3::Y, Vec3::X, Vec3::NEG_Z],
    [Vec3::NEG_Y, Vec3::X, Vec3::Z],
    [Vec3::Z, Vec3::X, Vec3::Y],
    [Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y],
];

fn face_of_direction(d: Vec3) -> usize {
    CUBE_AXES.iter().position(|a| a[0] == d).unwrap_or(0)
}

/// A set of views covering the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSet {
    pub kind: ViewsKind,
    pub views: Vec<View>,
    /// Centre of the cube, or eye of the single view.
    pub center: Vec3,
    /// For the cube: `adjacency[face][edge]` is the face across that edge.
    pub adjacency: Vec<[u32; 4]>,
}

impl ViewSet {
    /// Numbers the views with content densely ([`View::slot`]).
    fn assign_slots(&mut self) {
        let mut next = 0;
        for v in &mut self.views {
            if v.has_content {
                v.slot = next;
                next += 1;
            } else {
                v.slot = NO_SLOT;
            }
        }
    }

    /// Views with content: the number of per-view blocks the structure stores.
    pub fn slots(&self) -> usize {
        self.views.iter().filter(|v| v.has_content).count()
    }

    /// Marks the views for which `keep` is false as without content (no
    /// passes, no memory) and renumbers the slots. Only sound when no
    /// triangle reaches a tile of those views: then no hit can lie in them.
    pub fn leave_out(&mut self, keep: &[bool]) {
        for (v, &k) in self.views.iter_mut().zip(keep) {
            v.has_content &= k;
        }
        self.assign_slots();
    }

    /// The cubemap of 004 §3.2: six 90° views sharing `center`, each centre of
    /// projection moved back by the near distance so the near planes pass
    /// through `center` and the six frusta together cover all of space.
    pub fn cube(center: Vec3, bounds: &Aabb, tiles: u32) -> ViewSet {
        let near = near_distance(center, bounds);
        let views = CUBE_AXES
            .iter()
            .map(|&[f, r, u]| View::new(center - f * near, r, u, f, 1.0, near, tiles, bounds))
            .collect();
        let adjacency = CUBE_AXES
            .iter()
            .map(|&[_, r, u]| {
                let mut a = [0u32; 4];
                a[EDGE_LEFT] = face_of_direction(-r) as u32;
                a[EDGE_RIGHT] = face_of_direction(r) as u32;
                a[EDGE_BOTTOM] = face_of_direction(-u) as u32;
                a[EDGE_TOP] = face_of_direction(u) as u32;
                a
            })
            .collect();
        let mut set = ViewSet {
            kind: ViewsKind::Cube,
            views,
            center,
            adjacency,
        };
        set.assign_slots();
        set
    }

    /// One 90° view. Without `eye` it looks along the bounds' thinnest axis
    /// ([`single_axis`]) from its negative side, far enough that the bounding
    /// sphere lies inside its frustum: then every triangle is seen and tracing
    /// is exact for every ray. With `eye`, it looks from there towards the
    /// bounds' centre; geometry outside its frustum is not seen, unless
    /// [`single_sees_all`] holds for the eye.
    pub fn single(eye: Option<Vec3>, bounds: &Aabb, tiles: u32) -> ViewSet {
        let c = bounds.center();
        let r = (bounds.extent().length() * 0.5).max(f32::MIN_POSITIVE);
        let (apex, forward, near) = match eye {
            None => {
                // sin(45°) = 1/sqrt(2): distance sqrt(2)·r puts the sphere inside the cone; 1.5·r adds room.
                let dist = 1.5 * r + r;
                let f = single_axis(bounds.extent());
                (c - f * dist, f, dist - r * 1.01)
            }
            Some(e) => {
                let f = (c - e).try_normalize().unwrap_or(Vec3::Z);
                // Outside the bounding sphere, no geometry is nearer than
                // `|c − e| − r`: a near plane at half that keeps all of it and
                // makes rays from the eye dilate less.
                let clear = 0.5 * ((c - e).length() - r);
                (e, f, fmax(near_distance(e, bounds), clear))
            }
        };
        let up_hint = if forward.y.abs() > 0.9 {
            Vec3::X
        } else {
            Vec3::Y
        };
        // Zeros made positive: a GPU may give either sign to a product with a
        // zero factor, and the views stage computes these axes there too.
        let right = positive_zeros(up_hint.cross(forward).normalize());
        let up = positive_zeros(forward.cross(right));
        let forward = positive_zeros(forward);
        let v = View::new(
            apex,
            right,
            up,
            forward,
            1.0,
            near.max(f32::MIN_POSITIVE),
            tiles,
            bounds,
        );
        let mut set = ViewSet {
            kind: ViewsKind::Single,
            views: vec![v],
            center: apex,
            adjacency: Vec::new(),
        };
        set.assign_slots();
        set
    }
}

impl ViewSet {
    /// Orthographic views looking along `+axis` over `bounds` (000 §5.3): one
    /// view, or with `cut`, two whose depth ranges meet at the plane
    /// `p[axis] = cut` (the first sees the bounds up to it, the second from
    /// it on; each far plane is pushed out past the other's near plane by
    /// the dilation, so together they hold every point of the bounds). The
    /// image is square, centred on the bounds, and holds their cross-section
    /// with room to spare, so every triangle is seen and tracing is exact
    /// for every ray. A cut outside the bounds leaves one view without content.
    pub fn ortho(axis: Axis, cut: Option<f32>, bounds: &Aabb, tiles: u32) -> ViewSet {
        let c = bounds.center();
        let e = bounds.extent();
        let r = (e.length() * 0.5).max(f32::MIN_POSITIVE);
        let forward = axis.unit();
        let (right, up) = match axis {
            Axis::X => (Vec3::NEG_Z, Vec3::Y),
            Axis::Y => (Vec3::X, Vec3::NEG_Z),
            Axis::Z => (Vec3::X, Vec3::Y),
        };
        // The apex a little behind the bounds, so every depth is positive
        // and at least `near` with room; the image half width covers the
        // cross-section, 1/1024 larger (far beyond rounding).
        let a = axis.index();
        let pad = r * (1.0 / 32.0);
        let apex = c - forward * (0.5 * e[a] + 2.0 * pad);
        // num::fmax throughout: the views stage makes the same choices on the GPU.
        let cross = [e.x, e.y, e.z]
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != a)
            .fold(0.0f32, |m, (_, &x)| fmax(m, x));
        let half = fmax(0.5 * cross, pad) * (1.0 + 1.0 / 1024.0);
        let near = fmax(pad, f32::MIN_POSITIVE);
        let views = match cut {
            None => vec![View::orthographic(
                apex, right, up, forward, half, near, tiles, bounds,
            )],
            Some(k) => {
                let (mut lo, mut hi) = (*bounds, *bounds);
                lo.max[a] = fmax(fmin(lo.max[a], k), lo.min[a]);
                hi.min[a] = fmin(fmax(hi.min[a], k), hi.max[a]);
                let first = View::orthographic(apex, right, up, forward, half, near, tiles, &lo);
                // The cut's depth as `to_view` computes it (the axes are unit
                // axes, so the other terms are zeros).
                let mut at = bounds.min;
                at[a] = hi.min[a];
                let near2 = fmax(first.to_view(at)[2], near);
                let second = View::orthographic(apex, right, up, forward, half, near2, tiles, &hi);
                vec![first, second]
            }
        };
        let mut set = ViewSet {
            kind: if cut.is_some() {
                ViewsKind::OrthoSplit
            } else {
                ViewsKind::Ortho
            },
            views,
            center: c,
            adjacency: Vec::new(),
        };
        set.assign_slots();
        set
    }
}

/// Room [`single_sees_all`] leaves between the bounding sphere and the cone
/// inside the single view's frustum: the sphere's radius is taken this much
/// larger, far beyond the rounding of projecting a point.
const SEES_ALL_MARGIN: f32 = 1.05;

/// Whether the single view from `eye` ([`ViewSet::single`] with `Some(eye)`,
/// looking at the centre of `bounds`) sees all of `bounds`: the bounding
/// sphere (its radius [`SEES_ALL_MARGIN`] larger) lies inside the 45° cone
/// within its frustum, and beyond its near plane. Then every triangle is
/// seen, and tracing through that view is exact for every ray, as through the
/// default placement. False for a non-finite eye or bounds, and for an eye
/// inside the sphere (only the cube sees around it).
pub fn single_sees_all(eye: Vec3, bounds: &Aabb) -> bool {
    let c = bounds.center();
    let r = bounds.extent().length() * 0.5 * SEES_ALL_MARGIN;
    let d = (c - eye).length();
    eye.is_finite()
        && r.is_finite()
        && d.is_finite()
        && d * std::f32::consts::FRAC_1_SQRT_2 >= r
        && near_distance(eye, bounds) < d - r
}

/// `v` with `-0.0` components replaced by `+0.0`.
pub fn positive_zeros(v: Vec3) -> Vec3 {
    let f = |x: f32| if x == 0.0 { 0.0 } else { x };
    Vec3::new(f(v.x), f(v.y), f(v.z))
}

/// Near distance for views centred at `c`: small against the scene, large
/// against the dilations (2^-5 of the scale: 128 times a ray's `EPS_RAY_REL`
/// share, so the walk's dilation near the centre stays under a tile or so).
fn near_distance(c: Vec3, bounds: &Aabb) -> f32 {
    let mut scale: f32 = 0.0;
    for p in corners(bounds) {
        scale = scale.max((p - c).abs().max_element());
    }
    if !(scale > 0.0) || !scale.is_finite() {
        scale = 1.0;
    }
    scale * (1.0 / 32.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }

    #[test]
    fn single_sees_all_needs_the_sphere_inside_the_cone() {
        // Unit box: radius sqrt(3), 5 % more; the cone needs sqrt(2) times that.
        let need = 3f32.sqrt() * 1.05 * std::f32::consts::SQRT_2;
        let b = unit_box();
        for dir in [Vec3::Z, Vec3::NEG_X, Vec3::new(1.0, 2.0, -2.0).normalize()] {
            assert!(single_sees_all(dir * (need * 1.01), &b), "{dir}");
            assert!(!single_sees_all(dir * (need * 0.99), &b), "{dir}");
        }
        assert!(!single_sees_all(Vec3::ZERO, &b));
        assert!(!single_sees_all(Vec3::new(0.0, f32::INFINITY, 0.0), &b));
        assert!(!single_sees_all(Vec3::new(f32::NAN, 0.0, 9.0), &b));
        // Every corner of the box is then inside the view's frustum, past its near plane.
        let eye = Vec3::new(1.0, 2.0, -2.0).normalize() * (need * 1.01);
        let v = &ViewSet::single(Some(eye), &b, 16).views[0];
        for c in corners(&b) {
            let p = v.to_view(c);
            assert!(
                p[2] > v.near && p[0].abs() < p[2] && p[1].abs() < p[2],
                "{c}: {p:?}"
            );
        }
    }

    #[test]
    fn cube_faces_are_orthonormal_and_right_handed() {
        let vs = ViewSet::cube(Vec3::ZERO, &unit_box(), 16);
        for v in &vs.views {
            assert_eq!(v.right.cross(v.up), v.forward);
            assert_eq!(v.right.dot(v.up), 0.0);
            assert_eq!(v.forward.dot(v.up), 0.0);
            assert!(v.has_content);
        }
    }

    #[test]
    fn adjacency_crosses_the_shared_edge() {
        // The point on edge e of face f at the far plane lies on the matching edge of the neighbour.
        let vs = ViewSet::cube(Vec3::ZERO, &unit_box(), 16);
        for (f, v) in vs.views.iter().enumerate() {
            for e in 0..4 {
                let g = vs.adjacency[f][e] as usize;
                assert_ne!(f, g);
                let (sx, sy) = match e {
                    EDGE_LEFT => (-1.0, 0.0),
                    EDGE_RIGHT => (1.0, 0.0),
                    EDGE_BOTTOM => (0.0, -1.0),
                    _ => (0.0, 1.0),
                };
                let z = 3.0;
                let p = v.apex + v.forward * z + v.right * (sx * z) + v.up * (sy * z);
                let w = &vs.views[g];
                let q = w.to_view(p);
                assert!(q[2] > 0.0);
                let (qx, qy) = (q[0] / q[2], q[1] / q[2]);
                assert!(
                    qx.abs() <= 1.0 + 1e-5 && qy.abs() <= 1.0 + 1e-5,
                    "face {f} edge {e} -> {g}: {qx} {qy}"
                );
                // The neighbour's neighbour across some edge is f again.
                assert!(vs.adjacency[g].contains(&(f as u32)));
            }
        }
    }

    #[test]
    fn shifted_cube_covers_all_space() {
        let vs = ViewSet::cube(Vec3::new(0.1, -0.2, 0.3), &unit_box(), 16);
        let mut s = 0x1234_5678u32;
        for _ in 0..10_000 {
            let mut r = || {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                (s as f32 / u32::MAX as f32) * 2.0 - 1.0
            };
            let p = Vec3::new(r(), r(), r()) * 1.5;
            let inside = vs.views.iter().any(|v| {
                let q = v.to_view(p);
                q[2] >= v.near && q[0].abs() <= q[2] && q[1].abs() <= q[2]
            });
            assert!(inside, "{p} is in no face");
        }
    }

    #[test]
    fn default_single_view_sees_the_whole_bounds() {
        let b = Aabb {
            min: Vec3::new(-3.0, 0.0, 2.0),
            max: Vec3::new(5.0, 1.0, 9.0),
        };
        let vs = ViewSet::single(None, &b, 8);
        let v = &vs.views[0];
        for c in corners(&b) {
            let q = v.to_view(c);
            assert!(q[2] > v.near && q[2] < v.far);
            assert!(q[0].abs() < q[2] && q[1].abs() < q[2]);
        }
    }
}
