// Stage `camera` of the GPU renderer (dirt_render::camera): one jittered
// primary ray per pixel, and the path it starts (throughput 1, no radiance,
// G(0) the ray's origin).

#import render_types
#import rng

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read_write> rays: array<Ray>;
@group(0) @binding(3) var<storage, read_write> paths: array<PathGpu>;

// Camera::ray: the ray through image point (x, y) in pixels.
fn camera_ray(x: f32, y: f32) -> Ray {
    let w = f32(params.width);
    let h = f32(params.height);
    let aspect = w / h;
    let sx = (x / w) * 2.0 - 1.0;
    let sy = 1.0 - (y / h) * 2.0;
    if params.orthographic == 0u {
        let dir = params.forward + params.right * (sx * params.tan_half_fov * aspect)
            + params.up * (sy * params.tan_half_fov);
        return Ray(params.eye, 0.0, normalize_glam(dir), f32_inf());
    }
    let hh = params.ortho_half_height;
    let o = params.eye + params.right * (sx * hh * aspect) + params.up * (sy * hh);
    return Ray(o, 0.0, params.forward, f32_inf());
}

@compute @workgroup_size(64)
fn camera(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let key = sampler_key(params.seed_mix, i, state.sample);
    let x = f32(i % params.width) + rng_get(key, 0u, DIM_PIXEL_X);
    let y = f32(i / params.width) + rng_get(key, 0u, DIM_PIXEL_Y);
    let ray = camera_ray(x, y);
    rays[i] = ray;
    if ray_valid(ray) {
        atomicAdd(&state.rays, 1u);
    }
    paths[i] = PathGpu(vec3<f32>(1.0), 1u, vec3<f32>(0.0), 0.0, ray.origin, 0u, vec3<f32>(0.0), 0u, vec3<f32>(0.0), 0u);
}
