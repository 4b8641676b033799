//! Stage `trace`: closest hits of a ray buffer through the structure.
//!
//! For each ray: the views it crosses are visited starting from the one it
//! enters first, switching to the face across the edge it leaves through
//! (the cube's adjacency table), and falling back to the unvisited view that
//! it enters first. In a view, tiles are walked linearly ([`walk_tiles`]) or
//! hierarchically through the Hi-Z pyramid. In a tile, the buckets its depth
//! span overlaps are visited in the ray's depth order and every primitive in
//! them is tested. Termination only when the entry of the next view, band,
//! cell or bucket lies beyond the best hit found (design brief §2), so the
//! result equals the brute-force closest hit.
//!
//! The loops of this module ([`trace_ray_plain`]) are the stage as `trace.wgsl`
//! mirrors it, line for line. [`trace`], [`trace_into`], [`trace_with_stats`]
//! and [`trace_ray`] run `trace_fast`: the same operations in the
//! same order without the per-ray allocations, counting and repeated
//! clipping, so the same hits and the same statistics, bit for bit
//! (`tests/trace_fast.rs`).

use crate::Ads;
use crate::trace_fast::{self, BoxCache, Scene, Scratch};
use dirt_core::{RAYS_PER_TASK, RayStats, Traversal};
use dirt_math::bucket::{bucket_ceil_depth, bucket_floor_depth, bucket_of};
use dirt_math::clip::{Interval, clip_ray_to_view, ray_depth};
use dirt_math::dda::{HiZCell, Walk, child_order, projected_direction, walk_tiles};
use dirt_math::encode::ordered_to_f32;
use dirt_math::num::{fmax, fmin};
use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::{Hit, Ray, Triangle, View, ViewRay};
use rayon::prelude::*;
use std::cell::Cell;

/// Closest hits of `rays`. Rays that fail [`Ray::validate`] miss.
pub fn trace(ads: &Ads, tris: &[Triangle], rays: &[Ray], traversal: Traversal) -> Vec<Hit> {
    let mut hits = vec![Hit::MISS; rays.len()];
    trace_into(ads, tris, rays, traversal, &mut hits, None);
    hits
}

/// [`trace`] with per-ray statistics.
pub fn trace_with_stats(
    ads: &Ads,
    tris: &[Triangle],
    rays: &[Ray],
    traversal: Traversal,
) -> (Vec<Hit>, Vec<RayStats>) {
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut stats = vec![RayStats::default(); rays.len()];
    trace_into(ads, tris, rays, traversal, &mut hits, Some(&mut stats));
    (hits, stats)
}

/// [`trace`] into caller-owned buffers, with per-ray statistics when `stats`
/// is given. `hits` (and `stats`) must hold one entry per ray; every entry is
/// written (a ray that fails [`Ray::validate`] gets zero statistics).
pub fn trace_into(
    ads: &Ads,
    tris: &[Triangle],
    rays: &[Ray],
    traversal: Traversal,
    hits: &mut [Hit],
    stats: Option<&mut [RayStats]>,
) {
    trace_into_from(ads, tris, rays, traversal, hits, stats, None);
}

/// [`trace_into`], returning the point every ray starts at where they all
/// start at one ([`common_origin`](crate::cost::common_origin)), which it
/// reads for itself: `DirtCpu` watches it, and reading the rays again cost
/// about 95 µs for 100,000 (more than a level-2 cache holds). With `boxes`,
/// the triangle boxes are kept across the traces of one build ([`BoxCache`]).
pub(crate) fn trace_into_from(
    ads: &Ads,
    tris: &[Triangle],
    rays: &[Ray],
    traversal: Traversal,
    hits: &mut [Hit],
    stats: Option<&mut [RayStats]>,
    boxes: Option<&mut BoxCache>,
) -> Option<dirt_math::Vec3> {
    // On a thread of the pool, so that each loop below starts there.
    crate::in_pool(|| {
        // Read once: what pays for the rays and their order both depend on it.
        let origin = crate::cost::common_origin(rays);
        let Some(mut sc) = Scene::new(ads, tris) else {
            // A view set or pyramid larger than the fast path's arrays.
            plain_into(ads, tris, rays, traversal, hits, stats);
            return origin;
        };
        if stats.is_none() {
            sc.prepare_for(rays, origin, boxes);
        }
        // Large batches run in a coherent order (nearby rays share cells, lists
        // and triangles in cache); the results land in input order. Rays that
        // all start at one point keep theirs (`coherent_order`).
        let order = if origin.is_none() {
            trace_fast::coherent_order(rays)
        } else {
            None
        };
        if let Some(order) = order {
            let index = |&i: &u32| i as usize;
            // Gathered first: a loop of loads only overlaps the cache misses of
            // reading rays out of order, which the walk would wait on one by one.
            let sorted: Vec<Ray> = order.par_iter().map(|o| rays[index(o)]).collect();
            match stats {
                Some(stats) => {
                    let out: Vec<(Hit, RayStats)> = sorted
                        .par_iter()
                        .with_max_len(RAYS_PER_TASK)
                        .map_init(Scratch::new, |scratch, r| {
                            trace_fast::trace_ray::<true>(&sc, scratch, r, traversal)
                        })
                        .collect();
                    for (o, (h, s)) in order.iter().zip(out) {
                        hits[index(o)] = h;
                        stats[index(o)] = s;
                    }
                }
                None => {
                    let mut out = vec![Hit::MISS; sorted.len()];
                    trace_chunks(&sc, &sorted, &mut out, traversal);
                    for (o, h) in order.iter().zip(out) {
                        hits[index(o)] = h;
                    }
                }
            }
            return origin;
        }
        match stats {
            Some(stats) => rays
                .par_iter()
                .zip(hits.par_iter_mut())
                .zip(stats.par_iter_mut())
                .with_max_len(RAYS_PER_TASK)
                .for_each_init(Scratch::new, |scratch, ((r, h), s)| {
                    (*h, *s) = trace_fast::trace_ray::<true>(&sc, scratch, r, traversal)
                }),
            None => trace_chunks(&sc, rays, hits, traversal),
        }
        origin
    })
}

/// Rays a parallel item of [`trace_chunks`] takes (looked at from the
/// apex together first, [`Scene::looks_at_apex`]).
const CHUNK: usize = trace_fast::LOOKS;

/// The hits of `rays` into `hits` (as long), without statistics. The
/// parallel items are chunks of [`CHUNK`] rays, each traced in a plain loop:
/// an item a ray cost a call through the loop's closure for each.
fn trace_chunks(sc: &Scene<'_>, rays: &[Ray], hits: &mut [Hit], traversal: Traversal) {
    rays.par_chunks(CHUNK)
        .zip(hits.par_chunks_mut(CHUNK))
        .with_max_len(RAYS_PER_TASK / CHUNK)
        .for_each_init(Scratch::new, |scratch, (rays, hits)| {
            let mut looks = [None; trace_fast::LOOKS];
            sc.looks_at_apex(rays, &mut looks);
            for ((r, h), look) in rays.iter().zip(hits).zip(looks) {
                *h = match look {
                    // A miss whether the ray is valid or not.
                    Some(None) => Hit::MISS,
                    _ if r.validate().is_err() => Hit::MISS,
                    _ => trace_fast::trace_looked::<false>(sc, scratch, r, traversal, look).0,
                };
            }
        });
}

fn plain_into(
    ads: &Ads,
    tris: &[Triangle],
    rays: &[Ray],
    traversal: Traversal,
    hits: &mut [Hit],
    stats: Option<&mut [RayStats]>,
) {
    match stats {
        Some(stats) => rays
            .par_iter()
            .zip(hits.par_iter_mut())
            .zip(stats.par_iter_mut())
            .for_each(|((r, h), s)| {
                *s = RayStats::default();
                *h = trace_ray_plain(ads, tris, r, traversal, s)
            }),
        None => rays.par_iter().zip(hits.par_iter_mut()).for_each(|(r, h)| {
            *h = trace_ray_plain(ads, tris, r, traversal, &mut RayStats::default())
        }),
    }
}

/// One ray; `stats` is overwritten with its statistics (zero for a ray that
/// fails [`Ray::validate`]). For many rays, [`trace_into`] gathers what the
/// rays share once.
pub fn trace_ray(
    ads: &Ads,
    tris: &[Triangle],
    ray: &Ray,
    traversal: Traversal,
    stats: &mut RayStats,
) -> Hit {
    match Scene::new(ads, tris) {
        Some(sc) => {
            let (h, s) = trace_fast::trace_ray::<true>(&sc, &mut Scratch::new(), ray, traversal);
            *stats = s;
            h
        }
        None => {
            *stats = RayStats::default();
            trace_ray_plain(ads, tris, ray, traversal, stats)
        }
    }
}

struct Ctx<'a> {
    ads: &'a Ads,
    tris: &'a [Triangle],
    ray: &'a Ray,
    sh: RayShear,
    best: Cell<Hit>,
    stats: Cell<RayStats>,
}

/// One ray through the plain stage: the loops `trace.wgsl` mirrors, and the
/// reference [`trace_ray`] is tested against. `stats` is overwritten with the
/// ray's statistics, except for a ray that fails [`Ray::validate`].
pub fn trace_ray_plain(
    ads: &Ads,
    tris: &[Triangle],
    ray: &Ray,
    traversal: Traversal,
    stats: &mut RayStats,
) -> Hit {
    if ray.validate().is_err() {
        return Hit::MISS;
    }
    let ctx = Ctx {
        ads,
        tris,
        ray,
        sh: RayShear::new(ray),
        best: Cell::new(Hit::MISS),
        stats: Cell::new(RayStats::default()),
    };
    let views = &ads.views.views;
    let n = views.len();
    let mut vrs = Vec::with_capacity(n);
    let mut ivs = Vec::with_capacity(n);
    let mut exits = Vec::with_capacity(n);
    for v in views {
        let vr = v.ray(ray);
        let (iv, exit) = if v.has_content {
            clip_ray_to_view(v, &vr, ray.tmin, ray.tmax)
        } else {
            (Interval::EMPTY, None)
        };
        vrs.push(vr);
        ivs.push(iv);
        exits.push(exit);
    }
    let mut visited = 0u32;
    let mut current = next_view(&ivs, visited, None);
    while let Some(f) = current {
        visited |= 1 << f;
        if ivs[f].t0 <= ctx.best.get().t {
            let mut s = ctx.stats.get();
            s.views += 1;
            ctx.stats.set(s);
            match traversal {
                Traversal::Linear => linear(&ctx, &views[f], &vrs[f], ivs[f]),
                Traversal::HiZ => hiz(&ctx, &views[f], &vrs[f], ivs[f]),
            }
        }
        let across = exits[f].and_then(|e| ads.views.adjacency.get(f).map(|a| a[e] as usize));
        current = next_view(&ivs, visited, across);
    }
    *stats = ctx.stats.get();
    ctx.best.get()
}

/// The view a ray walks next, given its interval in every view (`ivs`) and
/// the views it has walked (`visited`, a bit a view): the view `across` the
/// edge it left the last one through, if it has not walked it and enters
/// it; else the unvisited view it enters first (the first such on ties).
/// The first view is `next_view(ivs, 0, None)`.
pub(crate) fn next_view(ivs: &[Interval], visited: u32, across: Option<usize>) -> Option<usize> {
    let unvisited = |f: usize| visited & (1 << f) == 0 && !ivs[f].is_empty();
    match across {
        Some(g) if unvisited(g) => Some(g),
        _ => {
            let mut best: Option<usize> = None;
            for f in 0..ivs.len() {
                if unvisited(f) && best.is_none_or(|b| ivs[f].t0 < ivs[b].t0) {
                    best = Some(f);
                }
            }
            best
        }
    }
}

fn linear(ctx: &Ctx<'_>, v: &View, vr: &ViewRay, iv: Interval) {
    walk_tiles(v, vr, iv, &mut || ctx.best.get().t, &mut |span| {
        visit_tile(ctx, v, vr, span.i, span.j, span.iv);
        Walk::Continue
    });
}

fn hiz(ctx: &Ctx<'_>, v: &View, vr: &ViewRay, iv: Interval) {
    let levels = ctx.ads.hiz.len() as u32;
    let (dx, dy) = projected_direction(v, vr, &iv);
    let order = child_order(dx, dy);
    // Depth-first, front to back: at most 3 siblings wait per level.
    let mut stack: Vec<HiZCell> = Vec::with_capacity(3 * levels as usize + 1);
    stack.push(HiZCell {
        level: levels - 1,
        i: 0,
        j: 0,
    });
    while let Some(cell) = stack.pop() {
        let civ = cell.clip(v, vr, iv);
        if civ.is_empty() || civ.t0 > ctx.best.get().t {
            continue;
        }
        let w = ctx.ads.hiz_width(cell.level);
        let [zmin, zmax] = ctx.ads.hiz[cell.level as usize]
            [v.slot as usize * w * w + cell.j as usize * w + cell.i as usize];
        let (zmin, zmax) = (ordered_to_f32(zmin), ordered_to_f32(zmax));
        let (lo, hi) = depth_span(vr, civ);
        if !(hi >= zmin && lo <= zmax) {
            continue;
        }
        if cell.level == 0 {
            visit_tile(ctx, v, vr, cell.i, cell.j, civ);
            continue;
        }
        let cw = ctx.ads.hiz_width(cell.level - 1) as u32;
        for &(di, dj) in order.iter().rev() {
            let (i, j) = (2 * cell.i + di, 2 * cell.j + dj);
            if i < cw && j < cw {
                stack.push(HiZCell {
                    level: cell.level - 1,
                    i,
                    j,
                });
            }
        }
    }
}

/// The ray's depth span over an interval, rounded outward by its `eps`.
#[inline]
fn depth_span(vr: &ViewRay, iv: Interval) -> (f32, f32) {
    let za = ray_depth(vr, iv.t0);
    let zb = ray_depth(vr, iv.t1);
    (fmin(za, zb) - vr.eps, fmax(za, zb) + vr.eps)
}

fn visit_tile(ctx: &Ctx<'_>, v: &View, vr: &ViewRay, i: u32, j: u32, iv: Interval) {
    let mut st = ctx.stats.get();
    st.tiles += 1;
    let tile = v.slot as usize * v.tile_count() + (j * v.tiles + i) as usize;
    let [zmin, zmax] = ctx.ads.depth()[tile];
    let (zmin, zmax) = (ordered_to_f32(zmin), ordered_to_f32(zmax));
    let (lo, hi) = depth_span(vr, iv);
    if !(hi >= zmin && lo <= zmax) {
        ctx.stats.set(st);
        return;
    }
    let nb = ctx.ads.params.buckets;
    let b0 = bucket_of(lo, zmin, zmax, nb);
    let b1 = bucket_of(hi, zmin, zmax, nb);
    let ascending = vr.d[2] >= 0.0;
    for n in 0..=(b1 - b0) {
        let k = if ascending { b0 + n } else { b1 - n };
        let best = ctx.best.get();
        if best.is_hit() {
            // Depth of the best hit on this ray; no point of a later bucket can be closer.
            let zb = ray_depth(vr, best.t);
            if ascending && bucket_floor_depth(k, zmin, zmax, nb) > zb + vr.eps {
                break;
            }
            if !ascending && bucket_ceil_depth(k, zmin, zmax, nb) < zb - vr.eps {
                break;
            }
        }
        st.buckets += 1;
        let list = ctx.ads.lists.list(tile * nb as usize + k as usize);
        let mut best = ctx.best.get();
        for &id in list {
            st.tests += 1;
            intersect_closest(ctx.ray, &ctx.sh, &ctx.tris[id as usize], id, &mut best);
        }
        ctx.best.set(best);
    }
    ctx.stats.set(st);
}
