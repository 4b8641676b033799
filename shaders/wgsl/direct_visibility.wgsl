// Stage `direct_visibility` of the GPU renderer (dirt_render::direct_visibility):
// `confirm` tests each primary ray exactly against its pixel's rasterised
// candidate and, when it is hit at t, limits the ray to t (the trace is
// inclusive, so a primitive at the same t with a smaller id still wins);
// `settle` keeps the closer of the candidate and the trace and gives the ray
// back its full length. The primary hits are the full trace's, bit for bit:
// the candidate can only make the trace shorter. Compiled as DIRT's passes
// are (NoContraction on an exact device), so `intersect` is the CPU's.

#import render_types
#import triangle

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read_write> rays: array<Ray>;
@group(0) @binding(3) var<storage, read_write> hits: array<Hit>;
// The rasteriser's primitive per pixel (NO_PRIM: none), rows top to bottom.
@group(0) @binding(4) var<storage, read> raster: array<u32>;
@group(0) @binding(5) var<storage, read> tris: array<TriGpu>;
// The confirmed candidate per path (a miss where none was).
@group(0) @binding(6) var<storage, read_write> candidates: array<Hit>;

@compute @workgroup_size(64)
fn confirm(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    var c = hit_miss();
    let p = raster[i];
    let ray = rays[i];
    if (p < params.n_tris) & ray_valid(ray) {
        let t = tris[p];
        let h = intersect(ray, ray_shear(ray), t.p0, t.p1, t.p2);
        if h.hit {
            c = Hit(p, h.t, h.u, h.v);
            rays[i].tmax = h.t;
            atomicAdd(&state.confirmed, 1u);
        }
    }
    candidates[i] = c;
}

@compute @workgroup_size(64)
fn settle(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let c = candidates[i];
    if !hit_is_hit(c) {
        return;
    }
    let h = hits[i];
    // An unfinished walk stays what it is: `fetch` counts it and the render fails.
    if !hit_unfinished(h) & hit_closer_than(c, h) {
        hits[i] = c;
    }
    rays[i].tmax = f32_inf();
}
