// Stage `views` on the GPU: the view set of dirt_core::views_for, computed from
// the triangles without a read-back, for builds recorded into an application's
// encoder. Four entries, recorded in order:
//   bounds     one thread per triangle: the scene bounds (atomic min/max of the
//              ordered encoding) and the first non-finite triangle;
//   views      one thread: each view's apex, planes, eps and scale from the
//              bounds, as dirt_math::ViewSet::cube / single / ortho compute them;
//   reach      one thread per (triangle, view): which views a triangle reaches;
//   leave_out  one thread: views no triangle reaches get no slot.
// Slots are sparse here (slot = view index): the per-view blocks are sized
// for every view, because the host cannot know without a read-back which
// views have content. Every decision is the CPU's, to the bit.
#import types
#import num
#import divide
#import encode
#import view
#import clip
#import tris

// dirt_gpu::ViewsParams
struct ViewsParams {
    n_tris: u32,
    // 0 = cube, 1 = single, 2 = one orthographic view, 3 = two split.
    kind: u32,
    // 1: `center` is given (the cube's centre, or the single view's eye).
    has_center: u32,
    tri_shift: u32, // triangles per chunk: 2^tri_shift (tris.wgsl)
    center: vec3<f32>,
    // The axis orthographic views look along: 0, 1, 2, or 3 for the bounds' thinnest.
    axis: u32,
}

// dirt_gpu::FrameState (its first words)
struct FrameState {
    // ~ordered(min x, y, z), ordered(max x, y, z): both grow with atomicMax from zero.
    bounds: array<atomic<u32>, 6>,
    // 0xffffffff - index of the first triangle with a non-finite vertex, or 0.
    bad: atomic<u32>,
    // Bit v: some triangle reaches a tile of view v.
    reach: atomic<u32>,
}

@group(0) @binding(1) var<storage, read_write> views: array<View, 6>;
@group(0) @binding(2) var<storage, read_write> state: FrameState;
@group(0) @binding(3) var<uniform> params: ViewsParams;

fn tri_vertex(prim: u32, k: u32) -> vec3<f32> {
    return tri_load(prim, k, params.tri_shift);
}

fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

@compute @workgroup_size(64)
fn bounds(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let prim = gid.x + gid.y * nwg.x * 64u;
    if prim >= params.n_tris {
        return;
    }
    for (var k = 0u; k < 3u; k++) {
        let p = tri_vertex(prim, k);
        if !(is_finite(p.x) && is_finite(p.y) && is_finite(p.z)) {
            atomicMax(&state.bad, 0xffffffffu - prim);
            return;
        }
    }
    for (var k = 0u; k < 3u; k++) {
        let p = tri_vertex(prim, k);
        for (var a = 0u; a < 3u; a++) {
            let e = f32_to_ordered(p[a]);
            atomicMax(&state.bounds[a], ~e);
            atomicMax(&state.bounds[3u + a], e);
        }
    }
}

fn vec3_max_abs(p: vec3<f32>) -> f32 {
    return fmax(fmax(abs(p[0]), abs(p[1])), abs(p[2]));
}

// The eight corners in dirt_math::view::corners order (bit 0 x, bit 1 y, bit 2 z).
fn corner(lo: vec3<f32>, hi: vec3<f32>, k: u32) -> vec3<f32> {
    return vec3<f32>(select(lo[0], hi[0], (k & 1u) != 0u), select(lo[1], hi[1], (k & 2u) != 0u), select(lo[2], hi[2], (k & 4u) != 0u));
}

// dirt_math::view::near_distance.
fn near_distance(c: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    var scale = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let p = corner(lo, hi, k);
        scale = fmax(scale, vec3_max_abs(vec3<f32>(p[0] - c[0], p[1] - c[1], p[2] - c[2])));
    }
    if !(scale > 0.0) || !is_finite(scale) {
        scale = 1.0;
    }
    return scale * (1.0 / 32.0);
}

// dirt_math::View::new on the template's axes, tan and tiles.
fn fit_view(t: View, apex: vec3<f32>, near: f32, lo: vec3<f32>, hi: vec3<f32>, slot: u32) -> View {
    var v = t;
    v.apex = apex;
    v.near = near;
    var far = f32_neg_inf();
    var scale = near;
    for (var k = 0u; k < 8u; k++) {
        let p = to_view(v, corner(lo, hi, k));
        far = fmax(far, p[2]);
        scale = fmax(fmax(fmax(scale, abs(p[0])), abs(p[1])), abs(p[2]));
    }
    v.scale = scale;
    v.eps = (1.0 / 65536.0) * scale;
    if far > near {
        v.far = far + 2.0 * v.eps;
        v.slot = slot;
    } else {
        v.far = near;
        v.slot = NO_SLOT;
    }
    return v;
}

fn length3(a: vec3<f32>) -> f32 {
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1]);
}

// dirt_math::view::positive_zeros, on the bits: no float flag can fold it away.
fn positive_zero(x: f32) -> f32 {
    let b = bitcast<u32>(x);
    return bitcast<f32>(select(b, 0u, (b & 0x7fffffffu) == 0u));
}

fn positive_zeros(a: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(positive_zero(a[0]), positive_zero(a[1]), positive_zero(a[2]));
}

fn scale3(a: vec3<f32>, s: f32) -> vec3<f32> {
    return vec3<f32>(a[0] * s, a[1] * s, a[2] * s);
}

// dirt_math::view::Axis::thinnest: the axis of the smallest extent (ties go
// to z, then y), which the single view and the orthographic views look along.
fn thinnest_axis(e: vec3<f32>) -> u32 {
    if e[0] < e[1] && e[0] < e[2] {
        return 0u;
    } else if e[1] < e[2] {
        return 1u;
    }
    return 2u;
}

@compute @workgroup_size(1)
fn views_from_bounds() {
    var lo = vec3<f32>(ordered_to_f32(~atomicLoad(&state.bounds[0])), ordered_to_f32(~atomicLoad(&state.bounds[1])), ordered_to_f32(~atomicLoad(&state.bounds[2])));
    var hi = vec3<f32>(ordered_to_f32(atomicLoad(&state.bounds[3])), ordered_to_f32(atomicLoad(&state.bounds[4])), ordered_to_f32(atomicLoad(&state.bounds[5])));
    let bad = atomicLoad(&state.bad) != 0u;
    // No triangle: dirt_core::views_for_all's unit box.
    if params.n_tris == 0u || bad {
        lo = vec3<f32>(-1.0, -1.0, -1.0);
        hi = vec3<f32>(1.0, 1.0, 1.0);
    }
    let c = vec3<f32>((lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5, (lo[2] + hi[2]) * 0.5);
    if params.kind == 0u {
        var center = c;
        if params.has_center == 1u {
            center = params.center;
        }
        let near = near_distance(center, lo, hi);
        for (var f = 0u; f < 6u; f++) {
            let t = views[f];
            let apex = vec3<f32>(center[0] - t.forward[0] * near, center[1] - t.forward[1] * near, center[2] - t.forward[2] * near);
            views[f] = fit_view(t, apex, near, lo, hi, f);
        }
    } else if params.kind >= 2u {
        // dirt_math::ViewSet::ortho.
        let e = vec3<f32>(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
        let r = fmax(length3(e) * 0.5, 1.17549435e-38);
        var a = params.axis;
        if a > 2u {
            a = thinnest_axis(e);
        }
        var t = views[0];
        var fwd = vec3<f32>(0.0, 0.0, 0.0);
        fwd[a] = 1.0;
        // (right, up) for x: (-z, y); y: (x, -z); z: (x, y). Zeros made
        // positive, as the CPU's constants have them (a GPU may pick either
        // sign of a zero here).
        t.right = positive_zeros(select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 0.0, -1.0), a == 0u));
        t.up = positive_zeros(select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, -1.0), a == 1u));
        t.forward = positive_zeros(fwd);
        t.ortho = 1u;
        let pad = r * (1.0 / 32.0);
        let back = 0.5 * e[a] + 2.0 * pad;
        let apex = vec3<f32>(c[0] - fwd[0] * back, c[1] - fwd[1] * back, c[2] - fwd[2] * back);
        var cross = 0.0;
        for (var k = 0u; k < 3u; k++) {
            if k != a {
                cross = fmax(cross, e[k]);
            }
        }
        let half = fmax(0.5 * cross, pad) * (1.0 + 1.0 / 1024.0);
        t.tan = half;
        t.step = div_cr(2.0 * half, f32(t.tiles));
        let near = fmax(pad, 1.17549435e-38);
        if params.kind == 2u {
            views[0] = fit_view(t, apex, near, lo, hi, 0u);
        } else {
            var cut = c[a];
            if params.has_center == 1u {
                cut = params.center[a];
            }
            var hi1 = hi;
            hi1[a] = fmax(fmin(hi[a], cut), lo[a]);
            var lo2 = lo;
            lo2[a] = fmin(fmax(lo[a], cut), hi[a]);
            let first = fit_view(t, apex, near, lo, hi1, 0u);
            var at = lo;
            at[a] = lo2[a];
            views[0] = first;
            views[1] = fit_view(t, apex, fmax(to_view(first, at)[2], near), lo2, hi, 1u);
        }
    } else {
        var t = views[0];
        var apex: vec3<f32>;
        var near: f32;
        let r = fmax(length3(vec3<f32>(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])) * 0.5, 1.17549435e-38);
        var fwd = vec3<f32>(0.0, 0.0, 1.0);
        if params.has_center == 0u {
            // dirt_math::view::single_axis.
            let a = thinnest_axis(vec3<f32>(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
            if a == 0u {
                fwd = vec3<f32>(1.0, 0.0, 0.0);
            } else if a == 1u {
                fwd = vec3<f32>(0.0, 1.0, 0.0);
            }
            let dist = 1.5 * r + r;
            apex = vec3<f32>(c[0] - fwd[0] * dist, c[1] - fwd[1] * dist, c[2] - fwd[2] * dist);
            near = dist - r * 1.01;
        } else {
            let eye = params.center;
            let d = vec3<f32>(c[0] - eye[0], c[1] - eye[1], c[2] - eye[2]);
            let rcp = div_cr(1.0, length3(d));
            if is_finite(rcp) && rcp > 0.0 {
                fwd = scale3(d, rcp);
            }
            apex = eye;
            // ViewSet::single: outside the bounding sphere, a near plane at half the clearance.
            near = fmax(near_distance(eye, lo, hi), 0.5 * (length3(d) - r));
        }
        // The axes of ViewSet::single (exact for a unit axis: its products are 0 and ±1).
        var up_hint = vec3<f32>(0.0, 1.0, 0.0);
        if abs(fwd[1]) > 0.9 {
            up_hint = vec3<f32>(1.0, 0.0, 0.0);
        }
        let rc = cross3(up_hint, fwd);
        let right = positive_zeros(scale3(rc, div_cr(1.0, length3(rc))));
        t.up = positive_zeros(cross3(fwd, right));
        t.forward = positive_zeros(fwd);
        t.right = right;
        views[0] = fit_view(t, apex, fmax(near, 1.17549435e-38), lo, hi, 0u);
    }
    if bad {
        for (var f = 0u; f < 6u; f++) {
            views[f].slot = NO_SLOT;
        }
    }
}

@compute @workgroup_size(64)
fn reach(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let prim = gid.x + gid.y * nwg.x * 64u;
    let f = gid.z;
    if prim >= params.n_tris || (atomicLoad(&state.reach) & (1u << f)) != 0u {
        return;
    }
    let v = views[f];
    if v.slot == NO_SLOT {
        return;
    }
    let poly = clip_triangle_to_view(v, to_view(v, tri_vertex(prim, 0u)), to_view(v, tri_vertex(prim, 1u)), to_view(v, tri_vertex(prim, 2u)));
    if polygon_tile_range(v, poly).ok {
        atomicOr(&state.reach, 1u << f);
    }
}

@compute @workgroup_size(1)
fn leave_out() {
    let reached = atomicLoad(&state.reach);
    for (var f = 0u; f < 6u; f++) {
        if (reached & (1u << f)) == 0u {
            views[f].slot = NO_SLOT;
        }
    }
}
