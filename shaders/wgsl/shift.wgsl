// Stage `shift` of the GPU renderer (dirt_render::shift): after a bounce,
// G(k-1) <- G(k) and G(k) <- G(k+1); `advance` moves the bounce counter on
// before the next one, and `tally` counts a sample's rays.

#import render_types

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read_write> paths: array<PathGpu>;
@group(0) @binding(3) var<storage, read_write> cur: array<SurfaceGpu>;
@group(0) @binding(4) var<storage, read> next: array<SurfaceGpu>;

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
