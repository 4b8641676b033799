// Mirrors dirt_math::clip: dilated half-spaces, ray intervals, polygon
// clipping and per-tile depth extents.
#import types
#import num
#import divide
#import view
#import work

// dirt_math::clip::HalfSpace as (kind, axis, s, ortho): kind 0 = Lo, 1 = Hi, 2 = Near (s = near),
// 3 = Far (s = far); Lo and Hi with ortho = 1 are OrthoLo and OrthoHi.
struct HalfSpace {
    kind: u32,
    axis: u32,
    s: f32,
    // 1 for a side of an orthographic view (dirt_math's OrthoLo and OrthoHi
    // are kinds 0 and 1 here with this flag): its value is picked with a
    // select, not a case of its own, so that a clip whose kind is known
    // where it is written still compiles to one case (a kind chosen at run
    // time put the whole switch into every clip of every loop, and
    // SwiftShader's compiler did not finish).
    ortho: u32,
}

fn hs_eval(h: HalfSpace, p: vec3<f32>, eps: f32) -> f32 {
    let o = h.ortho != 0u;
    switch h.kind {
        case 0u: {
            return select(p[h.axis] - h.s * p[2], p[h.axis] - h.s, o) + eps;
        }
        case 1u: {
            return select(h.s * p[2] - p[h.axis], h.s - p[h.axis], o) + eps;
        }
        case 2u: {
            return p[2] - h.s + eps;
        }
        default: {
            return h.s - p[2] + eps;
        }
    }
}

fn hs_slope(h: HalfSpace, d: vec3<f32>) -> f32 {
    let o = h.ortho != 0u;
    switch h.kind {
        case 0u: {
            return select(d[h.axis] - h.s * d[2], d[h.axis], o);
        }
        case 1u: {
            return select(h.s * d[2] - d[h.axis], -d[h.axis], o);
        }
        case 2u: {
            return d[2];
        }
        default: {
            return -d[2];
        }
    }
}

// dirt_math::View::lo: above tile boundary s of the view, on axis (0: x, 1: y).
fn view_lo(v: View, axis: u32, s: f32) -> HalfSpace {
    return HalfSpace(0u, axis, s, v.ortho);
}

// dirt_math::View::hi: below tile boundary s of the view.
fn view_hi(v: View, axis: u32, s: f32) -> HalfSpace {
    return HalfSpace(1u, axis, s, v.ortho);
}

// dirt_math::clip::Interval
struct Interval {
    t0: f32,
    t1: f32,
}

fn interval_empty() -> Interval {
    return Interval(f32_inf(), f32_neg_inf());
}

fn is_empty(iv: Interval) -> bool {
    return !(iv.t0 <= iv.t1);
}

// Intersects with the half-space; true when t1 moved.
fn clip_interval(iv: ptr<function, Interval>, h: HalfSpace, vr: ViewRay) -> bool {
    let f0 = hs_eval(h, vr.o, vr.eps);
    let f1 = hs_slope(h, vr.d);
    if f1 > 0.0 {
        let t = div_cr(-f0, f1);
        if t > (*iv).t0 {
            (*iv).t0 = t;
        }
    } else if f1 < 0.0 {
        let t = div_cr(-f0, f1);
        if t < (*iv).t1 {
            (*iv).t1 = t;
            return true;
        }
    } else if !(f0 >= 0.0) {
        *iv = interval_empty();
    }
    return false;
}

fn ray_point(vr: ViewRay, t: f32) -> vec3<f32> {
    return vec3<f32>(vr.o[0] + t * vr.d[0], vr.o[1] + t * vr.d[1], vr.o[2] + t * vr.d[2]);
}

fn ray_depth(vr: ViewRay, t: f32) -> f32 {
    return vr.o[2] + t * vr.d[2];
}

// The k-th of the six half-spaces of a whole view (dirt_math::clip::view_frustum).
fn view_halfspace(v: View, k: u32) -> HalfSpace {
    switch k {
        case 0u: {
            return view_lo(v, 0u, -v.tan);
        }
        case 1u: {
            return view_hi(v, 0u, v.tan);
        }
        case 2u: {
            return view_lo(v, 1u, -v.tan);
        }
        case 3u: {
            return view_hi(v, 1u, v.tan);
        }
        case 4u: {
            return HalfSpace(2u, 0u, v.near, 0u);
        }
        default: {
            return HalfSpace(3u, 0u, v.far, 0u);
        }
    }
}

// The k-th side half-space of the tile block [i0, i1) x [j0, j1) (dirt_math::clip::block_frustum).
fn block_halfspace(v: View, i0: u32, i1: u32, j0: u32, j1: u32, k: u32) -> HalfSpace {
    switch k {
        case 0u: {
            return view_lo(v, 0u, boundary(v, i0));
        }
        case 1u: {
            return view_hi(v, 0u, boundary(v, i1));
        }
        case 2u: {
            return view_lo(v, 1u, boundary(v, j0));
        }
        default: {
            return view_hi(v, 1u, boundary(v, j1));
        }
    }
}

const NO_EXIT: u32 = 0xffffffffu;

struct ViewClip {
    iv: Interval,
    exit: u32,
}

// dirt_math::clip::clip_ray_to_view
fn clip_ray_to_view(v: View, vr: ViewRay, tmin: f32, tmax: f32) -> ViewClip {
    var iv = Interval(tmin, tmax);
    var exit = NO_EXIT;
    for (var k = 0u; k < 6u && work(); k++) {
        if clip_interval(&iv, view_halfspace(v, k), vr) {
            exit = select(NO_EXIT, k, k < 4u);
        }
        if is_empty(iv) {
            return ViewClip(interval_empty(), NO_EXIT);
        }
    }
    return ViewClip(iv, exit);
}

const MAX_POLY: u32 = 16u;

struct Polygon {
    len: u32,
    v: array<vec3<f32>, 16>,
}

fn polygon_triangle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> Polygon {
    var p: Polygon;
    p.len = 3u;
    p.v[0] = a;
    p.v[1] = b;
    p.v[2] = c;
    return p;
}

// Sutherland-Hodgman against one half-space; points on the boundary are kept.
fn polygon_clip(poly: ptr<function, Polygon>, h: HalfSpace, eps: f32) {
    let n = (*poly).len;
    if n == 0u {
        return;
    }
    var out: array<vec3<f32>, 16>;
    var m = 0u;
    for (var k = 0u; k < n; k++) {
        let p = (*poly).v[k];
        let q = (*poly).v[(k + 1u) % n];
        let fp = hs_eval(h, p, eps);
        let fq = hs_eval(h, q, eps);
        if (fp >= 0.0) & (m < MAX_POLY) {
            out[m] = p;
            m += 1u;
        }
        if ((fp >= 0.0) != (fq >= 0.0)) & (m < MAX_POLY) {
            let w = div_cr(fp, fp - fq);
            out[m] = vec3<f32>(p[0] + (q[0] - p[0]) * w, p[1] + (q[1] - p[1]) * w, p[2] + (q[2] - p[2]) * w);
            m += 1u;
        }
    }
    (*poly).v = out;
    (*poly).len = m;
}

// Depth range of the vertices; x > y when empty.
fn polygon_depth_range(poly: ptr<function, Polygon>) -> vec2<f32> {
    var lo = f32_inf();
    var hi = f32_neg_inf();
    for (var k = 0u; k < (*poly).len; k++) {
        lo = fmin(lo, (*poly).v[k][2]);
        hi = fmax(hi, (*poly).v[k][2]);
    }
    return vec2<f32>(lo, hi);
}

// dirt_math::clip::clip_triangle_to_view; an empty polygon when outside.
fn clip_triangle_to_view(v: View, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> Polygon {
    var poly = polygon_triangle(a, b, c);
    for (var k = 0u; k < 6u; k++) {
        polygon_clip(&poly, view_halfspace(v, k), v.eps);
        if poly.len == 0u {
            return poly;
        }
    }
    return poly;
}

struct Extent {
    ok: bool,
    lo: f32,
    hi: f32,
}

// dirt_math::clip::tile_depth_extent: the tile's planes inside the range
// `r` (i0, i1, j0, j1) only: lower x where i > i0, upper x where i < i1, and
// so for y; the x planes are 0 and 1, y 2 and 3.
fn tile_depth_extent(v: View, poly: Polygon, i: u32, j: u32, r: vec4<u32>) -> Extent {
    var p = poly;
    for (var k = 0u; k < 4u; k++) {
        let inner = select(select(select((j < r.w), (j > r.z), k == 2u), (i < r.y), k == 1u), (i > r.x), k == 0u);
        if !inner {
            continue;
        }
        polygon_clip(&p, block_halfspace(v, i, i + 1u, j, j + 1u, k), v.eps);
        if p.len == 0u {
            return Extent(false, 0.0, 0.0);
        }
    }
    let d = polygon_depth_range(&p);
    return Extent(true, d.x - v.eps, d.y + v.eps);
}

struct TileRange {
    ok: bool,
    i0: u32,
    i1: u32,
    j0: u32,
    j1: u32,
}

// dirt_math::clip::polygon_tile_range
fn polygon_tile_range(v: View, poly: Polygon) -> TileRange {
    let none = TileRange(false, 0u, 0u, 0u, 0u);
    if poly.len == 0u {
        return none;
    }
    var pl = poly;
    let zlo = polygon_depth_range(&pl).x;
    let z = view_w(v, zlo);
    let delta = div_cr(div_cr(v.eps, z), v.step) + 0.00390625;
    var xlo = f32_inf();
    var xhi = f32_neg_inf();
    var ylo = f32_inf();
    var yhi = f32_neg_inf();
    for (var k = 0u; k < poly.len; k++) {
        let p = poly.v[k];
        let pz = view_w(v, p[2]);
        let x = tile_coord(v, div_cr(p[0], pz));
        let y = tile_coord(v, div_cr(p[1], pz));
        xlo = fmin(xlo, x);
        xhi = fmax(xhi, x);
        ylo = fmin(ylo, y);
        yhi = fmax(yhi, y);
    }
    let last = v.tiles - 1u;
    if !((xhi + delta >= 0.0) & (yhi + delta >= 0.0) & (xlo - delta <= f32(v.tiles)) & (ylo - delta <= f32(v.tiles))) {
        return none;
    }
    return TileRange(true, floor_index(xlo - delta, last), floor_index(xhi + delta, last), floor_index(ylo - delta, last), floor_index(yhi + delta, last));
}
