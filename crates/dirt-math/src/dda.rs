//! Walking the tiles a ray crosses in one view.
//!
//! [`walk_tiles`] is the conservative 2D DDA of the linear traversal: it steps
//! through the slabs ("bands") of tiles along the major axis of the projected
//! segment in the ray's direction and, inside each band, through the tiles of
//! the minor axis the segment spans there. Every tile whose (dilated) frustum
//! the ray segment enters is yielded, corner crossings included, each with the
//! ray's parameter interval inside it, so the caller knows its depth span.
//!
//! [`HiZCell`] and [`child_order`] are the stepping helpers of the hierarchical
//! traversal: the interval of a ray inside a cell of the Hi-Z pyramid, and the
//! front-to-back order of a cell's four children.

use crate::clip::{Interval, ray_point};
use crate::num::{floor_index, fmax, fmin};
use crate::view::{View, ViewRay};

/// A tile with the ray's interval inside its dilated frustum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileSpan {
    pub i: u32,
    pub j: u32,
    pub iv: Interval,
}

/// What the visitor of [`walk_tiles`] tells the walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    Continue,
    Stop,
}

/// Projected tile coordinates of the ray at `t` (depth clamped away from the apex).
#[inline]
pub fn tile_xy(v: &View, vr: &ViewRay, t: f32) -> [f32; 2] {
    let p = ray_point(vr, t);
    let z = v.w(p[2]);
    [v.tile_coord(p[0] / z), v.tile_coord(p[1] / z)]
}

/// Dilation of the walk in tile units: the ray's `eps` seen at the smallest
/// depth of the segment, plus room for the rounding of the projection.
#[inline]
pub fn dilation(v: &View, vr: &ViewRay, iv: &Interval) -> f32 {
    let z0 = vr.o[2] + iv.t0 * vr.d[2];
    let z1 = vr.o[2] + iv.t1 * vr.d[2];
    let z = v.w(fmin(z0, z1) - vr.eps);
    vr.eps / z / v.step + 1.0 / 256.0
}

/// Inclusive tile index range of the continuous coordinates `a`, `b`, dilated by `d`
/// (how the walk picks its bands, and the tiles of a band).
#[inline]
pub fn index_range(a: f32, b: f32, d: f32, tiles: u32) -> Option<(u32, u32)> {
    let lo = fmin(a, b) - d;
    let hi = fmax(a, b) + d;
    if !(hi >= 0.0 && lo < tiles as f32) {
        return None;
    }
    let last = tiles - 1;
    Some((floor_index(lo, last), floor_index(hi, last)))
}

/// `iv` clipped to slab `k` of `axis` (slopes between tile boundaries `k`
/// and `k + 1`): how the walk cuts a band of tiles, and a tile of a band.
#[inline]
pub fn clip_to_slab(v: &View, vr: &ViewRay, iv: Interval, axis: usize, k: u32) -> Interval {
    let mut slab = iv;
    slab.clip(&v.lo(axis, v.boundary(k)), vr);
    slab.clip(&v.hi(axis, v.boundary(k + 1)), vr);
    slab
}

/// How [`walk_tiles`] orders the tiles a ray crosses within `iv`: bands of
/// tiles cut across the `major` axis (the one the ray's projection moves
/// most along), bands `k0..=k1` visited `forward` or backward, the tiles of
/// a band `minor_forward` or backward, every range dilated by `delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkPlan {
    pub major: usize,
    pub forward: bool,
    pub minor_forward: bool,
    pub delta: f32,
    pub k0: u32,
    pub k1: u32,
}

impl WalkPlan {
    /// The plan of the ray `vr` over `iv` (clipped to the view); `None`
    /// when the walk visits no tile.
    #[inline]
    pub fn of(v: &View, vr: &ViewRay, iv: Interval) -> Option<WalkPlan> {
        if iv.is_empty() || v.tiles == 0 {
            return None;
        }
        let a = tile_xy(v, vr, iv.t0);
        let b = tile_xy(v, vr, iv.t1);
        let delta = dilation(v, vr, &iv);
        let major = if (b[0] - a[0]).abs() >= (b[1] - a[1]).abs() {
            0
        } else {
            1
        };
        let minor = 1 - major;
        let (k0, k1) = index_range(a[major], b[major], delta, v.tiles)?;
        Some(WalkPlan {
            major,
            forward: b[major] >= a[major],
            minor_forward: b[minor] >= a[minor],
            delta,
            k0,
            k1,
        })
    }

    /// The axis the tiles of a band run along.
    #[inline]
    pub fn minor(&self) -> usize {
        1 - self.major
    }

    /// The index of the `n`-th band the walk visits (`n <= k1 - k0`).
    #[inline]
    pub fn band(&self, n: u32) -> u32 {
        if self.forward {
            self.k0 + n
        } else {
            self.k1 - n
        }
    }
}

/// Calls `visit` for every tile of `v` the ray crosses within `iv` (already
/// clipped to the view), front to back along the major axis. `visit` returns
/// [`Walk::Stop`] to end the walk. `bound` is consulted before each band: when
/// the band is entered after `bound()`, the walk ends (the termination rule:
/// no later tile can hold a closer hit).
pub fn walk_tiles(
    v: &View,
    vr: &ViewRay,
    iv: Interval,
    bound: &mut dyn FnMut() -> f32,
    visit: &mut dyn FnMut(TileSpan) -> Walk,
) {
    let Some(plan) = WalkPlan::of(v, vr, iv) else {
        return;
    };
    let (major, minor) = (plan.major, plan.minor());
    for n in 0..=(plan.k1 - plan.k0) {
        let k = plan.band(n);
        let band = clip_to_slab(v, vr, iv, major, k);
        if band.is_empty() {
            continue;
        }
        if band.t0 > bound() {
            return;
        }
        let p = tile_xy(v, vr, band.t0);
        let q = tile_xy(v, vr, band.t1);
        let Some((m0, m1)) = index_range(p[minor], q[minor], plan.delta, v.tiles) else {
            continue;
        };
        for e in 0..=(m1 - m0) {
            let m = if plan.minor_forward { m0 + e } else { m1 - e };
            let span = clip_to_slab(v, vr, band, minor, m);
            if span.is_empty() {
                continue;
            }
            let (i, j) = if major == 0 { (k, m) } else { (m, k) };
            if visit(TileSpan { i, j, iv: span }) == Walk::Stop {
                return;
            }
        }
    }
}

/// A cell of level `level` of the Hi-Z pyramid: tiles `[i·2^level, (i+1)·2^level)`
/// × the same in `j`, cut at the grid's edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HiZCell {
    pub level: u32,
    pub i: u32,
    pub j: u32,
}

impl HiZCell {
    /// The ray's interval inside the cell's dilated frustum.
    pub fn clip(&self, v: &View, vr: &ViewRay, iv: Interval) -> Interval {
        let i0 = self.i << self.level;
        let j0 = self.j << self.level;
        let i1 = ((self.i + 1) << self.level).min(v.tiles);
        let j1 = ((self.j + 1) << self.level).min(v.tiles);
        let mut out = iv;
        for h in &crate::clip::block_frustum(v, i0, i1, j0, j1) {
            out.clip(h, vr);
            if out.is_empty() {
                return Interval::EMPTY;
            }
        }
        out
    }
}

/// Number of Hi-Z levels for `tiles` tiles per side (level 0 = tiles, the last has one cell).
pub fn hiz_levels(tiles: u32) -> u32 {
    let mut n = 1;
    let mut w = tiles.max(1);
    while w > 1 {
        w = w.div_ceil(2);
        n += 1;
    }
    n
}

/// Cells per side at `level`.
pub fn hiz_width(tiles: u32, level: u32) -> u32 {
    let mut w = tiles.max(1);
    for _ in 0..level {
        w = w.div_ceil(2);
    }
    w
}

/// Front-to-back order of the four children `(di, dj)` of a cell for a ray whose
/// projection moves by `(dx, dy)`: the corner it enters first, then the
/// neighbour along the major axis, then along the minor axis, then the far corner.
pub fn child_order(dx: f32, dy: f32) -> [(u32, u32); 4] {
    let fx = if dx >= 0.0 { 0 } else { 1 };
    let fy = if dy >= 0.0 { 0 } else { 1 };
    if dx.abs() >= dy.abs() {
        [(fx, fy), (1 - fx, fy), (fx, 1 - fy), (1 - fx, 1 - fy)]
    } else {
        [(fx, fy), (fx, 1 - fy), (1 - fx, fy), (1 - fx, 1 - fy)]
    }
}

/// Direction of the projected segment in tile units (for [`child_order`]).
pub fn projected_direction(v: &View, vr: &ViewRay, iv: &Interval) -> (f32, f32) {
    let a = tile_xy(v, vr, iv.t0);
    let b = tile_xy(v, vr, iv.t1);
    (b[0] - a[0], b[1] - a[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::clip_ray_to_view;
    use crate::types::{Aabb, Ray};
    use crate::view::ViewSet;
    use glam::Vec3;
    use proptest::prelude::*;
    use std::collections::HashMap;

    fn v3(r: f32) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn walk(v: &View, ray: &Ray) -> (Interval, Vec<TileSpan>) {
        let vr = v.ray(ray);
        let (iv, _) = clip_ray_to_view(v, &vr, ray.tmin, ray.tmax);
        let mut out = Vec::new();
        walk_tiles(v, &vr, iv, &mut || f32::INFINITY, &mut |s| {
            out.push(s);
            Walk::Continue
        });
        (iv, out)
    }

    /// The tile of a sampled point, and whether it is safely inside the view.
    fn tile_of(v: &View, p: Vec3) -> Option<(u32, u32)> {
        let q = v.to_view(p);
        if !(q[2] >= v.near && q[2] <= v.far) {
            return None;
        }
        let (sx, sy) = (q[0] / v.w(q[2]), q[1] / v.w(q[2]));
        if sx.abs() > v.tan || sy.abs() > v.tan {
            return None;
        }
        let c = |s: f32| (v.tile_coord(s).floor() as i64).clamp(0, v.tiles as i64 - 1) as u32;
        Some((c(sx), c(sy)))
    }

    fn check_dense_sampling(v: &View, ray: &Ray) -> Result<(), TestCaseError> {
        let (_, spans) = walk(v, ray);
        let mut seen: HashMap<(u32, u32), Interval> = HashMap::new();
        for s in &spans {
            prop_assert!(
                seen.insert((s.i, s.j), s.iv).is_none(),
                "tile {:?} yielded twice",
                (s.i, s.j)
            );
        }
        let n = 4000;
        for k in 0..=n {
            let t = ray.tmin + (ray.tmax - ray.tmin) * (k as f32 / n as f32);
            if let Some(tile) = tile_of(v, ray.at(t)) {
                let iv = seen.get(&tile);
                prop_assert!(iv.is_some(), "tile {:?} of t={} not visited", tile, t);
                let iv = iv.copied().unwrap_or(Interval::EMPTY);
                prop_assert!(
                    iv.t0 <= t && t <= iv.t1,
                    "t={} outside the tile's span [{}, {}]",
                    t,
                    iv.t0,
                    iv.t1
                );
            }
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]
        #[test]
        fn visits_every_tile_a_dense_sampling_touches(o in v3(3.0), d in v3(1.0), face in 0usize..6, tiles in 1u32..40) {
            prop_assume!(d.length() > 1e-3);
            let vs = ViewSet::cube(Vec3::new(0.2, -0.1, 0.05), &Aabb { min: Vec3::splat(-2.0), max: Vec3::splat(2.0) }, tiles);
            check_dense_sampling(&vs.views[face], &Ray::new(o, d, 0.0, 8.0))?;
        }

        #[test]
        fn ortho_visits_every_tile_a_dense_sampling_touches(o in v3(3.0), d in v3(1.0), axis in 0usize..3, which in 0usize..3, tiles in 1u32..40) {
            prop_assume!(d.length() > 1e-3);
            let b = Aabb { min: Vec3::new(-2.0, -1.0, -0.5), max: Vec3::new(2.0, 1.5, 0.5) };
            let axis = crate::view::Axis::ALL[axis];
            let vs = ViewSet::ortho(axis, (which > 0).then_some(0.25), &b, tiles);
            check_dense_sampling(&vs.views[which.saturating_sub(1)], &Ray::new(o, d, 0.0, 8.0))?;
        }

        // Rays through tile corners (exact corner crossings) and along tile boundaries.
        #[test]
        fn corner_and_boundary_crossings(i in 0u32..16, j in 0u32..16, face in 0usize..6, o in v3(1.5), along in proptest::bool::ANY) {
            let vs = ViewSet::cube(Vec3::ZERO, &Aabb { min: Vec3::splat(-2.0), max: Vec3::splat(2.0) }, 16);
            let v = &vs.views[face];
            let target = v.apex + v.forward * 2.0 + v.right * (v.boundary(i) * 2.0) + v.up * (v.boundary(j) * 2.0);
            let ray = if along {
                // Along a boundary plane through the apex.
                Ray::new(v.apex + v.forward * 0.5 + v.right * (v.boundary(i) * 0.5), target - (v.apex + v.forward * 0.5 + v.right * (v.boundary(i) * 0.5)), 0.0, 3.0)
            } else {
                Ray::new(o, target - o, 0.0, 3.0)
            };
            prop_assume!(ray.dir().length() > 1e-3);
            check_dense_sampling(v, &ray)?;
        }
    }

    #[test]
    fn hiz_shapes() {
        assert_eq!(hiz_levels(1), 1);
        assert_eq!(hiz_levels(2), 2);
        assert_eq!(hiz_levels(5), 4);
        assert_eq!(hiz_width(5, 1), 3);
        assert_eq!(hiz_width(5, 3), 1);
        let o = child_order(1.0, 0.5);
        assert_eq!(o[0], (0, 0));
        assert_eq!(o[3], (1, 1));
        assert_eq!(child_order(-1.0, -2.0)[0], (1, 1));
    }
}
