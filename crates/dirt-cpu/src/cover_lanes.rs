//! [`for_each_fragment`] over a piece of triangles, [`LANES`] triangles at
//! a time: the part of the coverage rule every triangle pays — its vertices
//! in view space, whether they lie inside the view's (dilated) frustum, and
//! the range of tiles the triangle may touch — as lanes the compiler puts
//! side by side in vector registers. Each lane computes the scalar code's
//! values from the same operands in the same order (`+ − ×`, correctly
//! rounded `/`, comparisons and selects; no fused multiply-add), so it has
//! its bits: [`View::to_view`], the all-inside test of
//! [`clip_triangle_to_view_into`], [`Polygon::depth_range`] and
//! [`polygon_tile_range`].
//!
//! A triangle inside the frustum whose range is one tile gets that tile's
//! fragment from the lanes (the depth range of its vertices, as
//! [`cover_tiles`] computes it for a range of one tile); one inside the
//! frustum over several tiles goes on to [`cover_tiles`] from its range; one
//! that crosses the frustum is covered by [`for_each_covered_tile`] alone.
//! Small triangles, one tile each, are most of a deforming grid's or a
//! finely tessellated model's, and there the prologue was most of the
//! coverage's cost. The tests below check that the fragments, their order
//! and their bits are [`for_each_fragment`]'s on random triangles and views.
//!
//! [`View::to_view`]: dirt_math::View::to_view
//! [`clip_triangle_to_view_into`]: dirt_math::clip::clip_triangle_to_view_into
//! [`Polygon::depth_range`]: dirt_math::clip::Polygon::depth_range
//! [`polygon_tile_range`]: dirt_math::clip::polygon_tile_range

use crate::fill_depth::for_each_fragment;
use dirt_math::clip::{HalfSpace, Polygon, cover_tiles, for_each_covered_tile, view_frustum};
use dirt_math::num::{floor_index, fmax, fmin};
use dirt_math::{Triangle, View, ViewSet};
use std::array::from_fn;

/// Triangles whose prologue is computed together: two SSE2 (or NEON)
/// vectors of `f32` a value.
pub(crate) const LANES: usize = 8;

type L = [f32; LANES];

/// Most views of a set ([`ViewSet::cube`]'s six).
const MAX_VIEWS: usize = 6;

/// What the lanes found for one triangle in one view.
#[derive(Clone, Copy, Debug)]
enum Cover {
    /// Inside the frustum, touching no tile.
    Nothing,
    /// Inside the frustum, in one tile: `(i, j, zlo, zhi)`.
    One(u32, u32, f32, f32),
    /// Inside the frustum, over the tile range `(i0, i1, j0, j1)`.
    Range(u32, u32, u32, u32),
    /// Crossing the frustum: to be clipped to it.
    Clip,
}

/// [`HalfSpace::eval`] of three points' lanes.
#[inline(always)]
fn eval_lanes(h: &HalfSpace, p: &[L; 3], eps: f32) -> L {
    match *h {
        HalfSpace::Lo { axis, s } => from_fn(|k| p[axis][k] - s * p[2][k] + eps),
        HalfSpace::Hi { axis, s } => from_fn(|k| s * p[2][k] - p[axis][k] + eps),
        HalfSpace::Near(n) => from_fn(|k| p[2][k] - n + eps),
        HalfSpace::Far(f) => from_fn(|k| f - p[2][k] + eps),
        HalfSpace::OrthoLo { axis, s } => from_fn(|k| p[axis][k] - s + eps),
        HalfSpace::OrthoHi { axis, s } => from_fn(|k| s - p[axis][k] + eps),
    }
}

/// The covers of lanes `tri` (world-space vertex `n`, component `c`, lane
/// `k` at `tri[n][c][k]`) in view `v` into `covers`, and their view-space
/// vertices into `tv` (written in place: returned, they were copied).
#[inline(always)]
fn cover_lanes(v: &View, tri: &[[L; 3]; 3], covers: &mut [Cover; LANES], tv: &mut [[L; 3]; 3]) {
    // View::to_view: q = p - apex, then dot3 with right, up, forward.
    let apex = v.apex.to_array();
    for (tv, tri) in tv.iter_mut().zip(tri) {
        let q: [L; 3] = from_fn(|c| from_fn(|k| tri[c][k] - apex[c]));
        let dot = |a: dirt_math::Vec3| -> L {
            from_fn(|k| q[0][k] * a.x + q[1][k] * a.y + q[2][k] * a.z)
        };
        *tv = [dot(v.right), dot(v.up), dot(v.forward)];
    }
    let tv = &*tv;
    // clip_triangle_to_view_into's test: every vertex inside every plane.
    let mut inside = [true; LANES];
    for h in &view_frustum(v) {
        for p in tv {
            let f = eval_lanes(h, p, v.eps);
            inside = from_fn(|k| inside[k] & (f[k] >= 0.0));
        }
    }
    // Polygon::depth_range of the triangle: folds from ±inf in vertex order.
    let mut zlo = [f32::INFINITY; LANES];
    let mut zhi = [f32::NEG_INFINITY; LANES];
    for p in tv {
        zlo = from_fn(|k| fmin(zlo[k], p[2][k]));
        zhi = from_fn(|k| fmax(zhi[k], p[2][k]));
    }
    // polygon_tile_range.
    let w = |z: L| -> L {
        if v.ortho {
            [1.0; LANES]
        } else {
            from_fn(|k| fmax(z[k], v.near * 0.5))
        }
    };
    let z = w(zlo);
    let delta: L = from_fn(|k| v.eps / z[k] / v.step + 1.0 / 256.0);
    let (mut xlo, mut xhi) = ([f32::INFINITY; LANES], [f32::NEG_INFINITY; LANES]);
    let (mut ylo, mut yhi) = (xlo, xhi);
    for p in tv {
        let pz = w(p[2]);
        let x: L = from_fn(|k| (p[0][k] / pz[k] + v.tan) / v.step);
        let y: L = from_fn(|k| (p[1][k] / pz[k] + v.tan) / v.step);
        xlo = from_fn(|k| fmin(xlo[k], x[k]));
        xhi = from_fn(|k| fmax(xhi[k], x[k]));
        ylo = from_fn(|k| fmin(ylo[k], y[k]));
        yhi = from_fn(|k| fmax(yhi[k], y[k]));
    }
    let (tiles, last) = (v.tiles as f32, v.tiles - 1);
    *covers = from_fn(|k| {
        if !inside[k] {
            return Cover::Clip;
        }
        let d = delta[k];
        if !(xhi[k] + d >= 0.0 && yhi[k] + d >= 0.0 && xlo[k] - d <= tiles && ylo[k] - d <= tiles) {
            return Cover::Nothing;
        }
        let (i0, i1) = (floor_index(xlo[k] - d, last), floor_index(xhi[k] + d, last));
        let (j0, j1) = (floor_index(ylo[k] - d, last), floor_index(yhi[k] + d, last));
        if i0 == i1 && j0 == j1 {
            // cover_tiles on a range of one tile: the unclipped extent.
            Cover::One(i0, j0, zlo[k] - v.eps, zhi[k] + v.eps)
        } else {
            Cover::Range(i0, i1, j0, j1)
        }
    });
}

/// [`for_each_fragment`](crate::fill_depth::for_each_fragment) for every
/// triangle of `tris` in turn: `item(state, tile, zlo, zhi)` for each of a
/// triangle's fragments, in its order, then `end(state)`.
pub(crate) fn for_each_fragment_in<S>(
    set: &ViewSet,
    tris: &[Triangle],
    state: &mut S,
    mut item: impl FnMut(&mut S, usize, f32, f32),
    mut end: impl FnMut(&mut S),
) {
    let views: Vec<&View> = set.views.iter().filter(|v| v.has_content).collect();
    if views.len() > MAX_VIEWS {
        for t in tris {
            for_each_fragment(set, t, |tile, lo, hi| item(state, tile, lo, hi));
            end(state);
        }
        return;
    }
    let mut covers = [[Cover::Nothing; LANES]; MAX_VIEWS];
    let mut tvs = [[[[0.0; LANES]; 3]; 3]; MAX_VIEWS];
    for group in tris.chunks(LANES) {
        // Lanes past the group's triangles repeat its last; they are not used.
        let tri: [[L; 3]; 3] =
            from_fn(|n| from_fn(|c| from_fn(|k| group[k.min(group.len() - 1)].v[n][c])));
        for (f, v) in views.iter().enumerate() {
            cover_lanes(v, &tri, &mut covers[f], &mut tvs[f]);
        }
        for k in 0..group.len() {
            for (f, v) in views.iter().enumerate() {
                let base = v.slot as usize * v.tile_count();
                let tiles = v.tiles as usize;
                let mut emit = |i: u32, j: u32, lo: f32, hi: f32| {
                    item(state, base + j as usize * tiles + i as usize, lo, hi)
                };
                let tv = &tvs[f];
                let vertex = |n: usize| [tv[n][0][k], tv[n][1][k], tv[n][2][k]];
                match covers[f][k] {
                    Cover::Nothing => {}
                    Cover::One(i, j, lo, hi) => emit(i, j, lo, hi),
                    Cover::Range(i0, i1, j0, j1) => {
                        let poly = Polygon::triangle(vertex(0), vertex(1), vertex(2));
                        cover_tiles(v, &poly, (i0, i1, j0, j1), emit);
                    }
                    Cover::Clip => {
                        for_each_covered_tile(v, [vertex(0), vertex(1), vertex(2)], emit);
                    }
                }
            }
            end(state);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_math::view::Axis;
    use dirt_math::{Aabb, Vec3};
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f32> {
        prop_oneof![
            6 => -2.0f32..2.0,
            1 => Just(0.0f32),
            1 => Just(-0.0f32),
            1 => -1e-6f32..1e-6,
            1 => -40.0f32..40.0,
        ]
    }

    fn v3() -> impl Strategy<Value = Vec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Small triangles near a point (one tile, or a few), large ones, and
    /// some sharing vertices or degenerate.
    fn triangles() -> impl Strategy<Value = Vec<Triangle>> {
        prop::collection::vec(
            (
                v3(),
                v3(),
                v3(),
                prop_oneof![Just(1e-3f32), Just(0.05f32), Just(1.0f32)],
            ),
            1..40,
        )
        .prop_map(|ts| {
            ts.iter()
                .enumerate()
                .map(|(n, &(a, b, c, s))| match n % 4 {
                    // A small triangle around `a`.
                    0 | 1 => Triangle::new(a, a + b * s, a + c * s),
                    // Degenerate: two equal vertices.
                    2 if s < 0.01 => Triangle::new(a, a, c),
                    _ => Triangle::new(a, b, c),
                })
                .collect()
        })
    }

    fn view_set(kind: usize, tiles: u32, centre: Vec3) -> ViewSet {
        let b = Aabb {
            min: Vec3::splat(-2.0),
            max: Vec3::splat(2.0),
        };
        match kind {
            0 => ViewSet::cube(centre, &b, tiles),
            1 => ViewSet::single(Some(centre * 2.0 + Vec3::new(0.0, 0.0, 5.0)), &b, tiles),
            2 => ViewSet::ortho(Axis::Y, None, &b, tiles),
            _ => ViewSet::ortho(Axis::X, Some(centre.x), &b, tiles),
        }
    }

    /// Every fragment with its triangle, and where each triangle's end.
    type Walk = Vec<(usize, usize, u32, u32)>;

    fn lanes(views: &ViewSet, tris: &[Triangle]) -> Walk {
        let mut got = (Walk::new(), 0usize);
        for_each_fragment_in(
            views,
            tris,
            &mut got,
            |(w, t), tile, lo, hi| w.push((*t, tile, lo.to_bits(), hi.to_bits())),
            |(_, t)| *t += 1,
        );
        assert_eq!(got.1, tris.len(), "one end a triangle");
        got.0
    }

    fn plain(views: &ViewSet, tris: &[Triangle]) -> Walk {
        let mut w = Walk::new();
        for (t, tri) in tris.iter().enumerate() {
            for_each_fragment(views, tri, |tile, lo, hi| {
                w.push((t, tile, lo.to_bits(), hi.to_bits()))
            });
        }
        w
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        #[test]
        fn lanes_give_the_plain_fragments_bit_for_bit(
            tris in triangles(),
            kind in 0usize..4,
            tiles in prop_oneof![1u32..5, 5u32..70],
            centre in (-0.5f32..0.5, -0.5f32..0.5, -0.5f32..0.5),
        ) {
            let views = view_set(kind, tiles, Vec3::new(centre.0, centre.1, centre.2));
            prop_assert_eq!(lanes(&views, &tris), plain(&views, &tris));
        }
    }

    #[test]
    fn every_kind_of_cover_is_taken() {
        // A one-tile, a many-tile, a crossing and an outside triangle in one
        // single view, so that each arm above is exercised.
        let views = view_set(2, 16, Vec3::ZERO);
        let v = &views.views[0];
        let t = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| {
            Triangle::new(Vec3::from(a), Vec3::from(b), Vec3::from(c))
        };
        let tris = [
            t([0.01, 0.0, 0.01], [0.02, 0.0, 0.01], [0.01, 0.0, 0.02]),
            t([-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.5, 1.0]),
            t([-9.0, 0.0, 0.0], [0.0, 0.0, 0.1], [0.0, 0.3, 0.2]),
            t([9.0, 9.0, 9.0], [9.5, 9.0, 9.0], [9.0, 9.5, 9.0]),
        ];
        let tri: [[L; 3]; 3] =
            from_fn(|n| from_fn(|c| from_fn(|k| tris[k.min(tris.len() - 1)].v[n][c])));
        let mut covers = [Cover::Nothing; LANES];
        cover_lanes(v, &tri, &mut covers, &mut [[[0.0; LANES]; 3]; 3]);
        assert!(matches!(covers[0], Cover::One(..)), "{:?}", covers[0]);
        assert!(matches!(covers[1], Cover::Range(..)), "{:?}", covers[1]);
        assert!(matches!(covers[2], Cover::Clip), "{:?}", covers[2]);
        assert!(
            matches!(covers[3], Cover::Clip | Cover::Nothing),
            "{:?}",
            covers[3]
        );
        assert_eq!(lanes(&views, &tris), plain(&views, &tris));
    }
}
