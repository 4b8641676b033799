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
use crate::blocks::{Budget, Groups};
use crate::cover_lanes::for_each_fragment_in;
use crate::fill_depth::{Fragments, PIECE};
use dirt_core::IdLists;
use dirt_math::bucket::bucket_range;
use dirt_math::encode::ordered_to_f32;
use dirt_math::{Triangle, ViewSet};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Calls `f(list_index)` for every bucket of the depth bounds `depth[tile]`
/// that a triangle's fragment `[lo, hi]` in `tile` overlaps.
#[inline]
fn for_each_bucket(
    depth: &[[u32; 2]],
    buckets: u32,
    (tile, lo, hi): (usize, f32, f32),
    mut f: impl FnMut(usize),
) {
    let [zmin, zmax] = depth[tile];
    if let Some((b0, b1)) =
        bucket_range(lo, hi, ordered_to_f32(zmin), ordered_to_f32(zmax), buckets)
    {
        for b in b0..=b1 {
            f(tile * buckets as usize + b as usize);
        }
    }
}

/// Calls `f(state, t, list_index)` for every (tile, bucket) list that
/// triangle `t` of `tris` belongs to, triangles in order, and `end(state)`
/// after each triangle's lists.
fn for_each_list<S>(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    tris: &[Triangle],
    state: &mut S,
    mut f: impl FnMut(&mut S, usize, usize),
    mut end: impl FnMut(&mut S),
) {
    for_each_fragment_in(
        views,
        tris,
        &mut (state, 0usize),
        |(state, t), tile, lo, hi| {
            for_each_bucket(depth, buckets, (tile, lo, hi), |k| f(state, *t, k))
        },
        |(state, t)| {
            end(state);
            *t += 1;
        },
        None,
    );
}

/// Most list nodes the count pass keeps for the fill (per piece, the lists
/// each triangle joins, in [`for_each_list`]'s order), in all pieces together
/// (a piece past it keeps nothing, and the fill finds its lists again): the
/// kept nodes cost as much memory as the id buffer they become, and past
/// `u32::MAX` nodes the build is an error anyway.
const KEEP_MAX: usize = u32::MAX as usize - 1;

/// Builds the lists from the triangles and the depth bounds of `fill_depth`.
///
/// The coverage of a triangle (clipping it to every tile it touches) is the
/// stage's cost; the count pass keeps the list indices it finds, piece by
/// piece, so the fill writes the ids from them instead of clipping again.
pub fn fill_primitives(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    tris: &[Triangle],
) -> Result<IdLists, CpuError> {
    fill_primitives_from(views, depth, buckets, tris, Fragments::default())
}

/// [`fill_primitives`] from the fragments `fill_depth` kept
/// ([`fill_depth_keeping`](crate::fill_depth::fill_depth_keeping) over the
/// same views and triangles): the count pass clips only the triangles of the
/// pieces it kept nothing for.
pub fn fill_primitives_from(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    tris: &[Triangle],
    fragments: Fragments,
) -> Result<IdLists, CpuError> {
    fill_keeping(
        views,
        depth,
        buckets,
        tris,
        fragments,
        KEEP_MAX,
        dense_from(rayon::current_num_threads()),
    )
}

/// [`fill_primitives_from`] keeping at most `keep_max` nodes from the count
/// pass, counting by ranges the pieces of at least `dense_nodes` nodes a
/// triangle, every piece where it is 0 ([`dense_from`]).
fn fill_keeping(
    views: &ViewSet,
    depth: &[[u32; 2]],
    buckets: u32,
    tris: &[Triangle],
    fragments: Fragments,
    keep_max: usize,
    dense_nodes: usize,
) -> Result<IdLists, CpuError> {
    let n_lists = depth.len() * buckets as usize;
    // Count. The total comes from the prefix sum, not from one counter every
    // thread adds to at every node (its cache line went back and forth).
    // List `k` counts at `at[k + 1]`: the prefix sum turns that into the
    // list's start, the fill's cursor, which the fill moves to the list's
    // end, the next list's start; with `at[0] = 0` the array is then the
    // offsets. One array serves as counts, cursors and offsets.
    let mut at: Vec<AtomicU32> = (0..n_lists + 1).map(|_| AtomicU32::new(0)).collect();
    let counts = &at[1..];
    // List indices are kept as u32; more lists than that keep nothing.
    let keep = u32::try_from(n_lists).is_ok();
    let budget = Budget::new(keep_max);
    let mut frags = fragments.pieces;
    frags.resize_with(tris.len().div_ceil(PIECE), || None);
    // Per piece, its lists if kept, and whether they are left to
    // `count_by_range` (dense pieces) or were counted here.
    let kept: Vec<Option<(Groups<u32>, bool)>> = frags
        .into_par_iter()
        .zip(tris.par_chunks(PIECE))
        // A task a piece, as in fill_depth.
        .with_max_len(1)
        .map(|(frags, piece)| {
            // Per triangle, the lists it joins, from its fragments: kept by
            // fill_depth, or found again. A piece whose fragments already
            // number `dense_nodes` a triangle (any piece, where that is 0) is
            // left to `count_by_range`; the others are counted here, as their
            // lists are found.
            let dense = keep
                && (dense_nodes == 0
                    || frags
                        .as_ref()
                        .is_some_and(|f| f.len() >= dense_nodes * piece.len()));
            let mut lists = Groups::new();
            let add = |lists: &mut Groups<u32>, k: usize| {
                if !dense {
                    counts[k].fetch_add(1, Ordering::Relaxed);
                }
                if keep {
                    lists.push(k as u32);
                }
            };
            match frags {
                Some(frags) => frags.for_each_group(
                    &mut lists,
                    |lists, _, (tile, lo, hi)| {
                        for_each_bucket(depth, buckets, (tile as usize, lo, hi), |k| add(lists, k));
                    },
                    |lists, _| lists.close(),
                ),
                None => for_each_list(
                    views,
                    depth,
                    buckets,
                    piece,
                    &mut lists,
                    |lists, _, k| add(lists, k),
                    |lists| lists.close(),
                ),
            }
            if !keep {
                return None;
            }
            match budget.keep(lists) {
                Ok(lists) => Some((lists, dense)),
                Err(dropped) => {
                    if dense {
                        for &k in dropped.items() {
                            counts[k as usize].fetch_add(1, Ordering::Relaxed);
                        }
                    }
                    None
                }
            }
        })
        .collect();
    count_by_range(&mut at[1..], &kept);
    // Exclusive prefix sum, in 64 bits: more than u32::MAX nodes is an error
    // (the starts written past it are never used), not a wrap.
    let mut acc = 0u64;
    for c in &mut at[1..] {
        let n = *c.get_mut();
        *c.get_mut() = acc as u32;
        acc += u64::from(n);
    }
    let Ok(acc) = u32::try_from(acc) else {
        return Err(CpuError::TooManyNodes { nodes: acc });
    };
    let mut ids: Vec<AtomicU32> = (0..acc).map(|_| AtomicU32::new(u32::MAX)).collect();
    // Every piece's lists kept and, where density decides, most of them
    // dense: each range of lists is filled by one task from all pieces in
    // order, with plain stores, and every list comes out in triangle order.
    // Else the fill's cursors are shared and the lists sorted afterwards.
    let in_order =
        kept.iter().all(Option::is_some) && acc as usize >= dense_nodes.saturating_mul(tris.len());
    if in_order {
        fill_by_range(&mut at[1..], &mut ids, &kept);
    } else {
        let cursors = &at[1..];
        let put = |k: usize, id: usize| {
            let at = cursors[k].fetch_add(1, Ordering::Relaxed);
            ids[at as usize].store(id as u32, Ordering::Relaxed);
        };
        kept.into_par_iter()
            .zip(tris.par_chunks(PIECE))
            .with_max_len(1)
            .enumerate()
            .for_each(|(p, (found, piece))| {
                let first = p * PIECE;
                match found {
                    Some((lists, _)) => lists.for_each_group(
                        &mut (),
                        |_, t, k| put(k as usize, first + t),
                        |_, _| {},
                    ),
                    None => for_each_list(
                        views,
                        depth,
                        buckets,
                        piece,
                        &mut (),
                        |_, t, k| put(k, first + t),
                        |_| {},
                    ),
                }
            });
    }
    let offsets: Vec<u32> = at.into_iter().map(AtomicU32::into_inner).collect();
    debug_assert_eq!(offsets.last(), Some(&acc));
    let mut ids: Vec<u32> = ids.into_iter().map(AtomicU32::into_inner).collect();
    // Every slot was written exactly once (the counts and the fill walk the same pairs).
    debug_assert!(ids.iter().all(|&x| x != u32::MAX));
    if !in_order {
        sort_lists(&offsets, &mut ids);
    }
    Ok(IdLists { offsets, ids })
}

/// List nodes per triangle from which a piece is counted by ranges of lists
/// ([`count_by_range`]), not by atomic adds as its lists are found, in a
/// pool of more than [`RANGE_THREADS`] threads: there every range reads
/// every piece, so the reading grows with the threads while the atomic
/// adds are shared among them.
const DENSE: usize = 8;

/// Pools of up to this many threads count every kept piece by ranges and
/// fill the lists in order ([`fill_by_range`]): a range reads a node in
/// well under a nanosecond, where the atomic count, the atomic fill and
/// the sort it needs cost about 20 ns a node (2 threads: foliage, ortho2
/// r32 B8, fill_primitives 1.24 -> 0.70 ms; the tube's 17.2 -> 14.1 ms;
/// the deforming grid's 3 nodes a triangle 1.10 -> 1.02 ms). Each of `n`
/// threads reads all nodes while the atomic path's work is split `n` ways,
/// so past a few threads the density rule ([`DENSE`]) takes over.
const RANGE_THREADS: usize = 4;

/// The `dense_nodes` of [`fill_keeping`] for a pool of `threads` threads.
fn dense_from(threads: usize) -> usize {
    if threads <= RANGE_THREADS { 0 } else { DENSE }
}

/// Adds the dense kept pieces' list indices to `counts` (list `k` at `counts[k]`),
/// one task per range of lists, each reading every piece and counting only
/// its own lists: plain adds, where one shared array of atomic counters cost
/// a locked add (and often a cache miss it waited for) per node, a quarter
/// of cornell's build at cube r128 B8.
fn count_by_range(counts: &mut [AtomicU32], kept: &[Option<(Groups<u32>, bool)>]) {
    let dense = || {
        kept.iter()
            .flatten()
            .filter(|(_, dense)| *dense)
            .map(|(g, _)| g)
    };
    if dense().next().is_none() {
        return;
    }
    let chunk = counts.len().div_ceil(rayon::current_num_threads()).max(1);
    counts
        .par_chunks_mut(chunk)
        .enumerate()
        .for_each(|(r, counts)| {
            let lists = r * chunk..r * chunk + counts.len();
            for &k in dense().flat_map(Groups::items) {
                let k = k as usize;
                if lists.contains(&k) {
                    *counts[k - lists.start].get_mut() += 1;
                }
            }
        });
}

/// The fill of [`count_by_range`]'s ranges, when every piece was kept:
/// `cursors[k]` is list `k`'s start and ends at its end. The ranges hold
/// about equal numbers of nodes; a range's lists and ids are its own slices,
/// and pieces are read in order, so each list's ids come out ascending.
fn fill_by_range(
    cursors: &mut [AtomicU32],
    ids: &mut [AtomicU32],
    kept: &[Option<(Groups<u32>, bool)>],
) {
    let total = ids.len();
    let per = total.div_ceil(rayon::current_num_threads()).max(1);
    let start = |c: &AtomicU32| c.load(Ordering::Relaxed) as usize;
    // (first list, its cursors, its ids, the first id's index)
    let mut parts: Vec<(usize, &mut [AtomicU32], &mut [AtomicU32], usize)> = Vec::new();
    let (mut cursors, mut ids, mut list, mut at) = (cursors, ids, 0usize, 0usize);
    while !cursors.is_empty() {
        let n = cursors.partition_point(|c| start(c) < at + per).max(1);
        let (mine, rest) = cursors.split_at_mut(n);
        let end = rest.first().map_or(total, start);
        let (my_ids, rest_ids) = ids.split_at_mut(end - at);
        parts.push((list, mine, my_ids, at));
        (cursors, ids, list, at) = (rest, rest_ids, list + n, end);
    }
    parts.into_par_iter().for_each(|(first, cursors, ids, at)| {
        let lists = first..first + cursors.len();
        for (p, piece) in kept.iter().enumerate() {
            let Some((piece, _)) = piece else { continue };
            let base = p * PIECE;
            piece.for_each_group(
                &mut (),
                |_, t, k| {
                    let k = k as usize;
                    if lists.contains(&k) {
                        let c = cursors[k - first].get_mut();
                        *ids[*c as usize - at].get_mut() = (base + t) as u32;
                        *c += 1;
                    }
                },
                |_, _| {},
            );
        }
    });
}

/// Sorts every list (the fill's atomic cursors leave each in an arbitrary
/// order), in parallel over runs of lists of about equal node counts, with no
/// index of the lists (it would cost 16 bytes a list).
fn sort_lists(offsets: &[u32], ids: &mut [u32]) {
    let runs = 4 * rayon::current_num_threads();
    let per_run = ids.len().div_ceil(runs).max(1);
    let mut parts: Vec<(&[u32], &mut [u32])> = Vec::with_capacity(runs + 1);
    let (mut rest, mut lists, mut done) = (ids, offsets, 0usize);
    while lists.len() > 1 {
        // The first list boundary at or past `done + per_run` ends this run.
        let want = (done + per_run).min(u32::MAX as usize) as u32;
        let n = lists
            .partition_point(|&o| o < want)
            .clamp(1, lists.len() - 1);
        let end = lists[n] as usize;
        let (head, tail) = rest.split_at_mut(end - done);
        parts.push((&lists[..=n], head));
        (rest, lists, done) = (tail, &lists[n..], end);
    }
    parts.into_par_iter().for_each(|(lists, ids)| {
        let base = lists[0] as usize;
        for w in lists.windows(2) {
            let (a, b) = (w[0] as usize - base, w[1] as usize - base);
            if b - a > 1 {
                ids[a..b].sort_unstable();
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_core::AdsParams;

    /// The count pass finds again the fragments of pieces `fill_depth` kept
    /// nothing for, and the fill the lists of pieces the count pass kept
    /// nothing for: none kept, some kept, all kept give the same lists.
    #[test]
    fn pieces_kept_or_not_give_the_same_lists() {
        for name in ["cornell", "foliage"] {
            let tris = dirt_scene::builtin(name).expect("built-in").triangles;
            let params = AdsParams {
                resolution: 32,
                ..AdsParams::default()
            };
            let views = dirt_core::views_for(&tris, &params).expect("views");
            let depth = crate::fill_depth::fill_depth(&views, &tris);
            let b = params.buckets;
            let all = fill_primitives(&views, &depth, b, &tris).expect("fill");
            let nodes = all.ids.len();
            // Every list in triangle order, whichever fill made it.
            for w in all.offsets.windows(2) {
                let list = &all.ids[w[0] as usize..w[1] as usize];
                assert!(
                    list.windows(2).all(|p| p[0] < p[1]),
                    "{name}: a list out of order"
                );
            }
            assert!(
                nodes > 0 && tris.len() > 2 * PIECE,
                "{name}: several pieces"
            );
            let (_, every) = crate::fill_depth::fill_depth_keeping(&views, &tris, usize::MAX);
            let frags: usize = every.pieces.iter().flatten().map(|p| p.len()).sum();
            assert!(every.pieces.iter().all(Option::is_some) && frags > 0);
            // Every piece counted by ranges, the dense ones, none.
            for dense_nodes in [0, DENSE, 1 << 20] {
                for keep_frags in [0, frags / 2, frags] {
                    for keep_nodes in [0, nodes / 3, nodes - 1, KEEP_MAX] {
                        let (d, kept) =
                            crate::fill_depth::fill_depth_keeping(&views, &tris, keep_frags);
                        assert_eq!(
                            d, depth,
                            "{name}: the depth bounds do not depend on what is kept"
                        );
                        let some =
                            fill_keeping(&views, &depth, b, &tris, kept, keep_nodes, dense_nodes)
                                .expect("fill");
                        let at = format!(
                            "{name}, fragments {keep_frags}, nodes {keep_nodes}, dense {dense_nodes}"
                        );
                        assert_eq!(some.offsets, all.offsets, "{at}");
                        assert_eq!(some.ids, all.ids, "{at}");
                    }
                }
            }
        }
    }

    /// The runs of the sort split at list boundaries: every list sorted, none
    /// mixed with its neighbours, whatever the run length.
    #[test]
    fn lists_are_sorted_within_their_bounds() {
        let offsets = [0u32, 0, 3, 4, 9, 9, 12];
        let ids = [5u32, 1, 3, 7, 9, 8, 2, 6, 0, 4, 4, 1];
        let mut got = ids;
        sort_lists(&offsets, &mut got);
        assert_eq!(got, [1, 3, 5, 7, 0, 2, 6, 8, 9, 1, 4, 4]);
        let mut empty: [u32; 0] = [];
        sort_lists(&[0], &mut empty);
    }
}
