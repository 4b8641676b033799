// Stage `trace`: closest hits of a ray buffer. Mirrors dirt_cpu::trace and
// dirt_math::dda::walk_tiles line for line; read them side by side.
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

// dirt_gpu::TraceParams
struct TraceParams {
    n_rays: u32,
    n_views: u32,
    tiles: u32,
    buckets: u32,
    levels: u32,
    traversal: u32, // 0 = linear, 1 = Hi-Z
    n_slots: u32, // views with content: blocks per Hi-Z level
    _pad1: u32,
}

@group(0) @binding(0) var<storage, read> rays: array<Ray>;
@group(0) @binding(1) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(2) var<storage, read> tris: array<f32>;
@group(0) @binding(3) var<uniform> views: array<View, 6>;
@group(0) @binding(4) var<uniform> params: TraceParams;
@group(0) @binding(5) var<storage, read> hiz: array<u32>;
@group(0) @binding(6) var<storage, read> offsets: array<u32>;
@group(0) @binding(7) var<storage, read> ids: array<u32>;
@group(0) @binding(8) var<storage, read_write> stats: array<RayStats>;

var<private> g_ray: Ray;
var<private> g_sh: RayShear;
var<private> g_best: Hit;
var<private> g_stats: RayStats;
// Start of each Hi-Z level in `hiz` (in tiles; two u32 per tile).
var<private> g_level_base: array<u32, 16>;
// Cells per side of each Hi-Z level.
var<private> g_level_width: array<u32, 16>;

fn tri_vertex(prim: u32, k: u32) -> vec3<f32> {
    let b = prim * 9u + k * 3u;
    return vec3<f32>(tris[b], tris[b + 1u], tris[b + 2u]);
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
    g_stats.tiles += 1u;
    let tile = v.slot * tile_count(v) + (j * v.tiles + i);
    let zmin = ordered_to_f32(hiz[2u * tile]);
    let zmax = ordered_to_f32(hiz[2u * tile + 1u]);
    let span = depth_span(vr, iv);
    let lo = span.x;
    let hi = span.y;
    if !(hi >= zmin && lo <= zmax) {
        return;
    }
    let nb = params.buckets;
    let b0 = bucket_of(lo, zmin, zmax, nb);
    let b1 = bucket_of(hi, zmin, zmax, nb);
    let ascending = vr.d[2] >= 0.0;
    for (var n = 0u; n <= b1 - b0 && work(); n++) {
        let k = select(b1 - n, b0 + n, ascending);
        if hit_is_hit(g_best) {
            let zb = ray_depth(vr, g_best.t);
            if ascending && bucket_floor_depth(k, zmin, zmax, nb) > zb + vr.eps {
                break;
            }
            if !ascending && bucket_ceil_depth(k, zmin, zmax, nb) < zb - vr.eps {
                break;
            }
        }
        g_stats.buckets += 1u;
        let list = tile * nb + k;
        let start = offsets[list];
        let end = offsets[list + 1u];
        for (var at = start; at < end && work(); at++) {
            g_stats.tests += 1u;
            intersect_closest(ids[at]);
        }
    }
}

// dirt_math::dda::walk_tiles with the visitor of dirt_cpu::trace::linear.
fn linear(v: View, vr: ViewRay, iv: Interval) {
    if is_empty(iv) || v.tiles == 0u {
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
    var walking = true;
    while walking && n <= kr.hi - kr.lo && work() {
        let k = select(kr.hi - n, kr.lo + n, forward);
        var band = iv;
        clip_interval(&band, hs_lo(major, boundary(v, k)), vr);
        clip_interval(&band, hs_hi(major, boundary(v, k + 1u)), vr);
        if !is_empty(band) {
            if band.t0 > g_best.t {
                walking = false;
            } else {
                let p = tile_xy(v, vr, band.t0);
                let q = tile_xy(v, vr, band.t1);
                let mr = index_range(p[minor], q[minor], delta, v.tiles);
                if mr.ok {
                    for (var e = 0u; e <= mr.hi - mr.lo && work(); e++) {
                        let m = select(mr.hi - e, mr.lo + e, minor_forward);
                        var span = band;
                        clip_interval(&span, hs_lo(minor, boundary(v, m)), vr);
                        clip_interval(&span, hs_hi(minor, boundary(v, m + 1u)), vr);
                        if !is_empty(span) {
                            let i = select(m, k, major == 0u);
                            let j = select(k, m, major == 0u);
                            visit_tile(v, vr, i, j, span);
                        }
                    }
                }
            }
        }
        n += 1u;
    }
}

// dirt_cpu::trace::hiz
fn hiz_walk(v: View, vr: ViewRay, iv: Interval) {
    let levels = params.levels;
    let dir = projected_direction(v, vr, iv);
    var stack: array<vec3<u32>, 64>;
    var top = 0u;
    stack[0] = vec3<u32>(levels - 1u, 0u, 0u);
    top = 1u;
    while top > 0u && work() {
        top -= 1u;
        let cell = stack[top];
        let level = cell.x;
        let civ = hiz_cell_clip(v, vr, iv, level, cell.y, cell.z);
        if is_empty(civ) || civ.t0 > g_best.t {
            continue;
        }
        let w = g_level_width[level];
        let at = g_level_base[level] + v.slot * w * w + cell.z * w + cell.y;
        let zmin = ordered_to_f32(hiz[2u * at]);
        let zmax = ordered_to_f32(hiz[2u * at + 1u]);
        let span = depth_span(vr, civ);
        if !(span.y >= zmin && span.x <= zmax) {
            continue;
        }
        if level == 0u {
            visit_tile(v, vr, cell.y, cell.z, civ);
            continue;
        }
        let cw = g_level_width[level - 1u];
        for (var r = 0u; r < 4u && work(); r++) {
            let c = child_order(dir.x, dir.y, 3u - r);
            let i = 2u * cell.y + c.x;
            let j = 2u * cell.z + c.y;
            if i < cw && j < cw && top < 64u {
                stack[top] = vec3<u32>(level - 1u, i, j);
                top += 1u;
            }
        }
    }
}

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let r = gid.x + gid.y * nwg.x * 64u;
    if r >= params.n_rays {
        return;
    }
    g_ray = rays[r];
    g_best = hit_miss();
    g_stats = RayStats(0u, 0u, 0u, 0u);
    let ray = g_ray;
    // Rays that fail Ray::validate miss (dirt_math::Ray::validate).
    let o = ray.origin;
    let d = ray.dir;
    let finite_o = abs(o[0]) <= 3.4028235e38 && abs(o[1]) <= 3.4028235e38 && abs(o[2]) <= 3.4028235e38;
    let finite_d = abs(d[0]) <= 3.4028235e38 && abs(d[1]) <= 3.4028235e38 && abs(d[2]) <= 3.4028235e38;
    let nonzero = !(d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0);
    let range_ok = ray.tmin >= 0.0 && abs(ray.tmin) <= 3.4028235e38 && !(ray.tmax < ray.tmin) && ray.tmax == ray.tmax;
    if !(finite_o && finite_d && nonzero && range_ok) {
        hits[r] = g_best;
        stats[r] = g_stats;
        return;
    }
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
    var visited = 0u;
    var current = first_unvisited(&ivs, n, visited);
    while current < n && work() {
        let f = current;
        visited |= 1u << f;
        if ivs[f].t0 <= g_best.t {
            g_stats.views += 1u;
            if params.traversal == 0u {
                linear(views[f], vrs[f], ivs[f]);
            } else {
                hiz_walk(views[f], vrs[f], ivs[f]);
            }
        }
        // Across the edge the ray leaves through, else the next view it enters.
        current = first_unvisited(&ivs, n, visited);
        if exits[f] != NO_EXIT && n == 6u {
            let g = views[f].adjacency[exits[f]];
            if (visited & (1u << g)) == 0u && !is_empty(ivs[g]) {
                current = g;
            }
        }
    }
    if g_work > WORK_BUDGET {
        g_best = Hit(UNFINISHED_ID, 0.0, 0.0, 0.0);
    }
    hits[r] = g_best;
    stats[r] = g_stats;
}

// The unvisited view the ray enters first (the first such on ties); n when none.
fn first_unvisited(ivs: ptr<function, array<Interval, 6>>, n: u32, visited: u32) -> u32 {
    var best = n;
    var best_t0 = 0.0;
    for (var f = 0u; f < n && work(); f++) {
        let iv = (*ivs)[f];
        if (visited & (1u << f)) == 0u && !is_empty(iv) && (best == n || iv.t0 < best_t0) {
            best = f;
            best_t0 = iv.t0;
        }
    }
    return best;
}
