// Stage `trace`: closest hits of a ray buffer. Mirrors dirt_cpu::trace and
// dirt_math::dda::walk_tiles; read them side by side. Two differences of
// form, none of result:
// - the Hi-Z walk is stackless: it visits the same cells in the same order
//   as the CPU's stack (depth first, children in `child_order`), keeping
//   only the current cell, so that a ray's whole traversal state is small;
// - every loop of the walk counts against the ray's work budget for the
//   dispatch (`step`). A ray that spends it saves where each loop stood and
//   is listed as unfinished; `trace_continue` resumes it exactly there in
//   the next dispatch, until every ray is done (`schedule` sizes each
//   dispatch from the list). Hits and statistics are those of one
//   uninterrupted walk.
#import types
#import num
#import divide
#import encode
#import view
#import clip
#import bucket
#import dda
#import triangle
#import work
#import ids
#import hiz
#import offsets
#import tris

// dirt_gpu::TraceParams
struct TraceParams {
    n_rays: u32,
    n_views: u32,
    tiles: u32,
    buckets: u32,
    levels: u32,
    traversal: u32, // 0 = linear, 1 = Hi-Z
    n_slots: u32, // views with content: blocks per Hi-Z level
    budget: u32, // loop iterations per ray per dispatch (dirt_gpu::trace::WORK_BUDGET at most)
    capacity: u32, // rays the pool has room for
    with_stats: u32, // 1: write per-ray statistics
    id_shift: u32, // list ids per chunk: 2^id_shift (ids.wgsl)
    id_capacity: u32, // list ids the chunks hold
    tri_shift: u32, // triangles per chunk: 2^tri_shift (tris.wgsl)
    hiz_shift: u32, // Hi-Z cells per chunk: 2^hiz_shift (hiz.wgsl)
    offset_shift: u32, // list offsets per chunk: 2^offset_shift (offsets.wgsl)
    counted: u32, // 1: the first dispatch traces the rays below pool.head.count_in
}

// dirt_gpu::PoolHeader
struct PoolHeader {
    // Unfinished rays listed for the next `trace_continue`.
    count_in: u32,
    // Unfinished rays listed by the dispatch running now.
    count_out: atomic<u32>,
    // Which to-do list `trace_continue` reads (the other is written).
    parity: u32,
    // Continuation dispatches that had rays to continue.
    rounds: u32,
}

// Two to-do lists of `capacity` ray indices, then STATE_WORDS per ray.
struct Pool {
    head: PoolHeader,
    data: array<u32>,
}

@group(0) @binding(0) var<storage, read> rays: array<Ray>;
@group(0) @binding(1) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(3) var<uniform> views: array<View, 6>;
@group(0) @binding(4) var<uniform> params: TraceParams;
@group(0) @binding(8) var<storage, read_write> stats: array<RayStats>;
@group(0) @binding(9) var<storage, read_write> pool: Pool;
@group(0) @binding(10) var<storage, read_write> dispatch: array<u32>;

const NONE: u32 = 0xffffffffu;
// dirt_gpu::trace::STATE_WORDS
const STATE_WORDS: u32 = 16u;

var<private> g_ray: Ray;
var<private> g_sh: RayShear;
var<private> g_best: Hit;
var<private> g_stats: RayStats;
// Start of each Hi-Z level in `hiz` (in tiles; two u32 per tile).
var<private> g_level_base: array<u32, 16>;
// Cells per side of each Hi-Z level.
var<private> g_level_width: array<u32, 16>;

// Where the walk stands. Slots: 0 the views, then for the linear walk 1 the
// major and 2 the minor tile index, for the Hi-Z walk 1 the cell; 3 the
// buckets and 4 the list entries of a tile.
var<private> g_idx: array<u32, 5>;
// Views visited (bits).
var<private> g_visited: u32;
// The Hi-Z walk's current cell (packed) and whether it is being left.
var<private> g_cell: u32;
var<private> g_leaving: bool;
// The slot whose loop ran out of budget; NONE while the walk runs.
var<private> g_fail: u32;
// The slot a resumed walk stopped at; NONE once it is reached again.
var<private> g_resume: u32;
// Whether this dispatch has run one iteration past the resume point: every
// dispatch does, so every ray finishes.
var<private> g_progress: bool;

// One iteration of slot `slot`'s loop, its index `index`; false (and the
// walk saved) once the budget is spent.
fn step(slot: u32, index: u32) -> bool {
    if g_fail != NONE {
        return false;
    }
    g_work += 1u;
    g_idx[slot] = index;
    if g_resume == NONE {
        if g_progress & (g_work > params.budget) {
            g_fail = slot;
            return false;
        }
        g_progress = true;
    }
    return true;
}

// Resuming: whether slot's loop continues at its saved index...
fn resumes(slot: u32) -> bool {
    return (g_resume != NONE) & (g_resume >= slot);
}
// ...inside an iteration already begun (inner loops were running).
fn resumes_inside(slot: u32) -> bool {
    return (g_resume != NONE) & (g_resume > slot);
}
// The loop of the slot the walk stopped at begins its saved iteration afresh.
fn resumed(slot: u32) {
    if g_resume == slot {
        g_resume = NONE;
    }
}

fn tri_vertex(prim: u32, k: u32) -> vec3<f32> {
    return tri_load(prim, k, params.tri_shift);
}

fn intersect_closest(prim: u32) {
    let h = intersect(g_ray, g_sh, tri_vertex(prim, 0u), tri_vertex(prim, 1u), tri_vertex(prim, 2u));
    if h.hit {
        let cand = Hit(prim, h.t, h.u, h.v);
        if hit_closer_than(cand, g_best) {
            g_best = cand;
        }
    }
}

// The ray's depth span over an interval, rounded outward by its eps.
fn depth_span(vr: ViewRay, iv: Interval) -> vec2<f32> {
    let za = ray_depth(vr, iv.t0);
    let zb = ray_depth(vr, iv.t1);
    return vec2<f32>(fmin(za, zb) - vr.eps, fmax(za, zb) + vr.eps);
}

fn visit_tile(v: View, vr: ViewRay, i: u32, j: u32, iv: Interval) {
    // Resumed inside this tile: it was counted and passed the depth test.
    if !resumes_inside(2u) {
        g_stats.tiles += 1u;
    }
    let tile = v.slot * tile_count(v) + (j * v.tiles + i);
    let z = hiz_cell(tile, params.hiz_shift);
    let zmin = ordered_to_f32(z.x);
    let zmax = ordered_to_f32(z.y);
    let span = depth_span(vr, iv);
    let lo = span.x;
    let hi = span.y;
    if !((hi >= zmin) & (lo <= zmax)) {
        return;
    }
    let nb = params.buckets;
    let b0 = bucket_of(lo, zmin, zmax, nb);
    let b1 = bucket_of(hi, zmin, zmax, nb);
    let ascending = vr.d[2] >= 0.0;
    var n = 0u;
    if resumes(3u) {
        n = g_idx[3];
    }
    var inside = resumes_inside(3u);
    resumed(3u);
    for (; n <= b1 - b0 && step(3u, n); n++) {
        let k = select(b1 - n, b0 + n, ascending);
        if !inside {
            if hit_is_hit(g_best) {
                let zb = ray_depth(vr, g_best.t);
                // Nested, not `&&`: only the edge the walk needs is computed.
                if ascending {
                    if bucket_floor_depth(k, zmin, zmax, nb) > zb + vr.eps {
                        break;
                    }
                } else if bucket_ceil_depth(k, zmin, zmax, nb) < zb - vr.eps {
                    break;
                }
            }
            g_stats.buckets += 1u;
        }
        let list = tile * nb + k;
        var at = offset_load(list, params.offset_shift);
        let end = offset_load(list + 1u, params.offset_shift);
        if inside {
            at = g_idx[4];
            resumed(4u);
        }
        inside = false;
        for (; at < end && step(4u, at); at++) {
            g_stats.tests += 1u;
            intersect_closest(id_load(at, params.id_shift));
        }
    }
}

// dirt_math::dda::walk_tiles with the visitor of dirt_cpu::trace::linear.
fn linear(v: View, vr: ViewRay, iv: Interval) {
    if is_empty(iv) | (v.tiles == 0u) {
        return;
    }
    let a = tile_xy(v, vr, iv.t0);
    let b = tile_xy(v, vr, iv.t1);
    let delta = dilation(v, vr, iv);
    let major = select(1u, 0u, abs(b[0] - a[0]) >= abs(b[1] - a[1]));
    let minor = 1u - major;
    let kr = index_range(a[major], b[major], delta, v.tiles);
    if !kr.ok {
        return;
    }
    let forward = b[major] >= a[major];
    let minor_forward = b[minor] >= a[minor];
    // Structured without `continue` and with a single exit: lavapipe
    // mis-ran later loops of the kernel after `continue` in these loops.
    var n = 0u;
    if resumes(1u) {
        n = g_idx[1];
    }
    // Resumed inside this band: it passed the closest-hit test already.
    var inside = resumes_inside(1u);
    resumed(1u);
    var walking = true;
    while walking && n <= kr.hi - kr.lo && step(1u, n) {
        let k = select(kr.hi - n, kr.lo + n, forward);
        var band = iv;
        clip_interval(&band, view_lo(v, major, boundary(v, k)), vr);
        clip_interval(&band, view_hi(v, major, boundary(v, k + 1u)), vr);
        if !is_empty(band) {
            if !inside & (band.t0 > g_best.t) {
                walking = false;
            } else {
                let p = tile_xy(v, vr, band.t0);
                let q = tile_xy(v, vr, band.t1);
                let mr = index_range(p[minor], q[minor], delta, v.tiles);
                if mr.ok {
                    var e = 0u;
                    if resumes(2u) {
                        e = g_idx[2];
                    }
                    resumed(2u);
                    for (; e <= mr.hi - mr.lo && step(2u, e); e++) {
                        let m = select(mr.hi - e, mr.lo + e, minor_forward);
                        var span = band;
                        clip_interval(&span, view_lo(v, minor, boundary(v, m)), vr);
                        clip_interval(&span, view_hi(v, minor, boundary(v, m + 1u)), vr);
                        if !is_empty(span) {
                            let i = select(m, k, major == 0u);
                            let j = select(k, m, major == 0u);
                            visit_tile(v, vr, i, j, span);
                        }
                    }
                }
            }
        }
        inside = false;
        n += 1u;
    }
}

fn pack_cell(c: vec3<u32>) -> u32 {
    return (c.x << 28u) | (c.z << 14u) | c.y;
}

fn unpack_cell(p: u32) -> vec3<u32> {
    return vec3<u32>(p >> 28u, p & 0x3fffu, (p >> 14u) & 0x3fffu);
}

fn cell_exists(c: vec3<u32>) -> bool {
    let w = g_level_width[c.x];
    return (c.y < w) & (c.z < w);
}

// Child k (in child_order) of `c`'s parent: one of c's siblings or c.
fn sibling(dir: vec2<f32>, c: vec3<u32>, k: u32) -> vec3<u32> {
    let o = child_order(dir.x, dir.y, k);
    return vec3<u32>(c.x, (c.y & ~1u) + o.x, (c.z & ~1u) + o.y);
}

// The first child of `c` that exists; the one at (2i, 2j) always does.
fn first_child(dir: vec2<f32>, c: vec3<u32>) -> vec3<u32> {
    let corner = vec3<u32>(c.x - 1u, 2u * c.y, 2u * c.z);
    // Unrolled, like every short loop here that need not count.
    let s0 = sibling(dir, corner, 0u);
    if cell_exists(s0) {
        return s0;
    }
    let s1 = sibling(dir, corner, 1u);
    if cell_exists(s1) {
        return s1;
    }
    let s2 = sibling(dir, corner, 2u);
    if cell_exists(s2) {
        return s2;
    }
    return sibling(dir, corner, 3u);
}

// The next sibling of `c` in child_order that exists; `c` itself when none.
fn next_sibling(dir: vec2<f32>, c: vec3<u32>) -> vec3<u32> {
    let me = vec2<u32>(c.y & 1u, c.z & 1u);
    var rank = 3u;
    if all(child_order(dir.x, dir.y, 0u) == me) {
        rank = 0u;
    } else if all(child_order(dir.x, dir.y, 1u) == me) {
        rank = 1u;
    } else if all(child_order(dir.x, dir.y, 2u) == me) {
        rank = 2u;
    }
    if rank < 1u {
        let s = sibling(dir, c, 1u);
        if cell_exists(s) {
            return s;
        }
    }
    if rank < 2u {
        let s = sibling(dir, c, 2u);
        if cell_exists(s) {
            return s;
        }
    }
    if rank < 3u {
        let s = sibling(dir, c, 3u);
        if cell_exists(s) {
            return s;
        }
    }
    return c;
}

// dirt_cpu::trace::hiz, without the stack: each iteration either arrives at
// a cell (tests it; descends to its first child, visits its tile, or turns
// to leave it) or leaves one (to its next sibling, else up to its parent).
fn hiz_walk(v: View, vr: ViewRay, iv: Interval) {
    let levels = params.levels;
    let root = levels - 1u;
    let dir = projected_direction(v, vr, iv);
    var cell = vec3<u32>(root, 0u, 0u);
    var inside = false;
    if resumes(1u) {
        cell = unpack_cell(g_cell);
        inside = resumes_inside(1u);
    } else {
        g_leaving = false;
    }
    resumed(1u);
    var walking = true;
    while walking {
        if g_fail == NONE {
            g_cell = pack_cell(cell);
        }
        if !step(1u, 0u) {
            break;
        }
        if g_leaving {
            if cell.x == root {
                walking = false;
            } else {
                let next = next_sibling(dir, cell);
                if all(next == cell) {
                    cell = vec3<u32>(cell.x + 1u, cell.y / 2u, cell.z / 2u);
                } else {
                    cell = next;
                    g_leaving = false;
                }
            }
        } else {
            let level = cell.x;
            let civ = hiz_cell_clip(v, vr, iv, level, cell.y, cell.z);
            var enter = inside;
            if !inside & !(is_empty(civ) | (civ.t0 > g_best.t)) {
                let w = g_level_width[level];
                let at = g_level_base[level] + v.slot * w * w + cell.z * w + cell.y;
                let z = hiz_cell(at, params.hiz_shift);
                let zmin = ordered_to_f32(z.x);
                let zmax = ordered_to_f32(z.y);
                let span = depth_span(vr, civ);
                enter = (span.y >= zmin) & (span.x <= zmax);
            }
            inside = false;
            if enter & (level > 0u) {
                cell = first_child(dir, cell);
            } else {
                if enter {
                    visit_tile(v, vr, cell.y, cell.z, civ);
                    if g_fail != NONE {
                        break;
                    }
                }
                g_leaving = true;
            }
        }
    }
}

fn state_base(r: u32) -> u32 {
    return 2u * params.capacity + r * STATE_WORDS;
}

fn save_state(r: u32) {
    let b = state_base(r);
    pool.data[b] = g_best.prim;
    pool.data[b + 1u] = bitcast<u32>(g_best.t);
    pool.data[b + 2u] = bitcast<u32>(g_best.u);
    pool.data[b + 3u] = bitcast<u32>(g_best.v);
    pool.data[b + 4u] = g_stats.views;
    pool.data[b + 5u] = g_stats.tiles;
    pool.data[b + 6u] = g_stats.buckets;
    pool.data[b + 7u] = g_stats.tests;
    pool.data[b + 8u] = g_visited | (g_idx[0] << 8u) | (g_fail << 16u) | (select(0u, 1u, g_leaving) << 24u);
    pool.data[b + 9u] = g_idx[1];
    pool.data[b + 10u] = g_idx[2];
    pool.data[b + 11u] = g_idx[3];
    pool.data[b + 12u] = g_idx[4];
    pool.data[b + 13u] = g_cell;
}

fn load_state(r: u32) {
    let b = state_base(r);
    g_best = Hit(pool.data[b], bitcast<f32>(pool.data[b + 1u]), bitcast<f32>(pool.data[b + 2u]), bitcast<f32>(pool.data[b + 3u]));
    g_stats = RayStats(pool.data[b + 4u], pool.data[b + 5u], pool.data[b + 6u], pool.data[b + 7u]);
    let w = pool.data[b + 8u];
    g_visited = w & 0xffu;
    g_idx[0] = (w >> 8u) & 0xffu;
    g_resume = (w >> 16u) & 0xffu;
    g_leaving = ((w >> 24u) & 1u) == 1u;
    g_idx[1] = pool.data[b + 9u];
    g_idx[2] = pool.data[b + 10u];
    g_idx[3] = pool.data[b + 11u];
    g_idx[4] = pool.data[b + 12u];
    g_cell = pool.data[b + 13u];
}

fn finish(r: u32) {
    hits[r] = g_best;
    if params.with_stats == 1u {
        stats[r] = g_stats;
    }
}

// Whether a ray passes dirt_math::Ray::validate (those that fail miss).
fn ray_is_valid(ray: Ray) -> bool {
    let o = ray.origin;
    let d = ray.dir;
    let finite_o = (abs(o[0]) <= F32_MAX) & (abs(o[1]) <= F32_MAX) & (abs(o[2]) <= F32_MAX);
    let finite_d = (abs(d[0]) <= F32_MAX) & (abs(d[1]) <= F32_MAX) & (abs(d[2]) <= F32_MAX);
    let nonzero = !((d[0] == 0.0) & (d[1] == 0.0) & (d[2] == 0.0));
    let range_ok = (ray.tmin >= 0.0) & (abs(ray.tmin) <= F32_MAX) & !(ray.tmax < ray.tmin) & (ray.tmax == ray.tmax);
    return finite_o & finite_d & nonzero & range_ok;
}

// Traces ray `r` from the start or, `resuming`, from its saved state.
fn trace_ray(r: u32, resuming: bool) {
    g_ray = rays[r];
    g_work = 0u;
    g_fail = NONE;
    g_resume = NONE;
    g_progress = false;
    if resuming {
        load_state(r);
    } else {
        g_best = hit_miss();
        g_stats = RayStats(0u, 0u, 0u, 0u);
        g_visited = 0u;
        if !ray_is_valid(g_ray) {
            finish(r);
            return;
        }
    }
    let ray = g_ray;
    g_sh = ray_shear(ray);
    // Level bases of the Hi-Z buffer.
    var base = 0u;
    var width = max(params.tiles, 1u);
    for (var l = 0u; l < params.levels && work(); l++) {
        g_level_base[l] = base;
        g_level_width[l] = width;
        base += params.n_slots * width * width;
        width = (width + 1u) / 2u;
    }
    let n = params.n_views;
    var vrs: array<ViewRay, 6>;
    var ivs: array<Interval, 6>;
    var exits: array<u32, 6>;
    for (var f = 0u; f < n && work(); f++) {
        let v = views[f];
        let vr = view_ray(v, ray);
        var c = ViewClip(interval_empty(), NO_EXIT);
        if v.slot != NO_SLOT {
            c = clip_ray_to_view(v, vr, ray.tmin, ray.tmax);
        }
        vrs[f] = vr;
        ivs[f] = c.iv;
        exits[f] = c.exit;
    }
    var current = 0u;
    if resumes(0u) {
        current = g_idx[0];
    } else {
        current = first_unvisited(&ivs, n, g_visited);
    }
    while current < n && step(0u, current) {
        let f = current;
        // Resumed inside this view: it was marked, counted and tested.
        let inside = resumes_inside(0u);
        resumed(0u);
        if !inside {
            g_visited |= 1u << f;
        }
        if inside | (ivs[f].t0 <= g_best.t) {
            if !inside {
                g_stats.views += 1u;
            }
            if params.traversal == 0u {
                linear(views[f], vrs[f], ivs[f]);
            } else {
                hiz_walk(views[f], vrs[f], ivs[f]);
            }
        }
        // Across the edge the ray leaves through, else the next view it enters.
        current = first_unvisited(&ivs, n, g_visited);
        if (exits[f] != NO_EXIT) & (n == 6u) {
            let g = views[f].adjacency[exits[f]];
            if ((g_visited & (1u << g)) == 0u) & !is_empty(ivs[g]) {
                current = g;
            }
        }
    }
    if g_fail != NONE {
        save_state(r);
        // Listed for the next dispatch; the hit says so until then.
        let out = select(0u, params.capacity, pool.head.parity == 0u);
        pool.data[out + atomicAdd(&pool.head.count_out, 1u)] = r;
        hits[r] = Hit(UNFINISHED_ID, 0.0, 0.0, 0.0);
        return;
    }
    finish(r);
}

// The first dispatch: one thread per ray.
@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let r = gid.x + gid.y * nwg.x * 64u;
    if (r >= params.n_rays) | ((params.counted == 1u) & (r >= pool.head.count_in)) {
        return;
    }
    // Lists that did not fit their ids (a build recorded ahead of its count):
    // the structure is incomplete, and every ray says so.
    if offset_load(params.n_slots * params.tiles * params.tiles * params.buckets, params.offset_shift) > params.id_capacity {
        hits[r] = Hit(STRUCTURE_FULL_ID, 0.0, 0.0, 0.0);
        if params.with_stats == 1u {
            stats[r] = RayStats(0u, 0u, 0u, 0u);
        }
        return;
    }
    trace_ray(r, false);
}

// The later dispatches: one thread per unfinished ray (indirect, sized by `schedule`).
@compute @workgroup_size(64)
fn trace_continue(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    if s >= pool.head.count_in {
        return;
    }
    let list = select(0u, params.capacity, pool.head.parity == 1u);
    trace_ray(pool.data[list + s], true);
}

// Before a counted first dispatch: the ray count copied into count_in from the
// caller's buffer, clamped to the ray buffer, sizes it (one row of workgroups:
// n_rays is at most dirt_gpu::TraceResources::max_rays).
@compute @workgroup_size(1)
fn size_first() {
    let n = min(pool.head.count_in, params.n_rays);
    pool.head.count_in = n;
    dispatch[0] = (n + 63u) / 64u;
    dispatch[1] = 1u;
    dispatch[2] = 1u;
}

// Between dispatches: the rays just listed become the next dispatch's input.
@compute @workgroup_size(1)
fn schedule() {
    let n = atomicLoad(&pool.head.count_out);
    atomicStore(&pool.head.count_out, 0u);
    pool.head.count_in = n;
    pool.head.parity = 1u - pool.head.parity;
    if n > 0u {
        pool.head.rounds += 1u;
    }
    dispatch[0] = (n + 63u) / 64u;
    dispatch[1] = 1u;
    dispatch[2] = 1u;
}

// The unvisited view the ray enters first (the first such on ties); n when none.
fn first_unvisited(ivs: ptr<function, array<Interval, 6>>, n: u32, visited: u32) -> u32 {
    var best = n;
    var best_t0 = 0.0;
    for (var f = 0u; f < n && work(); f++) {
        let iv = (*ivs)[f];
        if ((visited & (1u << f)) == 0u) & !is_empty(iv) & ((best == n) | (iv.t0 < best_t0)) {
            best = f;
            best_t0 = iv.t0;
        }
    }
    return best;
}
