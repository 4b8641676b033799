//! The deferred path tracer on the GPU (001 §4.2): this crate's stages as
//! WGSL passes over a shading buffer that never leaves the GPU.
//!
//! One sample is one command encoder and one submission: `camera` writes the
//! primary rays, `direct_visibility`'s `confirm` limits each to its pixel's
//! rasterised candidate when the exact test hits it, then DIRT's `trace`
//! (`dirt_gpu::TraceResources`, the same passes `DirtGpu` runs),
//! `direct_visibility`'s `settle` (the closer of candidate and trace),
//! `fetch`, and per bounce `shade`'s steps
//! (`next_event`, the shadow trace, `apply_shadows`, `sample_scatter`, the
//! trace, `fetch`, `scatter`) and `shift` — or, for `Mode::Ao`,
//! `ambient_occlusion`, the occlusion trace and `apply_occlusion`; `accum`
//! adds the sample to the image. The host writes 8 bytes before each sample
//! (its number) and reads the image back once, at the end — or never: a
//! window or canvas presents [`GpuRenderer::sums`] where they lie
//! ([`GpuRenderer::add_sample`], then [`output`]'s pass). The candidates are the CPU rasteriser's
//! ([`Renderer::raster`], made once per camera), uploaded with the scene; a
//! camera that rasterises nothing (orthographic) leaves the stage out.
//!
//! Random numbers are the CPU renderer's bit for bit (`rng.wgsl`: integer
//! arithmetic only) and the hits are DIRT's, which equal the CPU's bit for bit
//! on an exact device; shading uses the GPU's `sqrt`, `sin`, `cos` and
//! division, so images agree with the CPU renderer's to rounding (a path whose
//! rounding flips a decision — a roulette draw, a ray grazing an edge — goes
//! its own way), not to the bit.
//!
//! In a browser page, which cannot block: [`GpuRenderer::add_sample`] and
//! [`GpuRenderer::mean_async`] ([`GpuRenderer::render`] and
//! [`GpuRenderer::counters`] block on their read-back).
//! Each secondary trace runs on the live rays packed to the front of its ray
//! buffer (`shift`'s `compact` and `expand`, an atomic counter,
//! `RenderState::live`); the counter sizes the trace's first dispatch
//! (`TraceResources::encode_trace_counted`, indirect), and its continuation
//! rounds are indirect too: nothing is dispatched for a path that has ended.

pub mod output;
pub mod types;

use crate::direct_visibility::VisibilityStats;
use crate::{Image, Mode, RenderError, Rendered, Renderer};
use dirt_core::Traversal;
use dirt_gpu::{Gpu, GpuAds, GpuError, TraceResources, wgpu};
use dirt_math::{Hit, Ray, Vec3};
use dirt_scene::LightKind;
use std::time::Duration;
use types::*;
use web_time::Instant;

/// Continuation rounds recorded after each trace's first dispatch: the
/// renderer cannot look at the pool between traces, so it records enough
/// for the walks of the scenes it was measured on; a ray still unfinished
/// after them is counted and the render fails (nothing silently dropped).
pub const TRACE_ROUNDS: u32 = 8;

const STATE_BYTES: u64 = std::mem::size_of::<RenderState>() as u64;
const LIVE_OFFSET: u64 = std::mem::offset_of!(RenderState, live) as u64;

/// Which trace of a sample a [`TraceRecord`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceKind {
    Primary,
    Shadow {
        bounce: u32,
    },
    Scatter {
        bounce: u32,
    },
    /// `Mode::Ao`'s occlusion rays.
    Occlusion,
}

/// One trace of the GPU renderer, read back (tests only: each costs a
/// submission and a wait).
#[derive(Clone, Debug)]
pub struct TraceRecord {
    pub sample: u32,
    pub kind: TraceKind,
    pub rays: Vec<Ray>,
    pub hits: Vec<Hit>,
}

/// Host↔GPU traffic of a render, counted by the renderer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Transfers {
    /// Command buffers submitted.
    pub submissions: u32,
    /// Buffers read back (each a wait for the GPU).
    pub read_backs: u32,
    /// Bytes written to the GPU after the scene was uploaded.
    pub bytes_written: u64,
    /// Bytes read back.
    pub bytes_read: u64,
}

impl Transfers {
    /// What was added since `before` (an earlier reading of the same renderer).
    pub fn since(self, before: Transfers) -> Transfers {
        Transfers {
            submissions: self.submissions - before.submissions,
            read_backs: self.read_backs - before.read_backs,
            bytes_written: self.bytes_written - before.bytes_written,
            bytes_read: self.bytes_read - before.bytes_read,
        }
    }
}

struct Pipelines {
    camera: wgpu::ComputePipeline,
    /// `direct_visibility`'s `confirm` and `settle`, with their bind group;
    /// none when the raster proposes nothing.
    direct_visibility: Option<DirectVisibility>,
    fetch: wgpu::ComputePipeline,
    primary: wgpu::ComputePipeline,
    next_event: wgpu::ComputePipeline,
    apply_shadows: wgpu::ComputePipeline,
    sample_scatter: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    ambient_occlusion: wgpu::ComputePipeline,
    apply_occlusion: wgpu::ComputePipeline,
    shift: wgpu::ComputePipeline,
    advance: wgpu::ComputePipeline,
    tally: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    expand: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
}

fn pipeline(gpu: &Gpu, m: &wgpu::ShaderModule, entry: &str) -> wgpu::ComputePipeline {
    gpu.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: m,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
}

/// Stage `direct_visibility` on the GPU: its pipelines (compiled exactly,
/// as DIRT's passes are) and the buffers only it reads.
struct DirectVisibility {
    confirm: wgpu::ComputePipeline,
    settle: wgpu::ComputePipeline,
    raster: wgpu::Buffer,
    candidates: wgpu::Buffer,
}

impl DirectVisibility {
    /// `None` when `r`'s raster proposes no primitive anywhere.
    fn new(gpu: &Gpu, r: &Renderer<'_>, n: u32) -> Result<Option<Self>, GpuError> {
        let prim = &r.raster.prim;
        if prim.len() != n as usize || prim.iter().all(|&p| p == dirt_math::INVALID_ID) {
            return Ok(None);
        }
        let [confirm, settle]: [wgpu::ComputePipeline; 2] =
            dirt_gpu::exact_compute_pipelines(gpu, "direct_visibility", &["confirm", "settle"])?
                .try_into()
                .map_err(|_| GpuError::Shader {
                    stage: "direct_visibility",
                    message: "expected two pipelines".into(),
                })?;
        Ok(Some(Self {
            confirm,
            settle,
            raster: storage(gpu, "raster", prim, wgpu::BufferUsages::COPY_DST),
            candidates: zeroed(
                gpu,
                "candidates",
                u64::from(n) * 16,
                wgpu::BufferUsages::empty(),
            ),
        }))
    }
}

impl Pipelines {
    fn new(gpu: &Gpu, r: &Renderer<'_>, n: u32) -> Result<Self, GpuError> {
        let camera = dirt_gpu::wgsl_module(gpu, "camera")?;
        let fetch = dirt_gpu::wgsl_module(gpu, "fetch")?;
        let shade = dirt_gpu::wgsl_module(gpu, "shade")?;
        let shift = dirt_gpu::wgsl_module(gpu, "shift")?;
        let accum = dirt_gpu::wgsl_module(gpu, "accum")?;
        Ok(Self {
            camera: pipeline(gpu, &camera, "camera"),
            direct_visibility: DirectVisibility::new(gpu, r, n)?,
            fetch: pipeline(gpu, &fetch, "fetch"),
            primary: pipeline(gpu, &shade, "primary"),
            next_event: pipeline(gpu, &shade, "next_event"),
            apply_shadows: pipeline(gpu, &shade, "apply_shadows"),
            sample_scatter: pipeline(gpu, &shade, "sample_scatter"),
            scatter: pipeline(gpu, &shade, "scatter"),
            ambient_occlusion: pipeline(gpu, &shade, "ambient_occlusion"),
            apply_occlusion: pipeline(gpu, &shade, "apply_occlusion"),
            shift: pipeline(gpu, &shift, "shift"),
            advance: pipeline(gpu, &shift, "advance"),
            tally: pipeline(gpu, &shift, "tally"),
            compact: pipeline(gpu, &shift, "compact"),
            expand: pipeline(gpu, &shift, "expand"),
            accumulate: pipeline(gpu, &accum, "accumulate"),
        })
    }
}

/// A storage buffer holding `data`, or one zeroed element when it is empty
/// (a binding cannot be empty).
fn storage<T: bytemuck::Pod + Default>(
    gpu: &Gpu,
    label: &str,
    data: &[T],
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let one = [T::default()];
    let data = if data.is_empty() { &one[..] } else { data };
    // Not `create_buffer_init`: it panics on a lost device.
    dirt_gpu::buffer_init(
        gpu,
        label,
        bytemuck::cast_slice(data),
        wgpu::BufferUsages::STORAGE | extra,
    )
}

fn zeroed(gpu: &Gpu, label: &str, bytes: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | extra,
        mapped_at_creation: false,
    })
}

/// A sample's error as `Gpu::scoped` carries it out of its scope.
fn inside_scope(e: RenderError) -> GpuError {
    match e {
        RenderError::Gpu(g) => g,
        other => GpuError::Device(other.to_string()),
    }
}

/// The counters in `bytes` (read back from the state buffer). Hits that were
/// not hits make the image wrong: an error, never an image.
fn counters_of(bytes: &[u8]) -> Result<RenderState, RenderError> {
    let Some(bytes) = bytes.get(..STATE_BYTES as usize) else {
        return Err(RenderError::Gpu(GpuError::Readback(format!(
            "{} bytes read back for {STATE_BYTES} of counters",
            bytes.len()
        ))));
    };
    let state: RenderState = bytemuck::pod_read_unaligned(bytes);
    if state.bad_hits > 0 {
        return Err(RenderError::Gpu(GpuError::Device(format!(
            "{} hits of the render were not finished walks ({TRACE_ROUNDS} continuation rounds per trace were not enough, or a frame structure was full): the image would be wrong",
            state.bad_hits
        ))));
    }
    Ok(state)
}

/// The scene as the passes read it.
struct SceneBuffers {
    tris: wgpu::Buffer,
    materials: wgpu::Buffer,
    textures: wgpu::Buffer,
    texels: wgpu::Buffer,
    lights: wgpu::Buffer,
    n_area: u32,
    n_punctual: u32,
    n_materials: u32,
}

fn tri_gpu(r: &Renderer<'_>) -> Vec<TriGpu> {
    let s = r.scene;
    s.triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut g = TriGpu {
                p0: t.v[0],
                p1: t.v[1],
                p2: t.v[2],
                light_prob: r.lights.prim_prob(i as u32),
                material: s.tri_material.get(i).copied().unwrap_or(NO_PRIM),
                ..TriGpu::default()
            };
            if let Some(n) = s.tri_normals.as_ref().and_then(|n| n.get(i)) {
                g.has_normals = 1;
                (g.n0, g.n1, g.n2) = (n[0], n[1], n[2]);
            }
            if let Some(uv) = s.tri_uvs.as_ref().and_then(|u| u.get(i)) {
                g.has_uvs = 1;
                (g.uv0, g.uv1, g.uv2) = (uv[0], uv[1], uv[2]);
            }
            g
        })
        .collect()
}

/// The lights as `shade` reads them: the area lights (with their CDF), then
/// the punctual ones.
fn light_table(r: &Renderer<'_>) -> Vec<LightGpu> {
    let (s, l) = (r.scene, &r.lights);
    let mut lights: Vec<LightGpu> = l
        .area
        .iter()
        .zip(l.cdf())
        .map(|(a, &cdf)| LightGpu {
            kind: 0,
            color: s
                .material_of(a.prim as usize)
                .map_or([0.0; 3], |m| m.emissive),
            prim: a.prim,
            area: a.area,
            cdf,
            ..LightGpu::default()
        })
        .collect();
    lights.extend(l.punctual.iter().map(|p| {
        let (kind, direction, cos_inner, cos_outer) = match p.kind {
            LightKind::Point => (1, p.direction, 1.0, 1.0),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => (
                2,
                p.direction.normalize_or(Vec3::NEG_Z),
                inner_cone.cos(),
                outer_cone.cos(),
            ),
            LightKind::Directional => (3, p.direction.normalize_or(Vec3::NEG_Y), 1.0, 1.0),
        };
        LightGpu {
            position: p.position.to_array(),
            kind,
            direction: direction.to_array(),
            range: p.range.filter(|r| *r > 0.0).unwrap_or(0.0),
            color: (Vec3::from_array(p.color) * p.intensity).to_array(),
            cos_inner,
            cos_outer,
            ..LightGpu::default()
        }
    }));
    lights
}

impl SceneBuffers {
    fn new(gpu: &Gpu, r: &Renderer<'_>) -> Self {
        let s = r.scene;
        // The textures `fetch` decoded (the used ones), packed one after another.
        let mut table = Vec::new();
        let mut texels: Vec<[f32; 4]> = Vec::new();
        let mut index = vec![NO_PRIM; r.fetcher.textures.len()];
        for (k, t) in r.fetcher.textures.iter().enumerate() {
            if let Some(t) = t {
                index[k] = table.len() as u32;
                table.push(TextureGpu {
                    offset: texels.len() as u32,
                    width: t.width,
                    height: t.height,
                    pad: 0,
                });
                texels.extend(t.texels.iter().map(|v| v.to_array()));
            }
        }
        let materials: Vec<MaterialGpu> = s
            .materials
            .iter()
            .map(|m| MaterialGpu {
                base: [m.base_color[0], m.base_color[1], m.base_color[2]],
                metallic: m.metallic,
                emissive: m.emissive,
                roughness: m.roughness,
                texture: m
                    .base_color_texture
                    .and_then(|t| index.get(t as usize).copied())
                    .unwrap_or(NO_PRIM),
                ..MaterialGpu::default()
            })
            .collect();
        let l = &r.lights;
        let lights = light_table(r);
        Self {
            tris: storage(
                gpu,
                "render triangles",
                &tri_gpu(r),
                wgpu::BufferUsages::COPY_DST,
            ),
            materials: storage(gpu, "materials", &materials, wgpu::BufferUsages::empty()),
            textures: storage(gpu, "textures", &table, wgpu::BufferUsages::empty()),
            texels: storage(gpu, "texels", &texels, wgpu::BufferUsages::empty()),
            lights: storage(gpu, "lights", &lights, wgpu::BufferUsages::COPY_DST),
            n_area: l.area.len() as u32,
            n_punctual: l.punctual.len() as u32,
            n_materials: materials.len() as u32,
        }
    }
}

/// The bind groups of every pass (the buffers never change during a render).
struct Binds {
    camera: wgpu::BindGroup,
    direct_visibility: Option<wgpu::BindGroup>,
    fetch_cur: wgpu::BindGroup,
    fetch_next: wgpu::BindGroup,
    primary: wgpu::BindGroup,
    next_event: wgpu::BindGroup,
    apply_shadows: wgpu::BindGroup,
    sample_scatter: wgpu::BindGroup,
    scatter: wgpu::BindGroup,
    ambient_occlusion: wgpu::BindGroup,
    apply_occlusion: wgpu::BindGroup,
    shift: wgpu::BindGroup,
    advance: wgpu::BindGroup,
    tally: wgpu::BindGroup,
    compact: wgpu::BindGroup,
    expand: wgpu::BindGroup,
    accumulate: wgpu::BindGroup,
}

fn bind(gpu: &Gpu, p: &wgpu::ComputePipeline, entries: &[(u32, &wgpu::Buffer)]) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = entries
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &p.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// The deferred path tracer on the GPU for one [`Renderer`] (scene, camera,
/// settings): its buffers and pipelines, made once, reused by every
/// [`GpuRenderer::render`].
pub struct GpuRenderer<'g> {
    gpu: &'g Gpu,
    pipelines: Pipelines,
    binds: Binds,
    trace: TraceResources,
    /// What `params` holds (the camera is rewritten by [`GpuRenderer::set_camera`]).
    params_value: RenderParams,
    params: wgpu::Buffer,
    /// The scene's tables (rewritten by [`GpuRenderer::set_scene`]).
    scene: SceneBuffers,
    n: u32,
    grid: [u32; 3],
    bounces: u32,
    has_lights: bool,
    /// `Mode::Ao`: one occlusion ray per primary hit instead of the bounces.
    ao: bool,
    spp: u32,
    width: u32,
    height: u32,
    state: wgpu::Buffer,
    rays: wgpu::Buffer,
    hits: wgpu::Buffer,
    trace_rays: wgpu::Buffer,
    trace_hits: wgpu::Buffer,
    sum: wgpu::Buffer,
    transfers: Transfers,
}

impl std::fmt::Debug for GpuRenderer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuRenderer")
            .field("paths", &self.n)
            .field("bounces", &self.bounces)
            .finish_non_exhaustive()
    }
}

impl<'g> GpuRenderer<'g> {
    /// Uploads `r`'s scene, lights and decoded textures and makes the
    /// shading buffer for its image.
    pub fn new(gpu: &'g Gpu, r: &Renderer<'_>) -> Result<Self, RenderError> {
        let s = &r.settings;
        let n64 = u64::from(s.width) * u64::from(s.height);
        let max_paths = TraceResources::max_rays(gpu).min(u32::MAX / 2);
        let biggest = std::mem::size_of::<PathGpu>() as u64 * n64;
        if n64 > u64::from(max_paths) || biggest > gpu.limits.max_storage_buffer_binding_size {
            return Err(RenderError::Gpu(GpuError::TooLarge {
                what: "the GPU renderer's shading buffer",
                bytes: biggest,
                limit: gpu.limits.max_storage_buffer_binding_size,
            }));
        }
        let n = n64 as u32;
        let (bounces, roulette_from) = match s.mode {
            Mode::Direct => (1, None),
            // One occlusion ray after the primary hit, no bounce.
            Mode::Ao => (0, None),
            _ => (s.bounces, s.russian_roulette),
        };
        gpu.scoped("the GPU renderer's set-up", || {
            let pipelines = Pipelines::new(gpu, r, n)?;
            let scene = SceneBuffers::new(gpu, r);
            let seed = crate::rng::seed_mix(s.seed);
            let mut params = RenderParams {
                offset: r.offset,
                environment: r.environment.to_array(),
                p_area: r.lights.p_area,
                seed_mix: [seed as u32, (seed >> 32) as u32],
                width: s.width,
                height: s.height,
                n_paths: n,
                n_area: scene.n_area,
                n_punctual: scene.n_punctual,
                roulette_from: roulette_from.unwrap_or(u32::MAX),
                n_tris: r.scene.triangles.len() as u32,
                n_materials: scene.n_materials,
                ao_radius: r.ao_radius,
                ..RenderParams::default()
            };
            params.set_camera(&r.camera);
            let params_value = params;
            let params = dirt_gpu::buffer_init(
                gpu,
                "render params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            );
            let n64 = u64::from(n);
            let copy = wgpu::BufferUsages::COPY_SRC;
            let state = zeroed(
                gpu,
                "render state",
                STATE_BYTES,
                wgpu::BufferUsages::COPY_DST | copy,
            );
            let rays = zeroed(gpu, "render rays", n64 * 32, copy);
            let hits = zeroed(gpu, "render hits", n64 * 16, copy);
            let paths = zeroed(gpu, "paths", n64 * 80, copy);
            let cur = zeroed(gpu, "G(k)", n64 * 80, copy);
            let next = zeroed(gpu, "G(k+1)", n64 * 80, copy);
            let shadows = zeroed(gpu, "shadows", n64 * 16, copy);
            // The secondary traces' packed rays and hits (`shift`'s `compact`).
            let trace_rays = zeroed(gpu, "packed rays", n64 * 32, copy);
            let trace_hits = zeroed(gpu, "packed hits", n64 * 16, copy);
            let slot_path = zeroed(gpu, "packed ray paths", n64 * 4, copy);
            let sum = zeroed(
                gpu,
                "radiance sum",
                n64 * 16,
                copy | wgpu::BufferUsages::COPY_DST,
            );
            let p = &pipelines;
            let sc = &scene;
            let fetch = |out: &wgpu::Buffer| {
                bind(
                    gpu,
                    &p.fetch,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &rays),
                        (3, &hits),
                        (4, &sc.tris),
                        (5, &sc.materials),
                        (6, &sc.textures),
                        (7, &sc.texels),
                        (8, out),
                    ],
                )
            };
            let binds = Binds {
                camera: bind(
                    gpu,
                    &p.camera,
                    &[(0, &params), (1, &state), (2, &rays), (3, &paths)],
                ),
                direct_visibility: p.direct_visibility.as_ref().map(|d| {
                    // `confirm` and `settle` share one layout.
                    bind(
                        gpu,
                        &d.confirm,
                        &[
                            (0, &params),
                            (1, &state),
                            (2, &rays),
                            (3, &hits),
                            (4, &d.raster),
                            (5, &sc.tris),
                            (6, &d.candidates),
                        ],
                    )
                }),
                fetch_cur: fetch(&cur),
                fetch_next: fetch(&next),
                primary: bind(gpu, &p.primary, &[(0, &params), (2, &paths), (3, &cur)]),
                next_event: bind(
                    gpu,
                    &p.next_event,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (3, &cur),
                        (5, &sc.tris),
                        (6, &sc.lights),
                        (7, &rays),
                        (8, &shadows),
                    ],
                ),
                apply_shadows: bind(
                    gpu,
                    &p.apply_shadows,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (8, &shadows),
                        (9, &hits),
                    ],
                ),
                ambient_occlusion: bind(
                    gpu,
                    &p.ambient_occlusion,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (3, &cur),
                        (7, &rays),
                    ],
                ),
                apply_occlusion: bind(
                    gpu,
                    &p.apply_occlusion,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (7, &rays),
                        (9, &hits),
                    ],
                ),
                sample_scatter: bind(
                    gpu,
                    &p.sample_scatter,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (3, &cur),
                        (7, &rays),
                    ],
                ),
                scatter: bind(
                    gpu,
                    &p.scatter,
                    &[
                        (0, &params),
                        (1, &state),
                        (2, &paths),
                        (3, &cur),
                        (4, &next),
                        (5, &sc.tris),
                    ],
                ),
                shift: bind(
                    gpu,
                    &p.shift,
                    &[(0, &params), (2, &paths), (3, &cur), (4, &next)],
                ),
                advance: bind(gpu, &p.advance, &[(1, &state)]),
                tally: bind(gpu, &p.tally, &[(1, &state)]),
                compact: bind(
                    gpu,
                    &p.compact,
                    &[
                        (0, &params),
                        (1, &state),
                        (5, &rays),
                        (6, &hits),
                        (7, &trace_rays),
                        (9, &slot_path),
                    ],
                ),
                expand: bind(
                    gpu,
                    &p.expand,
                    &[(1, &state), (6, &hits), (8, &trace_hits), (9, &slot_path)],
                ),
                accumulate: bind(gpu, &p.accumulate, &[(0, &params), (1, &paths), (2, &sum)]),
            };
            let groups = n.div_ceil(64);
            let x = groups.clamp(1, gpu.limits.max_compute_workgroups_per_dimension);
            let mut trace = TraceResources::new(gpu);
            trace.rounds = TRACE_ROUNDS;
            Ok(Self {
                gpu,
                pipelines,
                binds,
                trace,
                params_value,
                params,
                scene,
                n,
                grid: [x, groups.div_ceil(x), 1],
                bounces,
                has_lights: !r.lights.is_empty(),
                ao: s.mode == Mode::Ao,
                spp: s.spp,
                width: s.width,
                height: s.height,
                state,
                rays,
                hits,
                trace_rays,
                trace_hits,
                sum,
                transfers: Transfers::default(),
            })
        })
        .map_err(RenderError::from)
    }

    /// What this renderer has submitted and read back so far.
    pub fn transfers(&self) -> Transfers {
        self.transfers
    }

    fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        p: &wgpu::ComputePipeline,
        b: &wgpu::BindGroup,
        grid: [u32; 3],
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: None,
        });
        pass.set_pipeline(p);
        pass.set_bind_group(0, b, &[]);
        pass.dispatch_workgroups(grid[0], grid[1], grid[2]);
    }

    fn submit(&mut self, enc: wgpu::CommandEncoder) {
        self.gpu.submit(enc);
        self.transfers.submissions += 1;
    }

    fn read(&mut self, buf: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
        self.transfers.read_backs += 1;
        self.transfers.bytes_read += bytes;
        dirt_gpu::read_back(self.gpu, buf, 0, bytes)
    }

    /// [`GpuRenderer::read`] without blocking (a browser page awaits it).
    async fn read_async(&mut self, buf: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
        self.transfers.read_backs += 1;
        self.transfers.bytes_read += bytes;
        dirt_gpu::read_back_async(self.gpu, buf, 0, bytes).await
    }

    /// Records the trace of the ray buffer into the hit buffer; with
    /// `inspect`, submits what is recorded so far and reads both back.
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        ads: &GpuAds,
        traversal: Traversal,
        sample: u32,
        kind: TraceKind,
        inspect: &mut Option<&mut dyn FnMut(TraceRecord)>,
    ) -> Result<(), RenderError> {
        let (p, b, g) = (&self.pipelines, &self.binds, self.grid);
        if kind == TraceKind::Primary {
            // Every path has a primary ray: nothing to pack.
            self.trace.encode_trace(
                self.gpu, enc, ads, &self.rays, &self.hits, None, self.n, traversal,
            )?;
            if let (Some(d), Some(b)) = (&p.direct_visibility, &b.direct_visibility) {
                self.dispatch(enc, &d.settle, b, g);
            }
        } else {
            // The live rays packed to the front and counted; the count
            // sizes the trace's first dispatch.
            enc.clear_buffer(&self.state, LIVE_OFFSET, Some(4));
            self.dispatch(enc, &p.compact, &b.compact, g);
            self.trace.encode_trace_counted(
                self.gpu,
                enc,
                ads,
                &self.trace_rays,
                &self.trace_hits,
                None,
                self.n,
                (&self.state, LIVE_OFFSET),
                traversal,
            )?;
            self.dispatch(enc, &p.expand, &b.expand, g);
        }
        if let Some(f) = inspect.as_mut() {
            let done = std::mem::replace(
                enc,
                self.gpu.device.create_command_encoder(&Default::default()),
            );
            self.submit(done);
            let n = u64::from(self.n);
            let rays = bytemuck::pod_collect_to_vec(&self.read(&self.rays.clone(), n * 32)?);
            let hits = bytemuck::pod_collect_to_vec(&self.read(&self.hits.clone(), n * 16)?);
            f(TraceRecord {
                sample,
                kind,
                rays,
                hits,
            });
        }
        Ok(())
    }

    /// Records and submits sample `sample` of every pixel.
    fn sample(
        &mut self,
        ads: &GpuAds,
        traversal: Traversal,
        sample: u32,
        inspect: &mut Option<&mut dyn FnMut(TraceRecord)>,
    ) -> Result<(), RenderError> {
        self.gpu
            .queue
            .write_buffer(&self.state, 0, bytemuck::cast_slice(&[sample, 0u32]));
        self.transfers.bytes_written += 8;
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        let (p, b, g) = (&self.pipelines, &self.binds, self.grid);
        self.dispatch(&mut enc, &p.camera, &b.camera, g);
        if let (Some(d), Some(b)) = (&p.direct_visibility, &b.direct_visibility) {
            self.dispatch(&mut enc, &d.confirm, b, g);
        }
        self.trace(
            &mut enc,
            ads,
            traversal,
            sample,
            TraceKind::Primary,
            inspect,
        )?;
        let (p, b) = (&self.pipelines, &self.binds);
        self.dispatch(&mut enc, &p.fetch, &b.fetch_cur, g);
        if self.ao {
            self.dispatch(&mut enc, &p.ambient_occlusion, &b.ambient_occlusion, g);
            self.trace(
                &mut enc,
                ads,
                traversal,
                sample,
                TraceKind::Occlusion,
                inspect,
            )?;
            let (p, b) = (&self.pipelines, &self.binds);
            self.dispatch(&mut enc, &p.apply_occlusion, &b.apply_occlusion, g);
        } else {
            self.dispatch(&mut enc, &p.primary, &b.primary, g);
        }
        for bounce in 1..=self.bounces {
            let (p, b) = (&self.pipelines, &self.binds);
            self.dispatch(&mut enc, &p.advance, &b.advance, [1, 1, 1]);
            if self.has_lights {
                self.dispatch(&mut enc, &p.next_event, &b.next_event, g);
                self.trace(
                    &mut enc,
                    ads,
                    traversal,
                    sample,
                    TraceKind::Shadow { bounce },
                    inspect,
                )?;
                let (p, b) = (&self.pipelines, &self.binds);
                self.dispatch(&mut enc, &p.apply_shadows, &b.apply_shadows, g);
            }
            let (p, b) = (&self.pipelines, &self.binds);
            self.dispatch(&mut enc, &p.sample_scatter, &b.sample_scatter, g);
            self.trace(
                &mut enc,
                ads,
                traversal,
                sample,
                TraceKind::Scatter { bounce },
                inspect,
            )?;
            let (p, b) = (&self.pipelines, &self.binds);
            self.dispatch(&mut enc, &p.fetch, &b.fetch_next, g);
            self.dispatch(&mut enc, &p.scatter, &b.scatter, g);
            self.dispatch(&mut enc, &p.shift, &b.shift, g);
        }
        let (p, b) = (&self.pipelines, &self.binds);
        self.dispatch(&mut enc, &p.accumulate, &b.accumulate, g);
        self.dispatch(&mut enc, &p.tally, &b.tally, [1, 1, 1]);
        self.submit(enc);
        Ok(())
    }

    /// Starts the image over: the sums and the counters cleared (recorded
    /// and submitted, not waited for).
    pub fn restart(&mut self) {
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.sum, 0, None);
        enc.clear_buffer(&self.state, 0, None);
        self.submit(enc);
    }

    /// Adds sample `sample` of every pixel to the sums on the GPU (one
    /// submission, not waited for): the progressive form of
    /// [`GpuRenderer::render`], for a window or canvas that presents
    /// [`GpuRenderer::sums`] without reading them back.
    pub fn add_sample(
        &mut self,
        ads: &GpuAds,
        traversal: Traversal,
        sample: u32,
    ) -> Result<(), RenderError> {
        let gpu = self.gpu;
        gpu.scoped("a GPU sample", || {
            self.sample(ads, traversal, sample, &mut None)
                .map_err(inside_scope)
        })
        .map_err(RenderError::from)
    }

    /// Each pixel's radiance summed over the samples added since the last
    /// restart: `width·height` `vec4<f32>` (rgb, and 0), rows top to bottom,
    /// `STORAGE` usage.
    pub fn sums(&self) -> &wgpu::Buffer {
        &self.sum
    }

    /// Points the camera of `r` (the same scene and settings as this
    /// renderer's) and starts the image over: 128 bytes of parameters and the
    /// raster's candidates are written, nothing is compiled or made again.
    pub fn set_camera(&mut self, r: &Renderer<'_>) -> Result<(), RenderError> {
        let s = &r.settings;
        if (s.width, s.height) != (self.width, self.height) {
            return Err(RenderError::Unsupported(format!(
                "a new camera for a {}x{} image on a {}x{} renderer: make a new one",
                s.width, s.height, self.width, self.height
            )));
        }
        self.params_value.set_camera(&r.camera);
        self.gpu
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&self.params_value));
        self.transfers.bytes_written += std::mem::size_of::<RenderParams>() as u64;
        if let Some(d) = &self.pipelines.direct_visibility {
            // A camera that rasterises nothing proposes no candidate: every ray is traced in full.
            let none;
            let prim = if r.raster.prim.len() == self.n as usize {
                &r.raster.prim
            } else {
                none = vec![dirt_math::INVALID_ID; self.n as usize];
                &none
            };
            self.gpu
                .queue
                .write_buffer(&d.raster, 0, bytemuck::cast_slice(prim));
            self.transfers.bytes_written += 4 * u64::from(self.n);
        }
        self.restart();
        Ok(())
    }

    /// Another pose of the scene this renderer was made for (the same
    /// triangles, materials and lights, moved: an animation's next frame),
    /// seen by `r`'s camera: the triangle and light tables, the scene's
    /// parameters and the candidates are written, nothing is compiled or
    /// made again, and the image starts over. A pose with another triangle
    /// or light count is refused ([`RenderError::Unsupported`]: make a new
    /// renderer).
    pub fn set_scene(&mut self, r: &Renderer<'_>) -> Result<(), RenderError> {
        let tris = tri_gpu(r);
        let lights = light_table(r);
        let counts = (
            tris.len(),
            r.lights.area.len() as u32,
            r.lights.punctual.len() as u32,
        );
        let p = &self.params_value;
        if counts != (p.n_tris as usize, p.n_area, p.n_punctual) {
            return Err(RenderError::Unsupported(format!(
                "a pose with {} triangles and {}+{} lights on a renderer made for {} and {}+{}: make a new one",
                counts.0, counts.1, counts.2, p.n_tris, p.n_area, p.n_punctual
            )));
        }
        let q = &self.gpu.queue;
        q.write_buffer(&self.scene.tris, 0, bytemuck::cast_slice(&tris));
        if !lights.is_empty() {
            q.write_buffer(&self.scene.lights, 0, bytemuck::cast_slice(&lights));
        }
        self.transfers.bytes_written += (std::mem::size_of::<TriGpu>() * tris.len()
            + std::mem::size_of::<LightGpu>() * lights.len())
            as u64;
        // What depends on the pose: the scale's offset and AO radius, the lights' odds.
        self.params_value.offset = r.offset;
        self.params_value.ao_radius = r.ao_radius;
        self.params_value.p_area = r.lights.p_area;
        self.set_camera(r)
    }

    /// `slot`'s renderer pointed at `r` — at its camera, and at its scene's
    /// tables too when `posed` (an animation's next pose) — or, where there
    /// is none or that cannot be done (another image size, triangle or light
    /// count), a new one made for `r` on `gpu`. Whether the old one was kept.
    pub fn reuse(
        slot: &mut Option<GpuRenderer<'g>>,
        gpu: &'g Gpu,
        r: &Renderer<'_>,
        posed: bool,
    ) -> Result<bool, RenderError> {
        let kept = match slot.as_mut() {
            Some(g) if posed => g.set_scene(r).is_ok(),
            Some(g) => g.set_camera(r).is_ok(),
            None => false,
        };
        if !kept {
            *slot = Some(GpuRenderer::new(gpu, r)?);
        }
        Ok(kept)
    }

    /// The counters of the samples added since the last restart (one
    /// read-back): rays traced and hits that were not hits, which make
    /// the image wrong ([`RenderError::Gpu`]).
    pub fn counters(&mut self) -> Result<RenderState, RenderError> {
        let state = self.state.clone();
        counters_of(&self.read(&state, STATE_BYTES)?)
    }

    /// [`GpuRenderer::counters`] without blocking: the form a browser page
    /// awaits after each sample it presents on its canvas (the counters
    /// only, not the image).
    pub async fn counters_async(&mut self) -> Result<RenderState, RenderError> {
        let state = self.state.clone();
        counters_of(&self.read_async(&state, STATE_BYTES).await?)
    }

    /// Copies the sums and the counters into one staging buffer (recorded
    /// and submitted): what a read-back of the image takes.
    fn encode_result(&mut self) -> wgpu::Buffer {
        let n = u64::from(self.n);
        let staging = zeroed(
            self.gpu,
            "render result",
            n * 16 + STATE_BYTES,
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.sum, 0, &staging, 0, n * 16);
        enc.copy_buffer_to_buffer(&self.state, 0, &staging, n * 16, STATE_BYTES);
        self.submit(enc);
        staging
    }

    /// The mean of `samples` samples and the counters, from the bytes of
    /// [`GpuRenderer::encode_result`]'s buffer; hits that were not hits are
    /// an error.
    fn mean_of(&self, bytes: &[u8], samples: u32) -> Result<(Image, RenderState), RenderError> {
        let n = self.n as usize * 16;
        if bytes.len() < n + STATE_BYTES as usize {
            return Err(RenderError::Gpu(GpuError::Readback(format!(
                "{} bytes read back for {n} of sums and the counters",
                bytes.len()
            ))));
        }
        let (sums, state) = bytes.split_at(n);
        let state = counters_of(state)?;
        let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(sums);
        let inv = if samples == 0 {
            0.0
        } else {
            1.0 / samples as f32
        };
        let image = Image {
            width: self.width,
            height: self.height,
            pixels: sums
                .iter()
                .map(|s| (Vec3::new(s[0], s[1], s[2]) * inv).to_array())
                .collect(),
        };
        Ok((image, state))
    }

    /// The mean of the `samples` samples added since the last restart and
    /// the counters, in one read-back that does not block: the form a
    /// browser page awaits where no canvas presents the sums.
    pub async fn mean_async(&mut self, samples: u32) -> Result<(Image, RenderState), RenderError> {
        let staging = self.encode_result();
        let bytes = self.read_async(&staging, staging.size()).await?;
        self.mean_of(&bytes, samples)
    }

    /// Renders every sample through `ads` (built from the renderer's
    /// triangles) and reads the image back once. `progress` is called after
    /// each sample is submitted (not finished: the GPU runs ahead).
    pub fn render(
        &mut self,
        ads: &GpuAds,
        traversal: Traversal,
        progress: &mut dyn FnMut(&crate::Progress),
    ) -> Result<Rendered, RenderError> {
        self.render_inspected(ads, traversal, progress, None)
    }

    /// [`GpuRenderer::render`], handing every trace's rays and hits to
    /// `inspect` (read back per trace: for tests).
    pub fn render_inspected(
        &mut self,
        ads: &GpuAds,
        traversal: Traversal,
        progress: &mut dyn FnMut(&crate::Progress),
        mut inspect: Option<&mut dyn FnMut(TraceRecord)>,
    ) -> Result<Rendered, RenderError> {
        let start = Instant::now();
        let gpu = self.gpu;
        self.restart();
        gpu.scoped("the GPU render", || {
            for sample in 0..self.spp {
                self.sample(ads, traversal, sample, &mut inspect)
                    .map_err(inside_scope)?;
                progress(&crate::Progress {
                    samples_done: sample + 1,
                    spp: self.spp,
                    rays: 0,
                    elapsed: start.elapsed(),
                });
            }
            Ok(())
        })?;
        // One read-back: the image's sums and the counters behind them.
        let staging = self.encode_result();
        let bytes = self.read(&staging, staging.size())?;
        let (image, state) = self.mean_of(&bytes, self.spp)?;
        let n = u64::from(self.n);
        let confirmed = state.confirmed_total();
        Ok(Rendered {
            image,
            rays: state.rays_total(),
            visibility: VisibilityStats {
                confirmed,
                fallback: (n * u64::from(self.spp)).saturating_sub(confirmed),
            },
            trace_time: Duration::ZERO,
            elapsed: start.elapsed(),
            tracer: format!("dirt-gpu ({traversal}), shaded on the GPU"),
        })
    }
}
