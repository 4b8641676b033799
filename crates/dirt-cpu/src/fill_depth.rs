//! Stage `fill_depth`: per view and tile, the conservative depth bounds
//! `[zmin, zmax]` of every triangle part inside the tile's frustum.
//!
//! Output layout (the GPU pass writes the same bytes): for view `v` and tile
//! `(i, j)`, entry `v·tiles² + j·tiles + i` holds `[enc(zmin), enc(zmax)]` with
//! the order-preserving encoding of `dirt_math::encode`; an empty tile holds
//! `[enc(+inf), enc(-inf)]`. Updates are atomic min/max, as on the GPU.

use dirt_math::clip::for_each_covered_tile;
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF, f32_to_ordered};
use dirt_math::{Triangle, ViewSet};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Depth bounds of every tile of every view, encoded.
pub fn fill_depth(views: &ViewSet, tris: &[Triangle]) -> Vec<[u32; 2]> {
    let per_view: Vec<usize> = views.views.iter().map(|v| v.tile_count()).collect();
    let total: usize = per_view.iter().sum();
    let bounds: Vec<[AtomicU32; 2]> = (0..total)
        .map(|_| {
            [
                AtomicU32::new(ORDERED_POS_INF),
                AtomicU32::new(ORDERED_NEG_INF),
            ]
        })
        .collect();
    let mut base = 0;
    for (v, &count) in views.views.iter().zip(&per_view) {
        if v.has_content {
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
        base += count;
    }
    bounds
        .into_iter()
        .map(|[a, b]| [a.into_inner(), b.into_inner()])
        .collect()
}
