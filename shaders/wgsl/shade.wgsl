// Stage `shade` of the GPU renderer (dirt_render::shade): the three-point
// form of light transport over the shading buffer. One entry point per step
// of a bounce, in the CPU renderer's order:
//   primary        — emission of G(1) towards the eye; the environment for a miss
//   next_event     — one light sample per live path at G(k): a shadow ray and its payload
//   apply_shadows  — the payloads of shadow rays that reached their light
//   sample_scatter — the BSDF sampled at G(k): the ray towards G(k+1)
//   scatter        — after G(k+1) is fetched: throughput, MIS-weighted emission, roulette
// and, for Mode::Ao instead of all of them:
//   ambient_occlusion — one cosine-distributed ray of ao_radius per primary hit
//   apply_occlusion   — white where that ray reached nothing
// Each path writes its ray in its own slot, an invalid one when it sends none;
// shift's `compact` packs the valid ones for the trace.

#import render_types
#import rng
#import bsdf

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read_write> paths: array<PathGpu>;
@group(0) @binding(3) var<storage, read> cur: array<SurfaceGpu>;
@group(0) @binding(4) var<storage, read> next: array<SurfaceGpu>;
@group(0) @binding(5) var<storage, read> tris: array<TriGpu>;
@group(0) @binding(6) var<storage, read> lights: array<LightGpu>;
@group(0) @binding(7) var<storage, read_write> rays: array<Ray>;
@group(0) @binding(8) var<storage, read_write> shadows: array<ShadowGpu>;
@group(0) @binding(9) var<storage, read> hits: array<Hit>;

#import lights

fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    return select(0.0, a2 / (a2 + b2), a2 + b2 > 0.0);
}

fn offset_origin(sp: SurfaceGpu) -> vec3<f32> {
    return sp.p + sp.ng * params.offset;
}

@compute @workgroup_size(64)
fn primary(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let sp = cur[i];
    if sp.prim != NO_PRIM {
        paths[i].radiance += sp.emission;
    } else {
        paths[i].radiance += params.environment;
        paths[i].alive = 0u;
    }
}

@compute @workgroup_size(64)
fn next_event(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    rays[i] = no_ray();
    shadows[i] = ShadowGpu(vec3<f32>(0.0), NO_SHADOW);
    let path = paths[i];
    let sp = cur[i];
    if (path.alive == 0u) | (sp.prim == NO_PRIM) | (params.n_area + params.n_punctual == 0u) {
        return;
    }
    let f = bsdf_of(sp);
    if f.kind == BSDF_MIRROR {
        return;
    }
    let bounce = state.bounce;
    let wo = normalize_or_zero(path.prev - sp.p);
    let key = sampler_key(params.seed_mix, i, state.sample);
    let ls = light_sample(rng_get(key, bounce, DIM_LIGHT_PICK), rng_get(key, bounce, DIM_LIGHT_U), rng_get(key, bounce, DIM_LIGHT_V));
    let origin = offset_origin(sp);
    var ray: Ray;
    var c: vec3<f32>;
    var aim = NO_PRIM;
    if ls.kind == LIGHT_AREA {
        let to = ls.point - sp.p;
        let d2 = dot3(to, to);
        let wi = normalize_or_zero(to);
        let cos_l = -dot3(ls.normal, wi);
        let cos_s = dot3(sp.ns, wi);
        if !((d2 > 0.0) & (cos_l > 0.0) & (cos_s > 0.0) & (dot3(sp.ng, wi) > 0.0)) {
            return;
        }
        let fv = bsdf_eval(f, sp.ns, wo, wi);
        let pdf_light = ls.pdf * d2 / cos_l;
        let w = power_heuristic(pdf_light, bsdf_pdf(f, sp.ns, wo, wi));
        c = ls.radiance * fv * (cos_s * w / pdf_light);
        ray = Ray(origin, 0.0, ls.point - origin, 1.0);
        aim = ls.index;
    } else if ls.kind == LIGHT_POINT {
        let to = ls.point - sp.p;
        let d2 = dot3(to, to);
        let wi = normalize_or_zero(to);
        let cos_s = dot3(sp.ns, wi);
        if !((d2 > 0.0) & (cos_s > 0.0) & (dot3(sp.ng, wi) > 0.0)) {
            return;
        }
        let k = punctual_factor(lights[params.n_area + ls.index], -wi, sqrt(d2));
        let fv = bsdf_eval(f, sp.ns, wo, wi);
        c = ls.radiance * fv * (k * cos_s / (d2 * ls.pdf));
        ray = Ray(origin, 0.0, ls.point - origin, 1.0);
    } else {
        let wi = -ls.normal;
        let cos_s = dot3(sp.ns, wi);
        if !((cos_s > 0.0) & (dot3(sp.ng, wi) > 0.0)) {
            return;
        }
        let fv = bsdf_eval(f, sp.ns, wo, wi);
        c = ls.radiance * fv * (cos_s / ls.pdf);
        ray = Ray(origin, 0.0, wi, f32_inf());
    }
    c = path.throughput * c;
    if !finite3(c) | all(c == vec3<f32>(0.0)) | !ray_valid(ray) {
        return;
    }
    rays[i] = ray;
    shadows[i] = ShadowGpu(c, aim);
    atomicAdd(&state.rays, 1u);
}

@compute @workgroup_size(64)
fn apply_shadows(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let s = shadows[i];
    if s.aim == NO_SHADOW {
        return;
    }
    let h = hits[i];
    if hit_unfinished(h) {
        atomicAdd(&state.bad_hits, 1u);
        return;
    }
    let missed = h.prim == NO_PRIM;
    let reached = (s.aim != NO_PRIM) & ((h.prim == s.aim) | (h.t >= 1.0 - 1.0 / 1024.0));
    if missed | reached {
        paths[i].radiance += s.contribution;
    }
}

@compute @workgroup_size(64)
fn sample_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    rays[i] = no_ray();
    paths[i].scattered = 0u;
    let path = paths[i];
    let sp = cur[i];
    if (path.alive == 0u) | (sp.prim == NO_PRIM) {
        paths[i].alive = 0u;
        return;
    }
    let bounce = state.bounce;
    let wo = normalize_or_zero(path.prev - sp.p);
    let key = sampler_key(params.seed_mix, i, state.sample);
    let b = bsdf_sample(bsdf_of(sp), sp.ns, sp.ng, wo, rng_get(key, bounce, DIM_LOBE), rng_get(key, bounce, DIM_DIR_U), rng_get(key, bounce, DIM_DIR_V));
    if !b.ok {
        paths[i].alive = 0u;
        return;
    }
    paths[i].dir = b.wi;
    paths[i].weight = b.weight;
    paths[i].pdf = b.pdf;
    paths[i].delta = u32(b.delta);
    paths[i].scattered = 1u;
    rays[i] = Ray(offset_origin(sp), 0.0, b.wi, f32_inf());
    atomicAdd(&state.rays, 1u);
}

@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    var path = paths[i];
    if path.alive == 0u {
        return;
    }
    let sp = cur[i];
    if (path.scattered == 0u) | (sp.prim == NO_PRIM) {
        paths[i].alive = 0u;
        return;
    }
    path.throughput *= path.weight;
    let nx = next[i];
    if nx.prim == NO_PRIM {
        path.radiance += path.throughput * params.environment;
        path.alive = 0u;
        paths[i] = path;
        return;
    }
    if any(nx.emission != vec3<f32>(0.0)) {
        var w = 1.0;
        if path.delta == 0u {
            let to = nx.p - sp.p;
            let d2 = dot3(to, to);
            let cos_l = abs(dot3(nx.ng, -path.dir));
            var pdf_light = 0.0;
            if cos_l > 0.0 {
                pdf_light = light_pdf_area(nx.prim) * d2 / cos_l;
            }
            w = power_heuristic(path.pdf, pdf_light);
        }
        path.radiance += path.throughput * nx.emission * w;
    }
    let bounce = state.bounce;
    if bounce >= params.roulette_from {
        let q = min(max(max(path.throughput.x, path.throughput.y), path.throughput.z), 0.95);
        let u = rng_get(sampler_key(params.seed_mix, i, state.sample), bounce, DIM_ROULETTE);
        if !(u < q) {
            path.alive = 0u;
            paths[i] = path;
            return;
        }
        path.throughput /= q;
    }
    paths[i] = path;
}

// Mode::Ao (dirt_render::integrator's ambient_occlusion): a pixel whose primary
// ray misses is white; a primary hit sends one cosine-distributed ray of
// ao_radius above its geometric side and is black unless that ray misses.
@compute @workgroup_size(64)
fn ambient_occlusion(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    rays[i] = no_ray();
    let sp = cur[i];
    if sp.prim == NO_PRIM {
        paths[i].radiance = vec3<f32>(1.0);
        return;
    }
    paths[i].radiance = vec3<f32>(0.0);
    let key = sampler_key(params.seed_mix, i, state.sample);
    let d = cosine_sample(sp.ns, rng_get(key, 1u, DIM_DIR_U), rng_get(key, 1u, DIM_DIR_V));
    if dot(d, sp.ng) > 0.0 {
        rays[i] = Ray(offset_origin(sp), 0.0, d, params.ao_radius);
        atomicAdd(&state.rays, 1u);
    }
}

@compute @workgroup_size(64)
fn apply_occlusion(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    if !ray_valid(rays[i]) {
        return;
    }
    let h = hits[i];
    if hit_unfinished(h) {
        atomicAdd(&state.bad_hits, 1u);
        return;
    }
    if h.prim == NO_PRIM {
        paths[i].radiance = vec3<f32>(1.0);
    }
}
