//! Stage `fill_depth`: per view and tile, the conservative depth bounds
//! `[zmin, zmax]` of every triangle part inside the tile's frustum.
//!
//! Output layout (the GPU pass writes the same bytes): for view `v` and tile
//! `(i, j)`, entry `s·tiles² + j·tiles + i` with `s = v.slot` holds `[enc(zmin), enc(zmax)]` with
//! the order-preserving encoding of `dirt_math::encode`; an empty tile holds
//! `[enc(+inf), enc(-inf)]`. Views without content have no slot, no entries
//! and no pass. Updates are atomic min/max, as on the GPU.
//!
//! The coverage of a triangle (clipping it to every tile it touches) is the
//! build's cost, and `fill_primitives` needs the same fragments again: the
//! build keeps them ([`Fragments`], up to a budget) so that it does not clip
//! every triangle twice.

use crate::blocks::{Budget, Groups};
use crate::cover_lanes::for_each_fragment_in;
use crate::trace_fast::ViewBox;
use dirt_math::clip::for_each_covered_tile;
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF, f32_to_ordered};
use dirt_math::{Triangle, ViewSet};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Triangles per piece: the unit in which the build keeps what one pass
/// found for the next, and of the parallel loops over triangles.
pub(crate) const PIECE: usize = 256;

/// The budget grows by `EARN.0` fragments for every `EARN.1` found. Three
/// for every four kept every piece of foliage's build (ortho r16 B8: its
/// fill_primitives 0.37 -> 0.29 ms, 2 threads) and of 2CylinderEngine's
/// (ortho r128 B8: 5.3 -> 4.3 ms), where one for every two left the last
/// pieces to be clipped again; every build of `peak_memory.rs` stays within
/// 2.5 times its structure (one for every one: the deforming grid's cube r8
/// build 2.68 times).
const EARN: (usize, usize) = (3, 4);

/// Calls `f(tile, zlo, zhi)` for every tile of every view with content that
/// triangle `t` touches (`tile` indexes the depth bounds), with its
/// conservative depth extent there: views in order, then
/// [`for_each_covered_tile`]'s order. The stage's definition; the build runs
/// it eight triangles at a time ([`crate::cover_lanes`], the same fragments).
pub(crate) fn for_each_fragment(views: &ViewSet, t: &Triangle, mut f: impl FnMut(usize, f32, f32)) {
    for v in &views.views {
        if v.has_content {
            let base = v.slot as usize * v.tile_count();
            let tiles = v.tiles as usize;
            let tv = [
                v.to_view(t.vertex(0)),
                v.to_view(t.vertex(1)),
                v.to_view(t.vertex(2)),
            ];
            for_each_covered_tile(v, tv, |i, j, lo, hi| {
                f(base + j as usize * tiles + i as usize, lo, hi);
            });
        }
    }
}

/// The fragments `fill_depth` found, kept for `fill_primitives`: per piece of
/// [`PIECE`] triangles, one group per triangle of `(tile, zlo, zhi)` in
/// [`for_each_fragment`]'s order, or `None` where the budget had run out (the
/// next stage finds those again).
#[derive(Debug, Default)]
pub struct Fragments {
    pub(crate) pieces: Vec<Option<Groups<(u32, f32, f32)>>>,
    /// For a set of one view with content: whether every triangle lies
    /// inside its frustum shrunk by its `eps`, so that the view sees all
    /// of the scene; `false` for other sets.
    pub(crate) inside: bool,
    /// Where asked for ([`fill_depth_imaging`]) and the set's one view with
    /// content is a perspective view: every triangle's box in its image,
    /// found as the triangles were covered. Else empty.
    pub(crate) images: Vec<ViewBox>,
}

/// Depth bounds of every tile of every view, encoded.
pub fn fill_depth(views: &ViewSet, tris: &[Triangle]) -> Vec<[u32; 2]> {
    fill_depth_keeping(views, tris, 0).0
}

/// [`fill_depth`], keeping the fragments of whole pieces while they number at
/// most `keep_max` in all, plus three for every four fragments found by
/// the pieces before ([`EARN`]).
pub fn fill_depth_keeping(
    views: &ViewSet,
    tris: &[Triangle],
    keep_max: usize,
) -> (Vec<[u32; 2]>, Fragments) {
    fill_depth_imaging(views, tris, keep_max, false)
}

/// [`fill_depth_keeping`], with `images` also each triangle's box in the
/// image of a set whose one view with content is a perspective view
/// ([`Fragments::images`]; the trace of rays from its apex reads them).
pub(crate) fn fill_depth_imaging(
    views: &ViewSet,
    tris: &[Triangle],
    keep_max: usize,
    images: bool,
) -> (Vec<[u32; 2]>, Fragments) {
    let imaged = images && {
        let mut with = views.views.iter().filter(|v| v.has_content);
        matches!((with.next(), with.next()), (Some(v), None) if !v.ortho)
    };
    let mut image = if imaged {
        vec![ViewBox::WHOLE; tris.len()]
    } else {
        Vec::new()
    };
    let per_view = views.views.first().map_or(0, |v| v.tile_count());
    let total = views.slots() * per_view;
    let bounds: Vec<[AtomicU32; 2]> = (0..total)
        .map(|_| {
            [
                AtomicU32::new(ORDERED_POS_INF),
                AtomicU32::new(ORDERED_NEG_INF),
            ]
        })
        .collect();
    // Tiles and the groups' ends are kept as u32: the budget never passes
    // `ceiling`, raised or not.
    let ceiling = if u32::try_from(total).is_ok() {
        u32::MAX as usize - 1
    } else {
        0
    };
    let budget = Budget::new(keep_max.min(ceiling));
    // Each piece writes its triangles' image boxes, if any are made.
    let image_pieces: Vec<Option<&mut [ViewBox]>> = if imaged {
        image.chunks_mut(PIECE).map(Some).collect()
    } else {
        (0..tris.len().div_ceil(PIECE)).map(|_| None).collect()
    };
    let (pieces, inside): (Vec<_>, Vec<bool>) = tris
        .par_chunks(PIECE)
        .zip(image_pieces)
        // A task a piece: pieces differ in cost (large triangles cover many
        // tiles), and halves split only as rayon sees fit were left uneven
        // on the two threads (2CylinderEngine's fill_depth 10.6 -> 12.1 ms
        // when the build runs in the pool, as `Ads::build` runs it).
        .with_max_len(1)
        .map(|(piece, images)| {
            // What is left of the budget; a piece that would take more keeps
            // nothing (and frees what it took at once: with each piece in
            // flight bounded by the budget, this stage's peak stays below
            // fill_primitives', whose lists cost at least as much).
            let room = budget.room();
            // Fragments seen, whether the piece still keeps them, and those kept.
            let mut st = (0usize, room > 0, Groups::new());
            let inside = for_each_fragment_in(
                views,
                piece,
                &mut st,
                |(seen, keep, found), tile, lo, hi| {
                    *seen += 1;
                    let e = &bounds[tile];
                    // A locked update only where it changes the bound: most
                    // fragments of a tile after its first do not (x86 has no
                    // atomic min or max, so each is a compare-exchange loop).
                    let (zlo, zhi) = (f32_to_ordered(lo), f32_to_ordered(hi));
                    if zlo < e[0].load(Ordering::Relaxed) {
                        e[0].fetch_min(zlo, Ordering::Relaxed);
                    }
                    if zhi > e[1].load(Ordering::Relaxed) {
                        e[1].fetch_max(zhi, Ordering::Relaxed);
                    }
                    if *keep {
                        if found.len() < room {
                            found.push((tile as u32, lo, hi));
                        } else {
                            *keep = false;
                            *found = Groups::new();
                        }
                    }
                },
                |(_, keep, found)| {
                    if *keep {
                        found.close();
                    }
                },
                images,
            );
            let (seen, keep, found) = st;
            // Every fragment becomes at least one list node of 4 bytes (its
            // depth extent lies in its tile's bounds): the fragments found
            // show that the structure will be larger, and the budget of the
            // pieces after this one grows with them (peak_memory.rs).
            budget.raise(seen * EARN.0 / EARN.1, ceiling);
            (budget.settle(found, keep), inside)
        })
        .unzip();
    let inside = inside.iter().all(|&x| x);
    let depth = bounds
        .into_iter()
        .map(|[a, b]| [a.into_inner(), b.into_inner()])
        .collect();
    (
        depth,
        Fragments {
            pieces,
            inside,
            images: image,
        },
    )
}
