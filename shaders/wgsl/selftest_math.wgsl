// Self-test kernels used by the GPU tests to compare single functions of the
// shared modules with their dirt-math twins, bit for bit. Not pipeline stages.
// Input and output are raw words; one invocation per case.
#import types
#import divide
#import triangle
#import dda

@group(0) @binding(0) var<storage, read> st_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> st_out: array<u32>;

fn st_f(i: u32) -> f32 {
    return bitcast<f32>(st_in[i]);
}

fn st_v(i: u32) -> vec3<f32> {
    return vec3<f32>(st_f(i), st_f(i + 1u), st_f(i + 2u));
}

// Case i: (a, b) -> div_cr(a, b).
@compute @workgroup_size(64)
fn divide(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if 2u * i + 1u < arrayLength(&st_in) {
        st_out[i] = bitcast<u32>(div_cr(st_f(2u * i), st_f(2u * i + 1u)));
    }
}

// Case i: a ray (8 words) and a triangle (9 words) -> (hit, t, u, v).
@compute @workgroup_size(64)
fn intersect_one(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let b = 17u * i;
    if b + 16u < arrayLength(&st_in) {
        let ray = Ray(st_v(b), st_f(b + 3u), st_v(b + 4u), st_f(b + 7u));
        let h = intersect(ray, ray_shear(ray), st_v(b + 8u), st_v(b + 11u), st_v(b + 14u));
        st_out[4u * i] = select(0u, 1u, h.hit);
        st_out[4u * i + 1u] = bitcast<u32>(h.t);
        st_out[4u * i + 2u] = bitcast<u32>(h.u);
        st_out[4u * i + 3u] = bitcast<u32>(h.v);
    }
}


// Case i: a view (28 words, dirt_math::ViewGpu), a ray (8 words) -> per view
// interval and exit, the walk's dilation and the projected end points
// (t0, t1, exit, delta, ax, ay, bx, by).
@compute @workgroup_size(64)
fn view_walk_one(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let b = 36u * i;
    if b + 35u < arrayLength(&st_in) {
        let v = View(st_v(b), st_f(b + 3u), st_v(b + 4u), st_f(b + 7u), st_v(b + 8u), st_f(b + 11u), st_v(b + 12u), st_f(b + 15u), st_in[b + 16u], st_f(b + 17u), st_f(b + 18u), st_in[b + 19u], vec4<u32>(st_in[b + 20u], st_in[b + 21u], st_in[b + 22u], st_in[b + 23u]), st_in[b + 24u], 0u, 0u, 0u);
        let ray = Ray(st_v(b + 28u), st_f(b + 31u), st_v(b + 32u), st_f(b + 35u));
        let vr = view_ray(v, ray);
        let c = clip_ray_to_view(v, vr, ray.tmin, ray.tmax);
        let o = 8u * i;
        st_out[o] = bitcast<u32>(c.iv.t0);
        st_out[o + 1u] = bitcast<u32>(c.iv.t1);
        st_out[o + 2u] = c.exit;
        if !is_empty(c.iv) {
            let a = tile_xy(v, vr, c.iv.t0);
            let e = tile_xy(v, vr, c.iv.t1);
            st_out[o + 3u] = bitcast<u32>(dilation(v, vr, c.iv));
            st_out[o + 4u] = bitcast<u32>(a.x);
            st_out[o + 5u] = bitcast<u32>(a.y);
            st_out[o + 6u] = bitcast<u32>(e.x);
            st_out[o + 7u] = bitcast<u32>(e.y);
        }
    }
}
