// Mirrors dirt_math::dda: the pieces of the conservative tile walk and the
// Hi-Z stepping helpers. The walk's loop itself lives in trace.wgsl (WGSL has
// no closures); it follows dirt_math::dda::walk_tiles line for line.
#import types
#import num
#import divide
#import view
#import clip

fn tile_xy(v: View, vr: ViewRay, t: f32) -> vec2<f32> {
    let p = ray_point(vr, t);
    let z = view_w(v, p[2]);
    return vec2<f32>(tile_coord(v, div_cr(p[0], z)), tile_coord(v, div_cr(p[1], z)));
}

fn dilation(v: View, vr: ViewRay, iv: Interval) -> f32 {
    let z0 = vr.o[2] + iv.t0 * vr.d[2];
    let z1 = vr.o[2] + iv.t1 * vr.d[2];
    let z = view_w(v, fmin(z0, z1) - vr.eps);
    return div_cr(div_cr(vr.eps, z), v.step) + 0.00390625;
}

struct IndexRange {
    ok: bool,
    lo: u32,
    hi: u32,
}

fn index_range(a: f32, b: f32, d: f32, tiles: u32) -> IndexRange {
    let lo = fmin(a, b) - d;
    let hi = fmax(a, b) + d;
    if !((hi >= 0.0) & (lo < f32(tiles))) {
        return IndexRange(false, 0u, 0u);
    }
    let last = tiles - 1u;
    return IndexRange(true, floor_index(lo, last), floor_index(hi, last));
}

fn hiz_width(tiles: u32, level: u32) -> u32 {
    var w = max(tiles, 1u);
    for (var l = 0u; l < level; l++) {
        w = (w + 1u) / 2u;
    }
    return w;
}

fn hiz_levels(tiles: u32) -> u32 {
    var n = 1u;
    var w = max(tiles, 1u);
    while w > 1u {
        w = (w + 1u) / 2u;
        n += 1u;
    }
    return n;
}

// dirt_math::dda::HiZCell::clip
fn hiz_cell_clip(v: View, vr: ViewRay, iv: Interval, level: u32, ci: u32, cj: u32) -> Interval {
    let i0 = ci << level;
    let j0 = cj << level;
    let i1 = min((ci + 1u) << level, v.tiles);
    let j1 = min((cj + 1u) << level, v.tiles);
    // The loop over the four planes of the Rust, unrolled (see triangle.wgsl).
    var out = iv;
    clip_interval(&out, block_halfspace(v, i0, i1, j0, j1, 0u), vr);
    if is_empty(out) {
        return interval_empty();
    }
    clip_interval(&out, block_halfspace(v, i0, i1, j0, j1, 1u), vr);
    if is_empty(out) {
        return interval_empty();
    }
    clip_interval(&out, block_halfspace(v, i0, i1, j0, j1, 2u), vr);
    if is_empty(out) {
        return interval_empty();
    }
    clip_interval(&out, block_halfspace(v, i0, i1, j0, j1, 3u), vr);
    if is_empty(out) {
        return interval_empty();
    }
    return out;
}

// dirt_math::dda::child_order: child k as (di, dj).
fn child_order(dx: f32, dy: f32, k: u32) -> vec2<u32> {
    let fx = select(1u, 0u, dx >= 0.0);
    let fy = select(1u, 0u, dy >= 0.0);
    if abs(dx) >= abs(dy) {
        switch k {
            case 0u: { return vec2<u32>(fx, fy); }
            case 1u: { return vec2<u32>(1u - fx, fy); }
            case 2u: { return vec2<u32>(fx, 1u - fy); }
            default: { return vec2<u32>(1u - fx, 1u - fy); }
        }
    }
    switch k {
        case 0u: { return vec2<u32>(fx, fy); }
        case 1u: { return vec2<u32>(fx, 1u - fy); }
        case 2u: { return vec2<u32>(1u - fx, fy); }
        default: { return vec2<u32>(1u - fx, 1u - fy); }
    }
}

fn projected_direction(v: View, vr: ViewRay, iv: Interval) -> vec2<f32> {
    let a = tile_xy(v, vr, iv.t0);
    let b = tile_xy(v, vr, iv.t1);
    return vec2<f32>(b[0] - a[0], b[1] - a[1]);
}
