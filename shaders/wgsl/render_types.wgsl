// The GPU renderer's structs. Each is declared once in Rust
// (`dirt_render::gpu::types`), and a test compares size and offsets with these
// declarations as naga sees them.

#import types

// No primitive: a surface that is not there (a miss), a shadow aimed at no triangle.
const NO_PRIM: u32 = 0xffffffffu;
// A path that sent no shadow ray this bounce.
const NO_SHADOW: u32 = 0xfffffffeu;
// dirt_gpu::trace::UNFINISHED and STRUCTURE_FULL: hits that are not hits.
const HIT_UNFINISHED: u32 = 0xfffffffeu;
const HIT_STRUCTURE_FULL: u32 = 0xfffffffdu;

// What every pass reads (dirt_render::gpu::types::RenderParams, 128 bytes).
struct RenderParams {
    eye: vec3<f32>,
    tan_half_fov: f32,
    forward: vec3<f32>,
    ortho_half_height: f32,
    up: vec3<f32>,
    orthographic: u32,
    right: vec3<f32>,
    offset: f32,
    environment: vec3<f32>,
    p_area: f32,
    // mix64(seed ^ golden ratio), (low, high) words: Sampler::new's first step.
    seed_mix: vec2<u32>,
    width: u32,
    height: u32,
    n_paths: u32,
    n_area: u32,
    n_punctual: u32,
    // Russian roulette from this bounce on; 0xffffffff: never.
    roulette_from: u32,
    n_tris: u32,
    n_materials: u32,
    // Mode::Ao: the length of the occlusion rays (Renderer::ao_radius).
    ao_radius: f32,
    pad1: u32,
}

// Written by the host before each sample, by the passes during it
// (dirt_render::gpu::types::RenderState, 32 bytes).
struct RenderState {
    sample: u32,
    bounce: u32,
    // Rays whose hits were not hits (UNFINISHED, STRUCTURE_FULL): nothing is silently dropped.
    bad_hits: atomic<u32>,
    // Valid rays handed to the trace this sample; `tally` adds them to (rays_lo, rays_hi).
    rays: atomic<u32>,
    rays_lo: u32,
    rays_hi: u32,
    // Primary rays whose rasterised candidate `direct_visibility` confirmed
    // this sample; `tally` adds them to (confirmed_lo, confirmed_hi).
    confirmed: atomic<u32>,
    confirmed_lo: u32,
    confirmed_hi: u32,
    // Valid rays `shift`'s `compact` packed for the trace being recorded.
    live: atomic<u32>,
}

// A triangle with everything fetch and the lights read (128 bytes).
struct TriGpu {
    p0: vec3<f32>,
    // Probability that next-event estimation picks this triangle among the area lights.
    light_prob: f32,
    p1: vec3<f32>,
    material: u32,
    p2: vec3<f32>,
    has_normals: u32,
    n0: vec3<f32>,
    has_uvs: u32,
    n1: vec3<f32>,
    pad0: u32,
    n2: vec3<f32>,
    pad1: u32,
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    pad2: vec2<f32>,
}

// dirt_scene::Material as shading reads it (48 bytes); texture NO_PRIM: none.
struct MaterialGpu {
    base: vec3<f32>,
    metallic: f32,
    emissive: vec3<f32>,
    roughness: f32,
    texture: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// A decoded texture's place in the texel array (16 bytes).
struct TextureGpu {
    offset: u32,
    width: u32,
    height: u32,
    pad: u32,
}

// An area light (kind 0) or a punctual one (1 point, 2 spot, 3 directional), 64 bytes.
// Area: `prim`, `area`, `cdf` (cumulative power), `color` its emission.
// Punctual: `color` is colour times intensity, `direction` unit, `range` 0 for none.
struct LightGpu {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    range: f32,
    color: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    prim: u32,
    area: f32,
    cdf: f32,
}

// One path of the shading buffer (80 bytes): throughput and radiance,
// G(k-1), and the sampling record of the ray that left G(k).
struct PathGpu {
    throughput: vec3<f32>,
    alive: u32,
    radiance: vec3<f32>,
    pdf: f32,
    prev: vec3<f32>,
    delta: u32,
    weight: vec3<f32>,
    scattered: u32,
    dir: vec3<f32>,
    pad: u32,
}

// A fetched surface point (dirt_render::fetch::SurfacePoint, 80 bytes); prim NO_PRIM: none.
struct SurfaceGpu {
    p: vec3<f32>,
    prim: u32,
    ng: vec3<f32>,
    front: u32,
    ns: vec3<f32>,
    metallic: f32,
    base: vec3<f32>,
    roughness: f32,
    emission: vec3<f32>,
    pad: u32,
}

// A shadow ray's payload (16 bytes); aim NO_SHADOW: no shadow ray.
struct ShadowGpu {
    contribution: vec3<f32>,
    aim: u32,
}

// The path a thread owns: one per pixel, over a 2-D grid of 64-wide workgroups.
fn path_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn finite1(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn finite3(v: vec3<f32>) -> bool {
    return finite1(v.x) & finite1(v.y) & finite1(v.z);
}

// glam's normalize_or_zero: v times the reciprocal of its length when that is finite and > 0.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let r = 1.0 / sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    if finite1(r) & (r > 0.0) {
        return v * r;
    }
    return vec3<f32>(0.0);
}

// glam's normalize (no check).
fn normalize_glam(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
}

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// dirt_math::Ray::validate as a predicate: the trace misses an invalid ray.
fn ray_valid(r: Ray) -> bool {
    let zero_dir = (r.dir.x == 0.0) & (r.dir.y == 0.0) & (r.dir.z == 0.0);
    let tmin_ok = (r.tmin >= 0.0) & finite1(r.tmin);
    let tmax_ok = (r.tmax == r.tmax) & (r.tmax >= r.tmin);
    return finite3(r.origin) & finite3(r.dir) & !zero_dir & tmin_ok & tmax_ok;
}

// A ray the trace misses at once: the slot of a path that sends none.
fn no_ray() -> Ray {
    return Ray(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0);
}

// A hit that is not one: a walk left unfinished, or a frame structure that
// was full. Whoever reads it counts it (state.bad_hits) and the render fails.
fn hit_unfinished(h: Hit) -> bool {
    return (h.prim == HIT_UNFINISHED) | (h.prim == HIT_STRUCTURE_FULL);
}
