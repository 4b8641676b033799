//! dirt-web: DIRT in a browser page.
//!
//! [`Page`] path-traces a scene progressively: each step renders one sample
//! pass and adds it to the running mean, tone-mapped as `dirt render`'s PNG
//! is. On the page's WebGPU device the whole sample runs there
//! (`dirt_render::gpu`: the frame build, the traces and the shading, one
//! submission) and the page's canvas, a WebGPU context, shows the sums
//! tone-mapped where they lie ([`Page::present_on`], the renderer's `output`
//! pass): the image is never read back, only the counters (48 bytes a step,
//! awaited: a browser resolves read-backs on its event loop, and the wait
//! paces the steps). Without a canvas the mean comes back in one read-back
//! a step ([`Page::rgba`]). Where the browser has no WebGPU, `dirt-render`
//! traces through `dirt-cpu` compiled to wasm ([`Backend`]) and the mean is
//! drawn on a 2D canvas. [`check`] measures the
//! portable path: a GPU build and trace against the CPU reference and brute
//! force over the same triangles and rays, bit for bit ([`compare`]).
//!
//! The page's bindings (`wasm-bindgen`, module `bind`) exist only in the
//! `wasm32` build; everything else builds and is tested natively too.

#[cfg(target_arch = "wasm32")]
pub mod bind;
pub mod compare;

use dirt_core::{AdsParams, Traversal};
use dirt_cpu::DirtCpu;
use dirt_gpu::{DirtGpu, Gpu, GpuError};
use dirt_math::{Hit, Ray, RayStats, Triangle};
use dirt_render::accum::Accumulator;
use dirt_render::gpu::GpuRenderer;
use dirt_render::gpu::output::{Drawn, SurfaceOutput};
use dirt_render::orbit::Orbit;
use dirt_render::{AsyncTrace, RenderError, Renderer, Settings};
use dirt_scene::{Scene, SceneError};
use web_time::{Duration, Instant};

/// Everything that can go wrong on the page.
#[derive(Debug, thiserror::Error)]
pub enum WebError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Trace(#[from] dirt_core::CoreError),
    #[error(transparent)]
    Cpu(#[from] dirt_cpu::CpuError),
    /// The browser gave no WebGPU adapter or device.
    #[error("no WebGPU: {0}")]
    NoWebGpu(String),
    #[error("image size {width}x{height} is invalid: both sides must be in 1..={max}")]
    BadSize { width: u32, height: u32, max: u32 },
}

/// Largest side of the page's image: a wasm page traces every pixel per sample.
pub const MAX_SIDE: u32 = 2048;

/// What traces the page's rays.
// A page holds one, so the variants' sizes (about 0.7 and 1 KiB) cost nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Backend {
    /// `dirt-gpu` on the page's device, built and traced without blocking.
    Gpu(DirtGpu<'static>),
    /// `dirt-cpu` in the page's thread.
    Cpu(DirtCpu),
}

impl Backend {
    /// DIRT on `gpu` with `params` and `traversal`, building in a frame (the
    /// GPU-resident build: views, lists and their sizes found on the GPU).
    pub fn gpu(gpu: &'static Gpu, params: AdsParams, traversal: Traversal) -> Backend {
        let mut t = DirtGpu::new(gpu, params, traversal);
        t.frame_builds = true;
        Backend::Gpu(t)
    }

    /// DIRT on the CPU with `params` and `traversal`.
    pub fn cpu(params: AdsParams, traversal: Traversal) -> Backend {
        Backend::Cpu(DirtCpu::new(params, traversal))
    }

    /// Builds over `tris`.
    pub async fn build(&mut self, tris: &[Triangle]) -> Result<(), WebError> {
        match self {
            Backend::Gpu(t) => {
                t.build_async(tris).await?;
            }
            Backend::Cpu(t) => {
                dirt_core::Tracer::build(t, tris)?;
            }
        }
        Ok(())
    }

    /// The closest hits of `rays`, with statistics when asked.
    pub async fn trace(
        &mut self,
        rays: &[Ray],
        with_stats: bool,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), WebError> {
        match self {
            Backend::Gpu(t) => {
                let out = t.trace_async(rays, with_stats).await?;
                Ok((out.hits, out.stats))
            }
            Backend::Cpu(t) => {
                let mut hits = vec![Hit::MISS; rays.len()];
                let mut stats = vec![RayStats::default(); if with_stats { rays.len() } else { 0 }];
                dirt_core::Tracer::trace_into(
                    t,
                    rays,
                    &mut hits,
                    with_stats.then_some(stats.as_mut_slice()),
                )?;
                Ok((hits, stats))
            }
        }
    }
}

impl AsyncTrace for Backend {
    fn name(&self) -> String {
        match self {
            Backend::Gpu(t) => dirt_core::Tracer::name(t),
            Backend::Cpu(t) => dirt_core::Tracer::name(t),
        }
    }

    async fn trace_rays(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        match self.trace(rays, false).await {
            Ok((hits, _)) => Ok(hits),
            Err(WebError::Render(e)) => Err(e),
            Err(WebError::Gpu(e)) => Err(RenderError::Gpu(e)),
            Err(WebError::Trace(e)) => Err(RenderError::Trace(e)),
            Err(other) => Err(RenderError::Trace(dirt_core::CoreError::backend(
                "dirt-web", other,
            ))),
        }
    }
}

/// A progressive path tracing of one scene from an orbiting camera.
#[derive(Debug)]
pub struct Page {
    scene: Scene,
    pub orbit: Orbit,
    settings: Settings,
    accum: Accumulator,
    backend: Backend,
    /// With the GPU backend: the renderer that shades there (made for the
    /// first step, pointed at each new camera), its samples since the
    /// camera moved, and their mean as last read back (none when a canvas
    /// presents them).
    shaded: Option<GpuRenderer<'static>>,
    gpu_samples: u32,
    gpu_mean: Option<dirt_render::Image>,
    /// The canvas's surface, where the GPU renderer's sums are drawn.
    canvas: Option<SurfaceOutput>,
    /// Rays traced since the camera last moved, and the time their sample passes took.
    rays: u64,
    busy: Duration,
    /// The last pass's rays per second.
    last_rate: f64,
}

impl Page {
    /// A page over `scene` at `width`×`height`, its structure built by `backend`.
    pub async fn new(
        scene: Scene,
        width: u32,
        height: u32,
        mut backend: Backend,
    ) -> Result<Page, WebError> {
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(WebError::BadSize {
                width,
                height,
                max: MAX_SIDE,
            });
        }
        scene.validate().map_err(RenderError::BadScene)?;
        let orbit = Orbit::for_scene(&scene, width as f32 / height as f32, None, None, None)?;
        backend.build(&scene.triangles).await?;
        let settings = Settings {
            width,
            height,
            ..Settings::default()
        };
        settings.validate()?;
        Ok(Page {
            scene,
            orbit,
            settings,
            accum: Accumulator::new(width, height),
            backend,
            shaded: None,
            gpu_samples: 0,
            gpu_mean: None,
            canvas: None,
            rays: 0,
            busy: Duration::ZERO,
            last_rate: 0.0,
        })
    }

    /// Renders one more sample pass and adds it to the mean.
    pub async fn step(&mut self) -> Result<(), WebError> {
        if let Backend::Gpu(t) = &self.backend {
            let start = Instant::now();
            if self.gpu_samples == 0 {
                let renderer = Renderer::new(&self.scene, self.orbit.camera()?, self.settings)?;
                GpuRenderer::reuse(&mut self.shaded, t.gpu(), &renderer, false)?;
            }
            let ads = t.built_ads()?;
            let Some(g) = self.shaded.as_mut() else {
                return Err(WebError::NoWebGpu("the GPU renderer was not made".into()));
            };
            g.add_sample(ads, t.traversal, self.gpu_samples)?;
            self.gpu_samples += 1;
            let rays = if let Some(out) = self.canvas.as_mut() {
                // The sums drawn where they lie; only the counters come back.
                out.draw(Drawn::Sums {
                    sums: g.sums(),
                    width: self.settings.width,
                    height: self.settings.height,
                    samples: self.gpu_samples,
                    exposure: 0.0,
                })?;
                g.counters_async().await?.rays_total()
            } else {
                // One read-back a step: the mean to draw, and the rays behind it.
                let (mean, counters) = g.mean_async(self.gpu_samples).await?;
                self.gpu_mean = Some(mean);
                counters.rays_total()
            };
            let took = start.elapsed();
            self.last_rate = rays.saturating_sub(self.rays) as f64 / took.as_secs_f64().max(1e-9);
            self.rays = rays;
            self.busy += took;
            return Ok(());
        }
        let start = Instant::now();
        let renderer = Renderer::new(&self.scene, self.orbit.camera()?, self.settings)?;
        let pass = renderer
            .render_sample_async(&mut self.backend, self.accum.samples)
            .await?;
        self.accum.add(&pass.radiance)?;
        let took = start.elapsed();
        self.rays += pass.rays;
        self.busy += took;
        self.last_rate = pass.rays as f64 / took.as_secs_f64().max(1e-9);
        Ok(())
    }

    /// Forgets the passes (after the camera moved).
    pub fn restart(&mut self) {
        self.accum.reset();
        self.gpu_samples = 0;
        self.gpu_mean = None;
        self.rays = 0;
        self.busy = Duration::ZERO;
    }

    /// The mean so far as 8-bit sRGBA, rows top to bottom (as `dirt render`'s
    /// PNG); none where the GPU renderer's image is presented on the canvas
    /// and never read back.
    pub fn rgba(&self) -> Option<Vec<u8>> {
        match (&self.backend, &self.gpu_mean) {
            (Backend::Cpu(_), _) => Some(self.accum.rgba8(0.0)),
            (Backend::Gpu(_), Some(m)) => Some(m.to_rgba8(0.0)),
            (Backend::Gpu(_), None) => None,
        }
    }

    /// Whether the samples are shaded on the GPU (the GPU backend).
    pub fn shaded_on_gpu(&self) -> bool {
        matches!(self.backend, Backend::Gpu(_))
    }

    /// From the next step on, the GPU renderer's sums are drawn on `out` (a
    /// canvas's WebGPU surface on the page's device) and not read back.
    /// Refused on the CPU backend, whose image is made on the host.
    pub fn present_on(&mut self, out: SurfaceOutput) -> Result<(), WebError> {
        if !self.shaded_on_gpu() {
            return Err(WebError::Render(RenderError::Unsupported(
                "presenting on a WebGPU canvas needs the GPU backend".into(),
            )));
        }
        self.gpu_mean = None;
        self.canvas = Some(out);
        Ok(())
    }

    /// Whether a canvas presents the image (no read-back of it).
    pub fn presents(&self) -> bool {
        self.canvas.is_some()
    }

    /// Sample passes in the mean.
    pub fn samples(&self) -> u32 {
        if self.shaded_on_gpu() {
            self.gpu_samples
        } else {
            self.accum.samples
        }
    }

    /// Rays per second over the passes since the camera last moved.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.busy.as_secs_f64().max(1e-9)
    }

    /// The last pass's rays per second.
    pub fn last_rays_per_second(&self) -> f64 {
        self.last_rate
    }

    pub fn size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    pub fn triangles(&self) -> usize {
        self.scene.triangles.len()
    }

    pub fn backend(&self) -> &Backend {
        &self.backend
    }

    /// The camera as `dirt render` takes it: `--eye=X,Y,Z --target=X,Y,Z --fov=F`.
    pub fn camera_args(&self) -> String {
        let v = |p: dirt_math::Vec3| format!("{},{},{}", p.x, p.y, p.z);
        format!(
            "--eye={} --target={} --fov={}",
            v(self.orbit.eye),
            v(self.orbit.target),
            self.orbit.fov
        )
    }
}

/// What [`check`] measured.
#[derive(Clone, Debug, Default)]
pub struct Check {
    /// The GPU's frame structure against the CPU's.
    pub structure: compare::StructureDiff,
    /// The GPU's hits and statistics against the CPU's.
    pub gpu_cpu: compare::HitDiff,
    /// The GPU's hits against brute force.
    pub gpu_truth: compare::HitDiff,
    /// The CPU's hits against brute force (none may differ anywhere).
    pub cpu_truth: compare::HitDiff,
}

impl Check {
    /// One line: what differs, or that nothing does.
    pub fn summary(&self) -> String {
        let s = &self.structure;
        let h = |d: &compare::HitDiff| {
            format!(
                "{}/{} rays differ (prim {}, t {} up to {} ulp, uv {}, stats {})",
                d.differ, d.rays, d.prim, d.t, d.t_ulps, d.uv, d.stats
            )
        };
        format!(
            "structure: views {} differ, Hi-Z cells {}/{}, lists {}/{}; gpu vs cpu: {}; gpu vs brute force: {}; cpu vs brute force: {}{}",
            s.views,
            s.hiz_cells,
            s.hiz_total,
            s.lists,
            s.lists_total,
            h(&self.gpu_cpu),
            h(&self.gpu_truth),
            h(&self.cpu_truth),
            [&s.first, &self.gpu_cpu.first, &self.gpu_truth.first]
                .into_iter()
                .flatten()
                .next()
                .map(|f| format!("; first: {f}"))
                .unwrap_or_default()
        )
    }
}

/// The settings the tests measure [`check`] at: the cube at r32 B4, one
/// view at r64 B2 and the split orthographic views at r32 B4 (small enough
/// for a software adapter).
pub fn check_params() -> [AdsParams; 3] {
    [
        AdsParams {
            resolution: 32,
            buckets: 4,
            ..AdsParams::default()
        },
        AdsParams {
            views: dirt_math::ViewsKind::Single,
            resolution: 64,
            buckets: 2,
            ..AdsParams::default()
        },
        AdsParams {
            views: dirt_math::ViewsKind::OrthoSplit,
            resolution: 32,
            buckets: 4,
            ..AdsParams::default()
        },
    ]
}

/// DIRT built in a frame on `gpu` and traced there, against the CPU
/// reference and brute force over the same `tris` and `rays`.
pub async fn check(
    gpu: &'static Gpu,
    tris: &[Triangle],
    rays: &[Ray],
    params: &AdsParams,
    traversal: Traversal,
) -> Result<Check, WebError> {
    let cpu = dirt_cpu::Ads::build(tris, params)?;
    let (cpu_hits, cpu_stats) = dirt_cpu::trace_with_stats(&cpu, tris, rays, traversal);
    let truth = dirt_cpu::brute_force::trace(tris, rays);
    let mut g = DirtGpu::new(gpu, *params, traversal);
    // Room for the CPU's lists: this measures the structure, not the ids' growth.
    g.entries_hint = cpu.lists.ids.len() as u64 + 1;
    g.build_async(tris).await?;
    let t = g.trace_async(rays, true).await?;
    let ads = g
        .ads()
        .ok_or_else(|| WebError::NoWebGpu("the frame build left no structure".into()))?;
    let views = ads.read_views_async(gpu).await?;
    let hiz = ads.read_hiz_async(gpu).await?;
    let lists = ads.read_lists_async(gpu).await?;
    Ok(Check {
        structure: compare::structure(&views, &hiz, &lists, &cpu),
        gpu_cpu: compare::hits(&t.hits, &cpu_hits, Some((&t.stats, &cpu_stats))),
        gpu_truth: compare::hits(&t.hits, &truth, None),
        cpu_truth: compare::hits(&cpu_hits, &truth, None),
    })
}

/// `n` rays for comparing tracers on `tris`, from `seed`: origins anywhere
/// in the scene's box (enlarged by a fifth), each aimed at a point of a
/// random triangle — every fourth at one of its vertices or edge midpoints,
/// where neighbouring triangles meet.
pub fn probe_rays(tris: &[Triangle], n: usize, seed: u64) -> Vec<Ray> {
    use dirt_math::{Aabb, Vec3};

    let mut state = seed;
    // splitmix64: the same numbers on every target.
    let mut next = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    if tris.is_empty() {
        return Vec::new();
    }
    let b = Aabb::of_triangles(tris);
    let pad = b.extent() * 0.1;
    let (lo, hi) = (b.min - pad, b.max + pad);
    (0..n)
        .map(|i| {
            let o = lo + (hi - lo) * Vec3::new(next(), next(), next());
            let t = &tris[((next() * tris.len() as f32) as usize).min(tris.len() - 1)];
            let [v0, v1, v2] = t.v.map(Vec3::from);
            let target = if i % 4 == 3 {
                match (next() * 6.0) as u32 {
                    0 => v0,
                    1 => v1,
                    2 => v2,
                    3 => (v0 + v1) * 0.5,
                    4 => (v1 + v2) * 0.5,
                    _ => (v2 + v0) * 0.5,
                }
            } else {
                let (mut u, mut v) = (next(), next());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                v0 + (v1 - v0) * u + (v2 - v0) * v
            };
            Ray::new(o, target - o, 0.0, f32::INFINITY)
        })
        .collect()
}
