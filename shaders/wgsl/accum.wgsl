// Stage `accum` of the GPU renderer (dirt_render::accum): each pixel adds
// its path's radiance for the sample, in sample order, as the CPU render does.

#import render_types

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read> paths: array<PathGpu>;
@group(0) @binding(2) var<storage, read_write> sum: array<vec4<f32>>;

@compute @workgroup_size(64)
fn accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    sum[i] += vec4<f32>(paths[i].radiance, 0.0);
}
