//! Stage `fill_depth`: per view and tile, the conservative depth bounds
//! `[zmin, zmax]` of every triangle part inside the tile's frustum.
//!
//! Output layout (the GPU pass writes the same bytes): for view `v` and tile
//! `(i, j)`, entry `s·tiles² + j·tiles + i` with `s = v.slot` holds `[enc(zmin), enc(zmax)]` with
//! the order-preserving encoding of `dirt_math::encode`; an empty tile holds
//! `[enc(+inf), enc(-inf)]`. Views without content have no slot, no entries
//! and no pass. Updates are atomic min/max, as on the GPU.

use dirt_math::clip::for_each_covered_tile;
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF, f32_to_ordered};
use dirt_math::{Triangle, ViewSet};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Depth bounds of every tile of every view, encoded.
pub fn fill_depth(views: &ViewSet, tris: &[Triangle]) -> Vec<[u32; 2]> {
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
    for v in &views.views {
        if v.has_content {
            let base = v.slot as usize * per_view;
            let tiles = v.tiles as usize;
            tris.par_iter().for_each(|t| {
                let tv = [
                    v.to_view(t.vertex(0)),
                    v.to_view(t.vertex(1)),
                    v.to_view(t.vertex(2)),
                ];
                for_each_covered_tile(v, tv, |i, j, lo, hi| {
                    let e = &bounds[base + j as usize * tiles + i as usize];
                    e[0].fetch_min(f32_to_ordered(lo), Ordering::Relaxed);
                    e[1].fetch_max(f32_to_ordered(hi), Ordering::Relaxed);
                });
            });
        }
    }
    bounds
        .into_iter()
        .map(|[a, b]| [a.into_inner(), b.into_inner()])
        .collect()
}
