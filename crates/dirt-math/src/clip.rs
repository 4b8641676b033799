//! Clipping against dilated view-space half-spaces: of a ray (to a parameter
//! interval) and of a polygon (Sutherland–Hodgman), and the depth extent of a
//! triangle inside one tile's frustum.
//!
//! Every half-space is moved outward by an absolute distance `eps` (see
//! [`crate::view`]), so the tests are conservative: a point that is inside in
//! exact arithmetic is inside after rounding.

use crate::num::{floor_index, fmax, fmin};
use crate::view::{View, ViewRay};

/// A half-space of view space, tested as `f(p) >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HalfSpace {
    /// `p[axis] - s·z + eps >= 0`: above the boundary of slope `s`.
    Lo { axis: usize, s: f32 },
    /// `s·z - p[axis] + eps >= 0`: below the boundary of slope `s`.
    Hi { axis: usize, s: f32 },
    /// `z - near + eps >= 0`.
    Near(f32),
    /// `far - z + eps >= 0`.
    Far(f32),
    /// `p[axis] - s + eps >= 0`: above the boundary `s` of an orthographic view.
    OrthoLo { axis: usize, s: f32 },
    /// `s - p[axis] + eps >= 0`: below the boundary `s` of an orthographic view.
    OrthoHi { axis: usize, s: f32 },
}

impl HalfSpace {
    /// Signed value at a view-space point.
    #[inline(always)]
    pub fn eval(&self, p: [f32; 3], eps: f32) -> f32 {
        match *self {
            HalfSpace::Lo { axis, s } => p[axis] - s * p[2] + eps,
            HalfSpace::Hi { axis, s } => s * p[2] - p[axis] + eps,
            HalfSpace::Near(n) => p[2] - n + eps,
            HalfSpace::Far(f) => f - p[2] + eps,
            HalfSpace::OrthoLo { axis, s } => p[axis] - s + eps,
            HalfSpace::OrthoHi { axis, s } => s - p[axis] + eps,
        }
    }

    /// Linear part of `eval` along a direction.
    #[inline]
    pub fn slope(&self, d: [f32; 3]) -> f32 {
        match *self {
            HalfSpace::Lo { axis, s } => d[axis] - s * d[2],
            HalfSpace::Hi { axis, s } => s * d[2] - d[axis],
            HalfSpace::Near(_) => d[2],
            HalfSpace::Far(_) => -d[2],
            HalfSpace::OrthoLo { axis, .. } => d[axis],
            HalfSpace::OrthoHi { axis, .. } => -d[axis],
        }
    }
}

/// A ray parameter interval `[t0, t1]`; empty when `t0 > t1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub t0: f32,
    pub t1: f32,
}

impl Interval {
    pub const EMPTY: Interval = Interval {
        t0: f32::INFINITY,
        t1: f32::NEG_INFINITY,
    };

    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.t0 <= self.t1)
    }

    /// Intersects with the half-space; returns true when this call moved `t1`
    /// (the ray leaves through this half-space's boundary).
    #[inline]
    pub fn clip(&mut self, h: &HalfSpace, vr: &ViewRay) -> bool {
        let f0 = h.eval(vr.o, vr.eps);
        let f1 = h.slope(vr.d);
        if f1 > 0.0 {
            let t = -f0 / f1;
            if t > self.t0 {
                self.t0 = t;
            }
        } else if f1 < 0.0 {
            let t = -f0 / f1;
            if t < self.t1 {
                self.t1 = t;
                return true;
            }
        } else if !(f0 >= 0.0) {
            *self = Interval::EMPTY;
        }
        false
    }
}

/// View-space point of the ray at `t` (no fused operations).
#[inline]
pub fn ray_point(vr: &ViewRay, t: f32) -> [f32; 3] {
    [
        vr.o[0] + t * vr.d[0],
        vr.o[1] + t * vr.d[1],
        vr.o[2] + t * vr.d[2],
    ]
}

/// View-space depth of the ray at `t`.
#[inline]
pub fn ray_depth(vr: &ViewRay, t: f32) -> f32 {
    vr.o[2] + t * vr.d[2]
}

/// The six half-spaces of a whole view.
pub fn view_frustum(v: &View) -> [HalfSpace; 6] {
    [
        v.lo(0, -v.tan),
        v.hi(0, v.tan),
        v.lo(1, -v.tan),
        v.hi(1, v.tan),
        HalfSpace::Near(v.near),
        HalfSpace::Far(v.far),
    ]
}

/// Side half-spaces of the block of tiles `[i0, i1) × [j0, j1)` (a tile, or a Hi-Z cell).
pub fn block_frustum(v: &View, i0: u32, i1: u32, j0: u32, j1: u32) -> [HalfSpace; 4] {
    [
        v.lo(0, v.boundary(i0)),
        v.hi(0, v.boundary(i1)),
        v.lo(1, v.boundary(j0)),
        v.hi(1, v.boundary(j1)),
    ]
}

/// Clips `[tmin, tmax]` of a ray to a view's frustum. Returns the interval and
/// the edge (`view::EDGE_*`) through which the ray leaves, if it leaves through a side.
pub fn clip_ray_to_view(v: &View, vr: &ViewRay, tmin: f32, tmax: f32) -> (Interval, Option<usize>) {
    let mut iv = Interval { t0: tmin, t1: tmax };
    let mut exit = None;
    for (k, h) in view_frustum(v).iter().enumerate() {
        if iv.clip(h, vr) {
            exit = if k < 4 { Some(k) } else { None };
        }
        if iv.is_empty() {
            return (Interval::EMPTY, None);
        }
    }
    (iv, exit)
}

/// Maximum vertices of a clipped polygon: a triangle clipped by 6 view planes
/// and 4 tile planes gains at most one vertex per plane.
pub const MAX_POLY: usize = 16;

/// A convex polygon in view space.
#[derive(Clone, Copy, Debug)]
pub struct Polygon {
    pub len: usize,
    pub v: [[f32; 3]; MAX_POLY],
}

impl Polygon {
    /// No vertices.
    pub const EMPTY: Polygon = Polygon {
        len: 0,
        v: [[0.0; 3]; MAX_POLY],
    };

    pub fn triangle(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Polygon {
        let mut v = [[0.0; 3]; MAX_POLY];
        v[0] = a;
        v[1] = b;
        v[2] = c;
        Polygon { len: 3, v }
    }

    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.v[..self.len]
    }

    /// Sutherland–Hodgman against one half-space. Points on the boundary are kept.
    pub fn clip(&mut self, h: &HalfSpace, eps: f32) {
        if self.len == 0 {
            return;
        }
        let mut out = Polygon::EMPTY;
        if self.clip_into(h, eps, &mut out) {
            self.copy_from(&out);
        }
    }

    /// Becomes `other`, copying only its vertices (a whole `Polygon` is
    /// 200 bytes, most of them unused; the clipping copies one per plane).
    pub fn copy_from(&mut self, other: &Polygon) {
        let n = other.len.min(MAX_POLY);
        self.v[..n].copy_from_slice(&other.v[..n]);
        self.len = n;
    }

    /// [`Polygon::clip`] writing the result to `out` (only its first `len`
    /// vertices): returns false, leaving `out` untouched, when every vertex is
    /// inside, so the result is `self` itself. Each vertex is evaluated once;
    /// when every vertex is outside the result is empty without the loop. Both
    /// shortcuts give exactly what the general loop would.
    pub fn clip_into(&self, h: &HalfSpace, eps: f32, out: &mut Polygon) -> bool {
        let n = self.len;
        let mut f = [0.0f32; MAX_POLY];
        let inside = self.eval_into(h, eps, &mut f);
        if inside == n {
            return false;
        }
        let mut m = 0;
        if inside > 0 {
            self.clipped_each(&f, |p, q, w| {
                out.v[m] = match w {
                    None => *p,
                    Some(w) => [
                        p[0] + (q[0] - p[0]) * w,
                        p[1] + (q[1] - p[1]) * w,
                        p[2] + (q[2] - p[2]) * w,
                    ],
                };
                m += 1;
            });
        }
        out.len = m;
        true
    }

    /// `self.clip(h, eps).depth_range()`, bit for bit, without the clipped
    /// polygon: only the depths of its vertices are computed, folded in its
    /// vertex order (`fmin` and `fmax` keep the first of two zeros, so the
    /// order is kept). The last clip of a tile's coverage needs no more.
    pub fn clipped_depth_range(&self, h: &HalfSpace, eps: f32) -> Option<(f32, f32)> {
        let n = self.len;
        let mut f = [0.0f32; MAX_POLY];
        let inside = self.eval_into(h, eps, &mut f);
        if inside == n {
            return self.depth_range();
        }
        if inside == 0 {
            return None;
        }
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        self.clipped_each(&f, |p, q, w| {
            let z = match w {
                None => p[2],
                Some(w) => p[2] + (q[2] - p[2]) * w,
            };
            (lo, hi) = (fmin(lo, z), fmax(hi, z));
        });
        Some((lo, hi))
    }

    /// The vertices of the polygon clipped by the plane valued `f` at its
    /// vertices (some inside, some not), in order, at most [`MAX_POLY`]:
    /// `emit(p, q, None)` for vertex `p` kept, `emit(p, q, Some(w))` for the
    /// crossing at `p + (q − p)·w` of edge `p → q`.
    #[inline(always)]
    fn clipped_each(
        &self,
        f: &[f32; MAX_POLY],
        mut emit: impl FnMut(&[f32; 3], &[f32; 3], Option<f32>),
    ) {
        let n = self.len;
        let mut m = 0;
        for k in 0..n {
            let next = if k + 1 == n { 0 } else { k + 1 };
            let (p, q) = (&self.v[k], &self.v[next]);
            let (fp, fq) = (f[k], f[next]);
            if fp >= 0.0 && m < MAX_POLY {
                emit(p, q, None);
                m += 1;
            }
            if ((fp >= 0.0) != (fq >= 0.0)) && m < MAX_POLY {
                emit(p, q, Some(fp / (fp - fq)));
                m += 1;
            }
        }
    }

    /// [`HalfSpace::eval`] of every vertex, with the match taken once; the
    /// number of vertices inside (`f >= 0`). Counted as each value is
    /// written: counted afterwards, the loop read the values back as pairs
    /// just after writing them one by one, and each such read waited for
    /// the writes to reach memory (a quarter of a clip's time).
    #[inline(always)]
    fn eval_into(&self, h: &HalfSpace, eps: f32, f: &mut [f32; MAX_POLY]) -> usize {
        let vs = &self.v[..self.len];
        let mut inside = 0;
        let mut each = |value: fn(&[f32; 3], usize, f32, f32) -> f32, axis: usize, s: f32| {
            for (fk, p) in f.iter_mut().zip(vs) {
                let x = value(p, axis, s, eps);
                *fk = x;
                inside += usize::from(x >= 0.0);
            }
        };
        match *h {
            HalfSpace::Lo { axis, s } => each(|p, a, s, e| p[a] - s * p[2] + e, axis, s),
            HalfSpace::Hi { axis, s } => each(|p, a, s, e| s * p[2] - p[a] + e, axis, s),
            HalfSpace::Near(near) => each(|p, _, n, e| p[2] - n + e, 0, near),
            HalfSpace::Far(far) => each(|p, _, f, e| f - p[2] + e, 0, far),
            HalfSpace::OrthoLo { axis, s } => each(|p, a, s, e| p[a] - s + e, axis, s),
            HalfSpace::OrthoHi { axis, s } => each(|p, a, s, e| s - p[a] + e, axis, s),
        }
        inside
    }

    /// Depth range of the vertices, or `None` when empty.
    pub fn depth_range(&self) -> Option<(f32, f32)> {
        if self.len == 0 {
            return None;
        }
        let mut lo = f32::INFINITY;
        let mut hi = f32::NEG_INFINITY;
        for p in self.vertices() {
            lo = fmin(lo, p[2]);
            hi = fmax(hi, p[2]);
        }
        Some((lo, hi))
    }
}

/// A triangle in a view's space, clipped to the view's (dilated) frustum, or
/// `None` when it is entirely outside.
pub fn clip_triangle_to_view(v: &View, tri: [[f32; 3]; 3]) -> Option<Polygon> {
    let mut out = Polygon::EMPTY;
    clip_triangle_to_view_into(v, tri, &mut out).then_some(out)
}

/// [`clip_triangle_to_view`] writing to `out` (only its first `len` vertices):
/// false, with `out` empty, when the triangle is entirely outside. The planes'
/// clips go back and forth between `out` and a scratch polygon instead of
/// copying one polygon per plane.
pub fn clip_triangle_to_view_into(v: &View, tri: [[f32; 3]; 3], out: &mut Polygon) -> bool {
    out.v[..3].copy_from_slice(&tri);
    out.len = 3;
    let planes = view_frustum(v);
    // Every vertex inside every plane (most triangles of a view that holds
    // the scene): each clip would keep the triangle as it is. The 18 tests
    // at once, without the per-plane clip's set-up.
    if planes
        .iter()
        .all(|h| tri.iter().all(|&p| h.eval(p, v.eps) >= 0.0))
    {
        return true;
    }
    let mut scratch = Polygon::EMPTY;
    // Whether the current polygon is in `scratch` (else in `out`).
    let mut in_scratch = false;
    for h in &planes {
        in_scratch ^= if in_scratch {
            scratch.clip_into(h, v.eps, out)
        } else {
            out.clip_into(h, v.eps, &mut scratch)
        };
        let len = if in_scratch { scratch.len } else { out.len };
        if len == 0 {
            out.len = 0;
            return false;
        }
    }
    if in_scratch {
        out.copy_from(&scratch);
    }
    true
}

/// Depth extent of a (view-clipped) polygon inside the frustum of tile `(i, j)`
/// of its tile range `(i0, i1, j0, j1)` ([`polygon_tile_range`]), rounded
/// outward by the view's `eps`; `None` when it does not touch the tile.
///
/// The polygon is clipped only to the tile's planes inside the range: its
/// lower x plane where `i > i0`, its upper where `i < i1`, and so for y
/// (x planes first, lower before upper). The range holds every point of
/// the polygon up to its margin, so a plane at the range's outer edge could
/// only trim slivers of that margin, and the polygon's extent without that
/// clip contains the extent with it. It stays conservative, saves the four
/// plane clips of a triangle inside one tile (the common case at fine
/// resolutions) and half of those of one over two by two tiles.
pub fn tile_depth_extent(
    v: &View,
    poly: &Polygon,
    range: (u32, u32, u32, u32),
    i: u32,
    j: u32,
) -> Option<(f32, f32)> {
    let (i0, i1, j0, j1) = range;
    let mut p = *poly;
    let x = inner_planes(v, 0, i, (i0, i1));
    let y = inner_planes(v, 1, j, (j0, j1));
    for h in x.iter().chain(&y).flatten() {
        p.clip(h, v.eps);
        if p.len == 0 {
            return None;
        }
    }
    let (lo, hi) = p.depth_range()?;
    Some((lo - v.eps, hi + v.eps))
}

/// The planes of tile `k` on `axis` (0: x, 1: y) that [`tile_depth_extent`]
/// clips to, lower then upper ([`block_frustum`]'s): those inside the
/// range `[k0, k1]` on that axis.
#[inline]
fn inner_planes(v: &View, axis: usize, k: u32, (k0, k1): (u32, u32)) -> [Option<HalfSpace>; 2] {
    [
        (k > k0).then(|| v.lo(axis, v.boundary(k))),
        (k < k1).then(|| v.hi(axis, v.boundary(k + 1))),
    ]
}

/// Conservative extent in tile coordinates, `[x0, x1, y0, y1]`, of the
/// view-clipped polygon with these view-space vertices: the range of their
/// coordinates, each widened by the image of the view's `eps` at their
/// smallest depth plus 1/256 of a tile of rounding room, so that it holds
/// the image of every point within `eps` of the polygon. `None` without
/// vertices. [`polygon_tile_range`] floors it to tiles.
#[inline]
pub fn tile_extent(v: &View, vertices: &[[f32; 3]]) -> Option<[f32; 4]> {
    if vertices.is_empty() {
        return None;
    }
    // Polygon::depth_range's smallest depth.
    let zlo = vertices.iter().fold(f32::INFINITY, |lo, p| fmin(lo, p[2]));
    let z = v.w(zlo);
    // Image error from the dilation at the smallest depth, plus rounding room.
    let delta = v.eps / z / v.step + 1.0 / 256.0;
    let (mut xlo, mut xhi, mut ylo, mut yhi) = (
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
    );
    for p in vertices {
        let pz = v.w(p[2]);
        let x = v.tile_coord(p[0] / pz);
        let y = v.tile_coord(p[1] / pz);
        xlo = fmin(xlo, x);
        xhi = fmax(xhi, x);
        ylo = fmin(ylo, y);
        yhi = fmax(yhi, y);
    }
    Some([xlo - delta, xhi + delta, ylo - delta, yhi + delta])
}

/// Conservative range of tiles `[i0, i1] × [j0, j1]` (inclusive) a view-clipped
/// polygon may touch: its [`tile_extent`], floored.
pub fn polygon_tile_range(v: &View, poly: &Polygon) -> Option<(u32, u32, u32, u32)> {
    let [x0, x1, y0, y1] = tile_extent(v, poly.vertices())?;
    let last = v.tiles - 1;
    if !(x1 >= 0.0 && y1 >= 0.0 && x0 <= v.tiles as f32 && y0 <= v.tiles as f32) {
        return None;
    }
    Some((
        floor_index(x0, last),
        floor_index(x1, last),
        floor_index(y0, last),
        floor_index(y1, last),
    ))
}

/// Calls `f(i, j, zlo, zhi)` for every tile of `v` whose dilated frustum the
/// triangle (in view space) touches, with its conservative depth extent there.
/// This is the coverage rule shared by `fill_depth` and `fill_primitives`.
///
/// The extent of tile `(i, j)` is [`tile_depth_extent`]'s, bit for bit: that
/// function clips against the tile's x planes, then its y planes, so the
/// polygon clipped to column `i`'s x planes is computed once per column and
/// only the y planes are applied per tile. Tiles are visited column by column.
pub fn for_each_covered_tile(v: &View, tri: [[f32; 3]; 3], f: impl FnMut(u32, u32, f32, f32)) {
    let mut poly = Polygon::EMPTY;
    if !clip_triangle_to_view_into(v, tri, &mut poly) {
        return;
    }
    let Some(range) = polygon_tile_range(v, &poly) else {
        return;
    };
    cover_tiles(v, &poly, range, f);
}

/// The rest of [`for_each_covered_tile`]: the tiles of the range
/// `(i0, i1, j0, j1)` ([`polygon_tile_range`]) of the view-clipped polygon
/// `poly`, with their extents, in its order.
pub fn cover_tiles(
    v: &View,
    poly: &Polygon,
    (i0, i1, j0, j1): (u32, u32, u32, u32),
    mut f: impl FnMut(u32, u32, f32, f32),
) {
    // Scratch polygons for the clips: written only as far as used, and
    // never copied (each clip reads one and writes the next). A tile's last
    // clip computes only depths (`Polygon::clipped_depth_range`).
    let (mut a, mut lo, mut hi) = (Polygon::EMPTY, Polygon::EMPTY, Polygon::EMPTY);
    for i in i0..=i1 {
        // tile_depth_extent's x planes are the same for the whole column.
        let x = inner_planes(v, 0, i, (i0, i1));
        if j0 == j1 {
            // One row: the column's clip is the tile's.
            if let Some((lo, hi)) = clip_depth_range(poly, x, v.eps, &mut lo) {
                f(i, j0, lo - v.eps, hi + v.eps);
            }
            continue;
        }
        let column = clip_some(poly, x, v.eps, &mut lo, &mut hi);
        if column.len == 0 {
            continue;
        }
        for j in j0..=j1 {
            let y = inner_planes(v, 1, j, (j0, j1));
            if let Some((lo, hi)) = clip_depth_range(column, y, v.eps, &mut a) {
                f(i, j, lo - v.eps, hi + v.eps);
            }
        }
    }
}

/// `poly` clipped to the half-spaces present, in turn ([`Polygon::clip`],
/// bit for bit), writing into the scratch polygons `a` and `b` only where a
/// clip changes something: the result is `poly`, `a` or `b`, never a copy.
fn clip_some<'a>(
    poly: &'a Polygon,
    [h0, h1]: [Option<HalfSpace>; 2],
    eps: f32,
    a: &'a mut Polygon,
    b: &'a mut Polygon,
) -> &'a Polygon {
    let p = match h0 {
        Some(h) if poly.clip_into(&h, eps, a) => &*a,
        _ => poly,
    };
    match h1 {
        Some(h) if p.len > 0 && p.clip_into(&h, eps, b) => b,
        _ => p,
    }
}

/// `clip_some(..).depth_range()`, the last clip computing only depths
/// ([`Polygon::clipped_depth_range`]).
#[inline]
fn clip_depth_range(
    poly: &Polygon,
    [h0, h1]: [Option<HalfSpace>; 2],
    eps: f32,
    a: &mut Polygon,
) -> Option<(f32, f32)> {
    // The last plane present takes only depths.
    let (first, last) = if h1.is_some() { (h0, h1) } else { (None, h0) };
    let p = match first {
        Some(h) if poly.clip_into(&h, eps, a) => &*a,
        _ => poly,
    };
    match last {
        _ if p.len == 0 => None,
        Some(h) => p.clipped_depth_range(&h, eps),
        None => p.depth_range(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Aabb, Ray};
    use crate::view::ViewSet;
    use glam::Vec3;
    use proptest::prelude::*;

    fn cube(tiles: u32) -> ViewSet {
        ViewSet::cube(
            Vec3::new(0.1, 0.05, -0.07),
            &Aabb {
                min: Vec3::splat(-2.0),
                max: Vec3::splat(2.0),
            },
            tiles,
        )
    }

    /// View `face` of nine: 0..6 the cube's faces, 6 one orthographic
    /// view, 7 and 8 the two of a split.
    fn face_view(face: usize, tiles: u32) -> View {
        let b = Aabb {
            min: Vec3::splat(-2.0),
            max: Vec3::splat(2.0),
        };
        let vs = match face {
            0..6 => cube(tiles),
            6 => ViewSet::ortho(crate::view::Axis::Y, None, &b, tiles),
            _ => ViewSet::ortho(crate::view::Axis::X, Some(0.3), &b, tiles),
        };
        vs.views[match face {
            0..6 => face,
            8 => 1,
            _ => 0,
        }]
    }

    fn v3() -> impl Strategy<Value = Vec3> {
        (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Sutherland–Hodgman written plainly (every vertex evaluated per edge,
    /// always copied): what `Polygon::clip` must equal bit for bit.
    fn clip_plain(poly: &Polygon, h: &HalfSpace, eps: f32) -> Polygon {
        let n = poly.len;
        let mut out = Polygon {
            len: 0,
            v: [[0.0; 3]; MAX_POLY],
        };
        for k in 0..n {
            let p = poly.v[k];
            let q = poly.v[(k + 1) % n];
            let fp = h.eval(p, eps);
            let fq = h.eval(q, eps);
            if fp >= 0.0 && out.len < MAX_POLY {
                out.v[out.len] = p;
                out.len += 1;
            }
            if ((fp >= 0.0) != (fq >= 0.0)) && out.len < MAX_POLY {
                let w = fp / (fp - fq);
                out.v[out.len] = [
                    p[0] + (q[0] - p[0]) * w,
                    p[1] + (q[1] - p[1]) * w,
                    p[2] + (q[2] - p[2]) * w,
                ];
                out.len += 1;
            }
        }
        out
    }

    fn bits(p: &Polygon) -> Vec<[u32; 3]> {
        p.vertices().iter().map(|q| q.map(f32::to_bits)).collect()
    }

    proptest! {
        // Every sampled point of a triangle that lies inside a tile's frustum
        // has a depth inside the tile extent computed by clipping.
        #[test]
        fn clipped_extents_contain_sampled_points(a in v3(), b in v3(), c in v3(), face in 0usize..9, tiles in 1u32..12) {
            let v = &face_view(face, tiles);
            let tri = [v.to_view(a), v.to_view(b), v.to_view(c)];
            let poly = clip_triangle_to_view(v, tri);
            let n = 24;
            for s in 0..=n {
                for t in 0..=(n - s) {
                    let (fs, ft) = (s as f32 / n as f32, t as f32 / n as f32);
                    let p = a + (b - a) * fs + (c - a) * ft;
                    let q = v.to_view(p);
                    if !(q[2] >= v.near && q[2] <= v.far) { continue; }
                    let (sx, sy) = (q[0] / v.w(q[2]), q[1] / v.w(q[2]));
                    if sx.abs() > v.tan || sy.abs() > v.tan { continue; }
                    let i = (v.tile_coord(sx).floor() as i64).clamp(0, tiles as i64 - 1) as u32;
                    let j = (v.tile_coord(sy).floor() as i64).clamp(0, tiles as i64 - 1) as u32;
                    let poly = poly.expect("a point inside the view means the clipped triangle is not empty");
                    let (i0, i1, j0, j1) = polygon_tile_range(v, &poly).expect("tile range");
                    prop_assert!(i0 <= i && i <= i1 && j0 <= j && j <= j1);
                    let (lo, hi) = tile_depth_extent(v, &poly, (i0, i1, j0, j1), i, j).expect("the tile holding a point of the triangle has an extent");
                    prop_assert!(lo <= q[2] && q[2] <= hi, "{} not in [{}, {}]", q[2], lo, hi);
                }
            }
        }

        // The shortcuts of Polygon::clip (all inside, all outside, one
        // evaluation per vertex) change no bit of the plain algorithm, through
        // a whole view and tile clip.
        #[test]
        fn polygon_clip_equals_plain(a in v3(), b in v3(), c in v3(), face in 0usize..6, tiles in 1u32..12, i in 0u32..12, j in 0u32..12) {
            let vs = cube(tiles);
            let v = &vs.views[face];
            let (i, j) = (i % tiles, j % tiles);
            let mut fast = Polygon::triangle(v.to_view(a), v.to_view(b), v.to_view(c));
            let mut plain = fast;
            let planes: Vec<HalfSpace> = view_frustum(v).into_iter().chain(block_frustum(v, i, i + 1, j, j + 1)).collect();
            let range_bits = |r: Option<(f32, f32)>| r.map(|(lo, hi)| (lo.to_bits(), hi.to_bits()));
            for h in &planes {
                // Only the depths of the clip: those of the clipped polygon.
                let depths = fast.clipped_depth_range(h, v.eps);
                fast.clip(h, v.eps);
                plain = clip_plain(&plain, h, v.eps);
                prop_assert_eq!(bits(&fast), bits(&plain));
                prop_assert_eq!(range_bits(depths), range_bits(plain.depth_range()));
            }
        }

        // The all-inside shortcut of clip_triangle_to_view changes no bit of
        // the plain clip through the six planes (the triangles here are both
        // inside and across the view's sides: small ones around `a`, large ones).
        #[test]
        fn view_clip_equals_plain(a in v3(), b in v3(), c in v3(), face in 0usize..6, scale in prop_oneof![Just(0.05f32), Just(1.0)]) {
            let vs = cube(4);
            let v = &vs.views[face];
            let tri = [v.to_view(a), v.to_view(a + b * scale), v.to_view(a + c * scale)];
            let mut plain = Polygon::triangle(tri[0], tri[1], tri[2]);
            for h in &view_frustum(v) {
                plain = clip_plain(&plain, h, v.eps);
            }
            let fast = clip_triangle_to_view(v, tri);
            prop_assert_eq!(fast.map(|p| bits(&p)).unwrap_or_default(), bits(&plain));
        }

        // for_each_covered_tile (column strips) reports exactly the tiles and
        // extents of tile_depth_extent over the tile range, bit for bit.
        #[test]
        fn covered_tiles_equal_tile_extents(a in v3(), b in v3(), c in v3(), face in 0usize..9, tiles in 1u32..16) {
            let v = &face_view(face, tiles);
            let tri = [v.to_view(a), v.to_view(b), v.to_view(c)];
            let mut got = Vec::new();
            for_each_covered_tile(v, tri, |i, j, lo, hi| got.push((i, j, lo.to_bits(), hi.to_bits())));
            let mut want = Vec::new();
            if let Some(poly) = clip_triangle_to_view(v, tri)
                && let Some((i0, i1, j0, j1)) = polygon_tile_range(v, &poly)
            {
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        if let Some((lo, hi)) = tile_depth_extent(v, &poly, (i0, i1, j0, j1), i, j) {
                            want.push((i, j, lo.to_bits(), hi.to_bits()));
                        }
                    }
                }
            }
            prop_assert_eq!(got, want);
        }

        // Points of a ray inside the view lie inside the clipped interval.
        #[test]
        fn ray_clip_contains_points_inside(o in v3(), d in v3(), face in 0usize..6) {
            prop_assume!(d.length() > 1e-3);
            let vs = cube(4);
            let v = &vs.views[face];
            let ray = Ray::new(o, d, 0.0, 10.0);
            let vr = v.ray(&ray);
            let (iv, _) = clip_ray_to_view(v, &vr, ray.tmin, ray.tmax);
            for k in 0..=200 {
                let t = k as f32 * 0.05;
                let q = v.to_view(ray.at(t));
                if q[2] >= v.near && q[2] <= v.far && q[0].abs() <= q[2] && q[1].abs() <= q[2] {
                    prop_assert!(iv.t0 <= t && t <= iv.t1, "t={} outside [{}, {}]", t, iv.t0, iv.t1);
                }
            }
        }
    }
}
