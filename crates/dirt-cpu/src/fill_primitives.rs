//! Stage `fill_primitives`: per view, tile and depth bucket, the list of
//! primitive ids whose part inside the tile overlaps the bucket.
//!
//! Sized exactly by counting (count, exclusive prefix sum, fill): there is no
//! fixed pool, so nothing can be dropped. Lists are stored contiguously
//! (`offsets`, `ids`); list `(v, tile, b)` with flat index
//! `(s·tiles² + j·tiles + i)·B + b` (`s` the view's slot) is `ids[offsets[k]..offsets[k+1]]`.
//! The fill uses atomic cursors, as the GPU does, so the order inside a list is
//! arbitrary; the CPU sorts each list afterwards so its structure is reproducible.

use crate::CpuError;
use dirt_core::IdLists;
use dirt_math::bucket::bucket_range;
use dirt_math::clip::for_each_covered_tile;
use dirt_math::encode::ordered_to_f32;
use dirt_math::{Triangle, ViewSet};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Calls `f(list_index)` for every (tile, bucket) list triangle `t` belongs to.
fn for_each_list(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    t: &Triangle,
    mut f: impl FnMut(usize),
) {
    for v in &views.views {
        let tiles = v.tiles as usize;
        if v.has_content {
            let base = v.slot as usize * v.tile_count();
            let tv = [
                v.to_view(t.vertex(0)),
                v.to_view(t.vertex(1)),
                v.to_view(t.vertex(2)),
            ];
            for_each_covered_tile(v, tv, |i, j, lo, hi| {
                let tile = base + j as usize * tiles + i as usize;
                let [zmin, zmax] = depth[tile];
                if let Some((b0, b1)) =
                    bucket_range(lo, hi, ordered_to_f32(zmin), ordered_to_f32(zmax), buckets)
                {
                    for b in b0..=b1 {
                        f(tile * buckets as usize + b as usize);
                    }
                }
            });
        }
    }
}

/// Builds the lists from the triangles and the depth bounds of `fill_depth`.
pub fn fill_primitives(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    tris: &[Triangle],
) -> Result<IdLists, CpuError> {
    let n_lists = depth.len() * buckets as usize;
    // Count. The total comes from the prefix sum, not from one counter every
    // thread adds to at every node (its cache line went back and forth).
    let counts: Vec<AtomicU32> = (0..n_lists).map(|_| AtomicU32::new(0)).collect();
    tris.par_iter().for_each(|t| {
        for_each_list(views, depth, buckets, t, |k| {
            counts[k].fetch_add(1, Ordering::Relaxed);
        });
    });
    // Exclusive prefix sum, in 64 bits: more than u32::MAX nodes is an error
    // (the offsets written past it are never used), not a wrap.
    let mut offsets = Vec::with_capacity(n_lists + 1);
    let mut acc = 0u64;
    for c in &counts {
        offsets.push(acc as u32);
        acc += u64::from(c.load(Ordering::Relaxed));
    }
    let Ok(acc) = u32::try_from(acc) else {
        return Err(CpuError::TooManyNodes { nodes: acc });
    };
    offsets.push(acc);
    // Fill through atomic cursors: the counters become the cursors (one
    // transient u32 per list, not two).
    let cursors = counts;
    for (c, &o) in cursors.iter().zip(&offsets) {
        c.store(o, Ordering::Relaxed);
    }
    let ids: Vec<AtomicU32> = (0..acc).map(|_| AtomicU32::new(u32::MAX)).collect();
    tris.par_iter().enumerate().for_each(|(id, t)| {
        for_each_list(views, depth, buckets, t, |k| {
            let at = cursors[k].fetch_add(1, Ordering::Relaxed);
            ids[at as usize].store(id as u32, Ordering::Relaxed);
        });
    });
    let mut ids: Vec<u32> = ids.into_iter().map(AtomicU32::into_inner).collect();
    // Every slot was written exactly once (the counts and the fill walk the same pairs).
    debug_assert!(ids.iter().all(|&x| x != u32::MAX));
    // Only lists of two or more ids need sorting (most hold zero or one);
    // collecting just those keeps this index small.
    let mut slices: Vec<&mut [u32]> = Vec::new();
    let mut rest = ids.as_mut_slice();
    for w in offsets.windows(2) {
        let (head, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
        if head.len() > 1 {
            slices.push(head);
        }
        rest = tail;
    }
    slices.par_iter_mut().for_each(|s| s.sort_unstable());
    Ok(IdLists { offsets, ids })
}
