// Stage `shift` of the GPU renderer (dirt_render::shift): after a bounce,
// G(k-1) <- G(k) and G(k) <- G(k+1); `advance` moves the bounce counter on
// before the next one, and `tally` counts a sample's rays. Around each
// secondary trace the wavefront is compacted as the CPU renderer's is:
// `compact` packs the valid rays of the paths to the front of the trace's
// ray buffer and counts them (`state.live`, which sizes the trace's first
// dispatch), and `expand` hands each hit back to its path.

#import render_types

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read_write> paths: array<PathGpu>;
@group(0) @binding(3) var<storage, read_write> cur: array<SurfaceGpu>;
@group(0) @binding(4) var<storage, read> next: array<SurfaceGpu>;
// One ray and hit per path, as the stages write and read them.
@group(0) @binding(5) var<storage, read> rays: array<Ray>;
@group(0) @binding(6) var<storage, read_write> hits: array<Hit>;
// The trace's packed rays and hits, and the path of each packed ray.
@group(0) @binding(7) var<storage, read_write> trace_rays: array<Ray>;
@group(0) @binding(8) var<storage, read> trace_hits: array<Hit>;
@group(0) @binding(9) var<storage, read_write> slot_path: array<u32>;

// The slot order follows the atomic counter, not the path order: every hit
// is the exact closest hit of its ray, whatever slot the ray is traced in.
@compute @workgroup_size(64)
fn compact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    // A path without a valid ray misses, as its ray would; `expand` writes
    // the others.
    hits[i] = hit_miss();
    let r = rays[i];
    if ray_valid(r) {
        let k = atomicAdd(&state.live, 1u);
        trace_rays[k] = r;
        slot_path[k] = i;
    }
}

@compute @workgroup_size(64)
fn expand(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = path_index(gid, groups);
    if k >= atomicLoad(&state.live) {
        return;
    }
    hits[slot_path[k]] = trace_hits[k];
}

@compute @workgroup_size(64)
fn shift(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let c = cur[i];
    if c.prim != NO_PRIM {
        paths[i].prev = c.p;
    }
    cur[i] = next[i];
    paths[i].scattered = 0u;
}

@compute @workgroup_size(1)
fn advance() {
    state.bounce += 1u;
}

// After a sample: its ray count and confirmed candidates join the 64-bit totals.
@compute @workgroup_size(1)
fn tally() {
    let r = atomicExchange(&state.rays, 0u);
    let lo = state.rays_lo + r;
    state.rays_hi += select(0u, 1u, lo < r);
    state.rays_lo = lo;
    let c = atomicExchange(&state.confirmed, 0u);
    let clo = state.confirmed_lo + c;
    state.confirmed_hi += select(0u, 1u, clo < c);
    state.confirmed_lo = clo;
}
