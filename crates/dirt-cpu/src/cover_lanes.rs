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
//! [`cover_tiles`] computes it for a range of one tile). One whose range is
//! two tiles, side by side or one above the other, gets each tile's part
//! from [`two_tiles`]: the one clip a tile takes there, at the middle
//! boundary, written for a triangle (no polygon copied, only the components
//! used). One whose range is two by two tiles gets them from [`four_tiles`]:
//! a clip at the middle x boundary per column, then one at the middle y
//! boundary per tile, written for a triangle like [`two_tiles`] (half of
//! the bunny's triangles at ortho r32, where [`cover_tiles`]' polygons
//! took 1,860 instructions a triangle and these take 540). One over more
//! tiles goes on to [`cover_tiles`] from its range; one that crosses the
//! frustum is covered by [`for_each_covered_tile`] alone. On a deforming
//! grid of small triangles nine in ten take the first two ways, and the
//! prologue and those clips were most of the coverage's cost. (Clipping
//! every lane at once, as slots under masks, measured 40 % slower than
//! [`cover_tiles`].)
//! The tests below check that the fragments, their order and their bits
//! are [`for_each_fragment`]'s on random triangles and views.
//!
//! [`View::to_view`]: dirt_math::View::to_view
//! [`clip_triangle_to_view_into`]: dirt_math::clip::clip_triangle_to_view_into
//! [`Polygon::depth_range`]: dirt_math::clip::Polygon::depth_range
//! [`polygon_tile_range`]: dirt_math::clip::polygon_tile_range

use crate::fill_depth::for_each_fragment;
use crate::trace_fast::{ViewBox, image_box};
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

/// A tile `(i, j)` and a triangle's depth extent there, if it reaches it.
type TilePart = (u32, u32, Option<(f32, f32)>);

/// What the lanes found for one triangle in one view.
#[derive(Clone, Copy, Debug)]
enum Cover {
    /// No fragment: outside a plane of the frustum, or inside it but
    /// touching no tile.
    Nothing,
    /// Inside the frustum, in one tile: `(i, j, zlo, zhi)`.
    One(u32, u32, f32, f32),
    /// Inside the frustum, over two tiles (side by side or one above the
    /// other): each tile with the triangle's depth extent there, if any.
    Two([TilePart; 2]),
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
/// vertices into `tv` (written in place: returned, they were copied). With
/// `inside`, also clears the lanes that may not lie inside the frustum
/// shrunk by `eps` (every vertex inside every plane: the frustum is convex).
/// Returns each lane's [`tile_extent`] of the unclipped triangle,
/// `[x0, x1, y0, y1]` (its bits: the values the range is floored from).
///
/// [`tile_extent`]: dirt_math::clip::tile_extent
#[inline(always)]
fn cover_lanes(
    v: &View,
    tri: &[[L; 3]; 3],
    covers: &mut [Cover; LANES],
    tv: &mut [[L; 3]; 3],
    mut inside: Option<&mut [bool; LANES]>,
) -> [L; 4] {
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
    // clip_triangle_to_view_into: every vertex inside every plane leaves the
    // triangle as it is; else the planes clip in order, and the first that
    // has a vertex outside empties it if it has every vertex outside (the
    // triangle reaches it unchanged). Then the view gets nothing of it.
    let mut cut = [false; LANES];
    let mut outside = [false; LANES];
    for h in &view_frustum(v) {
        let f = [
            eval_lanes(h, &tv[0], v.eps),
            eval_lanes(h, &tv[1], v.eps),
            eval_lanes(h, &tv[2], v.eps),
        ];
        let all_in: [bool; LANES] =
            from_fn(|k| (f[0][k] >= 0.0) & (f[1][k] >= 0.0) & (f[2][k] >= 0.0));
        let all_out: [bool; LANES] =
            from_fn(|k| !(f[0][k] >= 0.0) & !(f[1][k] >= 0.0) & !(f[2][k] >= 0.0));
        outside = from_fn(|k| outside[k] | (!cut[k] & all_out[k]));
        cut = from_fn(|k| cut[k] | !all_in[k]);
        if let Some(inside) = inside.as_deref_mut() {
            // `f = a + eps` at least `3·eps` leaves `a − eps`, the plane
            // shrunk by `eps`, positive through both roundings.
            let deep = 3.0 * v.eps;
            *inside =
                from_fn(|k| inside[k] & (f[0][k] >= deep) & (f[1][k] >= deep) & (f[2][k] >= deep));
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
    let w = |z: L| -> L { from_fn(|k| v.w(z[k])) };
    let z = w(zlo);
    let delta: L = from_fn(|k| v.eps / z[k] / v.step + 1.0 / 256.0);
    let (mut xlo, mut xhi) = ([f32::INFINITY; LANES], [f32::NEG_INFINITY; LANES]);
    let (mut ylo, mut yhi) = (xlo, xhi);
    for p in tv {
        let pz = w(p[2]);
        let x: L = from_fn(|k| v.tile_coord(p[0][k] / pz[k]));
        let y: L = from_fn(|k| v.tile_coord(p[1][k] / pz[k]));
        xlo = from_fn(|k| fmin(xlo[k], x[k]));
        xhi = from_fn(|k| fmax(xhi[k], x[k]));
        ylo = from_fn(|k| fmin(ylo[k], y[k]));
        yhi = from_fn(|k| fmax(yhi[k], y[k]));
    }
    let (tiles, last) = (v.tiles as f32, v.tiles - 1);
    let d = delta;
    let met: [bool; LANES] = from_fn(|k| {
        xhi[k] + d[k] >= 0.0
            && yhi[k] + d[k] >= 0.0
            && xlo[k] - d[k] <= tiles
            && ylo[k] - d[k] <= tiles
    });
    let extent: [L; 4] = [
        from_fn(|k| xlo[k] - d[k]),
        from_fn(|k| xhi[k] + d[k]),
        from_fn(|k| ylo[k] - d[k]),
        from_fn(|k| yhi[k] + d[k]),
    ];
    let i0: [u32; LANES] = from_fn(|k| floor_index(extent[0][k], last));
    let i1: [u32; LANES] = from_fn(|k| floor_index(extent[1][k], last));
    let j0: [u32; LANES] = from_fn(|k| floor_index(extent[2][k], last));
    let j1: [u32; LANES] = from_fn(|k| floor_index(extent[3][k], last));
    // A loop, not `from_fn`: that closure was left out of line.
    for (k, cover) in covers.iter_mut().enumerate() {
        let (i0, i1, j0, j1) = (i0[k], i1[k], j0[k], j1[k]);
        // Two tiles: side by side, or one above the other.
        let two = (i0 + 1 == i1 && j0 == j1) || (i0 == i1 && j0 + 1 == j1);
        *cover = if outside[k] {
            Cover::Nothing
        } else if cut[k] {
            Cover::Clip
        } else if !met[k] {
            Cover::Nothing
        } else if i0 == i1 && j0 == j1 {
            // cover_tiles on a range of one tile: the unclipped extent.
            Cover::One(i0, j0, zlo[k] - v.eps, zhi[k] + v.eps)
        } else if two {
            // The lower tile's index on the axis the range is split along.
            let (x_split, lower) = if i0 != i1 { (true, i0) } else { (false, j0) };
            let [a, b] = two_tiles(v, tv, k, x_split, lower);
            Cover::Two([(i0, j0, a), (i1, j1, b)])
        } else {
            Cover::Range(i0, i1, j0, j1)
        };
    }
    extent
}

/// [`HalfSpace::eval`] at a tile boundary of slope (or offset) `s`, of the
/// point at `a` on the boundary's axis and depth `z`: the lower tile's
/// plane (the axis' Hi) where `lower`, else the upper tile's (its Lo).
///
/// [`HalfSpace::eval`]: dirt_math::clip::HalfSpace::eval
#[inline(always)]
fn boundary_eval(v: &View, lower: bool, s: f32, a: f32, z: f32) -> f32 {
    let eps = v.eps;
    match (lower, v.ortho) {
        (true, true) => s - a + eps,
        (true, false) => s * z - a + eps,
        (false, true) => a - s + eps,
        (false, false) => a - s * z + eps,
    }
}

/// [`Polygon::clip_into`] of the polygon of depths `z` (its first `m`) by
/// the plane valued `f` at its vertices, folded into its depth range as
/// [`Polygon::clipped_depth_range`] folds it (each vertex inside, each
/// crossing edge's intersection, in order), widened by `eps` as
/// [`cover_tiles`] does; `None` where nothing is left.
///
/// [`Polygon::clip_into`]: dirt_math::clip::Polygon::clip_into
/// [`Polygon::clipped_depth_range`]: dirt_math::clip::Polygon::clipped_depth_range
#[inline(always)]
fn clipped_extent<const N: usize>(
    f: &[f32; N],
    z: &[f32; N],
    m: usize,
    eps: f32,
) -> Option<(f32, f32)> {
    let (mut zlo, mut zhi, mut any) = (f32::INFINITY, f32::NEG_INFINITY, false);
    for n in 0..m {
        let next = if n + 1 == m { 0 } else { n + 1 };
        if f[n] >= 0.0 {
            (zlo, zhi, any) = (fmin(zlo, z[n]), fmax(zhi, z[n]), true);
        }
        if (f[n] >= 0.0) != (f[next] >= 0.0) {
            let x = z[n] + (z[next] - z[n]) * (f[n] / (f[n] - f[next]));
            (zlo, zhi, any) = (fmin(zlo, x), fmax(zhi, x), true);
        }
    }
    any.then_some((zlo - eps, zhi + eps))
}

/// [`cover_tiles`] on a range of two tiles for lane `k`: the lower tile
/// (index `lower` on the split axis: x where `x_split`, else y) and the
/// upper, each with the triangle's depth extent there, if it reaches it.
/// Each tile takes one clip ([`tile_depth_extent`] leaves out the planes
/// at the range's outer edges), at the middle boundary, followed here as
/// [`Polygon::clip_into`] makes it: its output vertices in order as slots
/// (`v0, x01, v1, x12, v2, x20`: each vertex where it is inside, each
/// crossing edge's intersection), the depth range folded over them in that
/// order.
///
/// [`Polygon::clip_into`]: dirt_math::clip::Polygon::clip_into
/// [`tile_depth_extent`]: dirt_math::clip::tile_depth_extent
#[inline(always)]
fn two_tiles(
    v: &View,
    tv: &[[L; 3]; 3],
    k: usize,
    x_split: bool,
    lower: u32,
) -> [Option<(f32, f32)>; 2] {
    let eps = v.eps;
    let c = if x_split { 0 } else { 1 };
    let a: [f32; 3] = from_fn(|n| tv[n][c][k]);
    let z: [f32; 3] = from_fn(|n| tv[n][2][k]);
    // The middle boundary.
    let b = v.boundary(lower + 1);
    // The plane of the lower tile (`low`) or of the upper, at the vertices.
    let f = |low: bool| -> [f32; 3] { from_fn(|n| boundary_eval(v, low, b, a[n], z[n])) };
    [
        clipped_extent(&f(true), &z, 3, eps),
        clipped_extent(&f(false), &z, 3, eps),
    ]
}

/// [`cover_tiles`] on a range of two by two tiles, `(i0, i0 + 1, j0,
/// j0 + 1)`, for the view-space triangle `tri`: each tile, column by
/// column, with the triangle's depth extent there, if it reaches it. A
/// column is the triangle clipped at the middle x boundary (its one inner
/// x plane), followed as [`Polygon::clip_into`] makes it but keeping only
/// the y and z of its at most four vertices; a tile's extent is that
/// polygon clipped at the middle y boundary, folded into its depth range
/// as [`Polygon::clipped_depth_range`] folds it. Same operands, same
/// order: `cover_tiles`' bits, without its polygons.
///
/// [`Polygon::clip_into`]: dirt_math::clip::Polygon::clip_into
/// [`Polygon::clipped_depth_range`]: dirt_math::clip::Polygon::clipped_depth_range
fn four_tiles(v: &View, tri: [[f32; 3]; 3], (i0, j0): (u32, u32)) -> [TilePart; 4] {
    let eps = v.eps;
    let (bx, by) = (v.boundary(i0 + 1), v.boundary(j0 + 1));
    // One column (`left`: the lower x tile) and its two tiles. A closure
    // called twice, not a loop over the columns: as a loop the compiler
    // kept it rolled (the bunny's build, ortho r32: 97.7 M -> 99.2 M
    // instructions).
    let column = |i: u32, left: bool| -> [TilePart; 2] {
        let f: [f32; 3] = from_fn(|n| boundary_eval(v, left, bx, tri[n][0], tri[n][2]));
        // The column's vertices (a triangle cut by one plane has at most four).
        let (mut y, mut z, mut m) = ([0.0f32; 4], [0.0f32; 4], 0);
        for n in 0..3 {
            let (p, q) = (tri[n], tri[(n + 1) % 3]);
            let (fp, fq) = (f[n], f[(n + 1) % 3]);
            if fp >= 0.0 {
                (y[m & 3], z[m & 3], m) = (p[1], p[2], m + 1);
            }
            if (fp >= 0.0) != (fq >= 0.0) {
                let w = fp / (fp - fq);
                let (cy, cz) = (p[1] + (q[1] - p[1]) * w, p[2] + (q[2] - p[2]) * w);
                (y[m & 3], z[m & 3], m) = (cy, cz, m + 1);
            }
        }
        let tile = |below: bool| {
            let g: [f32; 4] = from_fn(|n| boundary_eval(v, below, by, y[n], z[n]));
            clipped_extent(&g, &z, m, eps)
        };
        [(i, j0, tile(true)), (i, j0 + 1, tile(false))]
    };
    let ([a, b], [c, d]) = (column(i0, true), column(i0 + 1, false));
    [a, b, c, d]
}

/// The image boxes ([`image_box`]) of a group's triangles into `out` (one
/// per triangle of the group) from their lanes: view-space vertices `tv`
/// and tile extents `extent` in `v`. Out of line: inlined, it left the
/// fragments' callback of [`for_each_fragment_in`] out of line instead.
#[inline(never)]
fn image_boxes(v: &View, tv: &[[L; 3]; 3], extent: &[L; 4], out: &mut [ViewBox]) {
    for (k, b) in out.iter_mut().enumerate() {
        *b = image_box(v, from_fn(|n| tv[n][2][k]), from_fn(|e| extent[e][k]));
    }
}

/// [`for_each_fragment`](crate::fill_depth::for_each_fragment) for every
/// triangle of `tris` in turn: `item(state, tile, zlo, zhi)` for each of a
/// triangle's fragments, in its order, then `end(state)`.
///
/// Returns, for a set with one view with content, whether every triangle
/// was found inside that view's frustum shrunk by its `eps` (`false` may
/// also mean one lies within a few `eps` of a plane); `false` for any
/// other set (not computed).
///
/// With `images` (as long as `tris`) and a set whose one view with content
/// is a perspective view, also writes each triangle's box in that view's
/// image ([`image_box`], what [`apex_boxes`] computes) from the lanes'
/// values, at the cost of the stores: the trace of rays from the view's
/// apex leaves out the listed triangles whose box misses the ray's.
///
/// [`apex_boxes`]: crate::trace_fast::apex_boxes
pub(crate) fn for_each_fragment_in<S>(
    set: &ViewSet,
    tris: &[Triangle],
    state: &mut S,
    mut item: impl FnMut(&mut S, usize, f32, f32),
    mut end: impl FnMut(&mut S),
    mut images: Option<&mut [ViewBox]>,
) -> bool {
    let views: Vec<&View> = set.views.iter().filter(|v| v.has_content).collect();
    if views.len() > MAX_VIEWS {
        for t in tris {
            for_each_fragment(set, t, |tile, lo, hi| item(state, tile, lo, hi));
            end(state);
        }
        return false;
    }
    let one = views.len() == 1;
    if !one || views[0].ortho {
        images = None;
    }
    let mut inside = [one; LANES];
    let mut covers = [[Cover::Nothing; LANES]; MAX_VIEWS];
    let mut tvs = [[[[0.0; LANES]; 3]; 3]; MAX_VIEWS];
    for (g, group) in tris.chunks(LANES).enumerate() {
        // Lanes past the group's triangles repeat its last; they are not used.
        let tri: [[L; 3]; 3] =
            from_fn(|n| from_fn(|c| from_fn(|k| group[k.min(group.len() - 1)].v[n][c])));
        for (f, v) in views.iter().enumerate() {
            let inside = one.then_some(&mut inside);
            let extent = cover_lanes(v, &tri, &mut covers[f], &mut tvs[f], inside);
            if let Some(images) = images.as_deref_mut() {
                image_boxes(v, &tvs[f], &extent, &mut images[g * LANES..][..group.len()]);
            }
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
                    Cover::Two(parts) => {
                        for (i, j, extent) in parts {
                            if let Some((lo, hi)) = extent {
                                emit(i, j, lo, hi);
                            }
                        }
                    }
                    Cover::Range(i0, i1, j0, j1) if i1 == i0 + 1 && j1 == j0 + 1 => {
                        let parts = four_tiles(v, [vertex(0), vertex(1), vertex(2)], (i0, j0));
                        for (i, j, extent) in parts {
                            if let Some((lo, hi)) = extent {
                                emit(i, j, lo, hi);
                            }
                        }
                    }
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
    one && inside.iter().all(|&x| x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_math::clip::view_frustum;
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
        lanes_inside(views, tris).0
    }

    /// [`lanes`], and whether they found every triangle inside the views.
    fn lanes_inside(views: &ViewSet, tris: &[Triangle]) -> (Walk, bool) {
        let (walk, inside, _) = lanes_imaging(views, tris);
        (walk, inside)
    }

    /// [`lanes_inside`], asking for the image boxes too (left
    /// [`ViewBox::WHOLE`] where none are made).
    fn lanes_imaging(views: &ViewSet, tris: &[Triangle]) -> (Walk, bool, Vec<ViewBox>) {
        let mut got = (Walk::new(), 0usize);
        let mut images = vec![ViewBox::WHOLE; tris.len()];
        let inside = for_each_fragment_in(
            views,
            tris,
            &mut got,
            |(w, t), tile, lo, hi| w.push((*t, tile, lo.to_bits(), hi.to_bits())),
            |(_, t)| *t += 1,
            Some(&mut images),
        );
        assert_eq!(got.1, tris.len(), "one end a triangle");
        (got.0, inside, images)
    }

    /// Whether every vertex lies inside every plane of the one view with
    /// content, shrunk by its `eps`.
    fn plain_inside(views: &ViewSet, tris: &[Triangle]) -> bool {
        let [v] = &views
            .views
            .iter()
            .filter(|v| v.has_content)
            .collect::<Vec<_>>()[..]
        else {
            return false;
        };
        tris.iter().all(|t| {
            (0..3).all(|k| {
                let p = v.to_view(t.vertex(k));
                view_frustum(v).iter().all(|h| h.eval(p, -v.eps) >= 0.0)
            })
        })
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
            let (walk, inside, images) = lanes_imaging(&views, &tris);
            prop_assert_eq!(walk, plain(&views, &tris));
            // Image boxes: apex_boxes' bits for a set whose one view with
            // content is a perspective view, none made for other sets.
            let with: Vec<&View> = views.views.iter().filter(|v| v.has_content).collect();
            let want = match &with[..] {
                [v] if !v.ortho => crate::trace_fast::apex_boxes(v, &tris),
                _ => vec![ViewBox::WHOLE; tris.len()],
            };
            prop_assert_eq!(format!("{images:?}"), format!("{want:?}"));
            // Found inside only where it is, and only for a set of one view.
            prop_assert!(!inside || plain_inside(&views, &tris));
            prop_assert!(!inside || views.slots() == 1);
        }

        /// four_tiles is cover_tiles on a two by two range, bit for bit, for
        /// triangles across its middle boundaries (some vertices on them) or
        /// beside them, in orthographic and perspective views.
        #[test]
        fn four_tiles_is_cover_tiles_on_two_by_two(
            corners in prop::array::uniform3((
                prop_oneof![4 => -1.5f32..1.5, 1 => Just(0.0f32)],
                prop_oneof![4 => -1.5f32..1.5, 1 => Just(0.0f32)],
                0.0f32..1.0,
            )),
            kind in 0usize..4,
            tiles in 2u32..40,
            at in (0.0f32..1.0, 0.0f32..1.0),
        ) {
            let views = view_set(kind, tiles, Vec3::ZERO);
            let v = views.views.iter().find(|v| v.tiles > 1).expect("a view");
            let (i0, j0) = ((at.0 * (v.tiles - 1) as f32) as u32, (at.1 * (v.tiles - 1) as f32) as u32);
            let (i0, j0) = (i0.min(v.tiles - 2), j0.min(v.tiles - 2));
            // Tile offsets from the middle boundaries, and a depth between the planes.
            let tri: [[f32; 3]; 3] = corners.map(|(u, w, t)| {
                let z = v.near + t * (v.far - v.near);
                let s = |b: u32, o: f32| (v.boundary(b) + o * v.step) * if v.ortho { 1.0 } else { z };
                [s(i0 + 1, u), s(j0 + 1, w), z]
            });
            let poly = Polygon::triangle(tri[0], tri[1], tri[2]);
            let mut want = Vec::new();
            cover_tiles(v, &poly, (i0, i0 + 1, j0, j0 + 1), |i, j, lo, hi| {
                want.push((i, j, lo.to_bits(), hi.to_bits()));
            });
            let got: Vec<_> = four_tiles(v, tri, (i0, j0))
                .into_iter()
                .filter_map(|(i, j, e)| e.map(|(lo, hi)| (i, j, lo.to_bits(), hi.to_bits())))
                .collect();
            prop_assert_eq!(got, want);
        }

        /// Triangles well inside a single view, or an orthographic one, are
        /// found inside it; one crossing a plane is not.
        #[test]
        fn triangles_well_inside_one_view_are_found_inside(
            tris in prop::collection::vec((v3(), v3(), v3()), 1..30),
            kind in 1usize..3,
            tiles in 1u32..70,
            crossing in any::<bool>(),
        ) {
            // Shrunk to a quarter of the views' bounds, about their centre.
            let mut tris: Vec<Triangle> = tris
                .iter()
                .map(|&(a, b, c)| Triangle::new(a * 0.01, b * 0.01, c * 0.01))
                .collect();
            let views = view_set(kind, tiles, Vec3::ZERO);
            if crossing {
                tris.push(Triangle::new(Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::splat(40.0)));
            }
            let (_, inside) = lanes_inside(&views, &tris);
            prop_assert_eq!(inside, !crossing);
        }
    }

    #[test]
    fn two_tiles_clips_at_the_middle_boundary_only() {
        // A view-space triangle over tiles 7, 8 and 9 of an orthographic
        // view (x from 7.3 to 9.5 tiles), asked as if its range were tiles 7
        // and 8: each part is tile_depth_extent's over that range, and the
        // upper tile is not clipped at its outer edge (x = 9 tiles), so its
        // extent reaches the far vertex's depth.
        let views = view_set(2, 16, Vec3::ZERO);
        let v = &views.views[0];
        let x = |tiles: f32| v.boundary(0) + tiles * v.step;
        let (z0, y) = (0.5 * (v.near + v.far), x(3.5));
        let corner = [
            [x(7.3), y, z0],
            [x(9.5), y, z0 + 0.1],
            [x(8.0), x(3.8), z0 + 0.2],
        ];
        let tv: [[L; 3]; 3] = from_fn(|n| from_fn(|c| [corner[n][c]; LANES]));
        let poly = Polygon::triangle(corner[0], corner[1], corner[2]);
        let extent = |i: u32| dirt_math::clip::tile_depth_extent(v, &poly, (7, 8, 3, 3), i, 3);
        assert_eq!(two_tiles(v, &tv, 0, true, 7), [extent(7), extent(8)]);
        let (_, hi) = extent(8).expect("the triangle reaches tile 8");
        assert_eq!(hi, z0 + 0.2 + v.eps);
    }

    #[test]
    fn every_kind_of_cover_is_taken() {
        // A one-tile, a many-tile, a crossing and an outside triangle (wholly
        // outside the first plane that has a vertex outside), and
        // two across a tile boundary, in one view, so that each arm above is
        // exercised.
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
            // Across the boundary at 0 on one axis, inside one tile on the other.
            t([-0.1, 0.0, 0.05], [0.1, 0.0, 0.05], [0.0, 0.2, 0.1]),
            t([0.05, 0.0, -0.1], [0.05, 0.0, 0.1], [0.1, 0.2, 0.0]),
        ];
        let tri: [[L; 3]; 3] =
            from_fn(|n| from_fn(|c| from_fn(|k| tris[k.min(tris.len() - 1)].v[n][c])));
        let mut covers = [Cover::Nothing; LANES];
        cover_lanes(v, &tri, &mut covers, &mut [[[0.0; LANES]; 3]; 3], None);
        assert!(matches!(covers[0], Cover::One(..)), "{:?}", covers[0]);
        assert!(matches!(covers[1], Cover::Range(..)), "{:?}", covers[1]);
        assert!(matches!(covers[2], Cover::Clip), "{:?}", covers[2]);
        assert!(matches!(covers[3], Cover::Nothing), "{:?}", covers[3]);
        for k in [4, 5] {
            assert!(
                matches!(covers[k], Cover::Two([(_, _, Some(_)), (_, _, Some(_))])),
                "{:?}",
                covers[k]
            );
        }
        assert_eq!(lanes(&views, &tris), plain(&views, &tris));
    }
}
