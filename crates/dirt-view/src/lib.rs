//! dirt-view: the interactive viewer behind `dirt view`.
//!
//! A winit window whose image is path-traced progressively through DIRT:
//! each displayed frame renders one more sample per pixel at the internal
//! resolution ([`dirt_render::Renderer::render_sample`]), adds it to an
//! [`accum::Accumulator`], tone-maps the mean as `dirt render` does and draws
//! it with wgpu ([`present`]). DIRT traces on the GPU on a hardware adapter
//! (on the very device that presents), else on the CPU, the image uploaded
//! each frame. Moving the camera ([`orbit`]), resizing, or a playing
//! animation restarts the accumulation.
//!
//! The samples so far and the rays per second are in the window's title, and
//! one line per frame goes to stdout (`frame N samples S rays R
//! mrays_per_s X time T camera eye=X,Y,Z target=X,Y,Z fov=DEG`), the numbers
//! exact enough that `dirt render --eye --target --fov` reproduces the view.
//!
//! This is the only crate of the project that knows winit.

pub use dirt_render::accum;
mod app;
pub use dirt_render::orbit;
pub mod present;

use dirt_core::{AdsParams, CoreError, Tracer, Traversal};
use dirt_cpu::{CpuError, DirtCpu};
use dirt_gpu::{DirtGpu, Gpu, GpuError, GpuOptions};
use dirt_math::Vec3;
use dirt_render::{Mode, RenderError, Settings};
use dirt_scene::SceneError;

/// Everything that can go wrong in the viewer.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("cannot open scene {spec:?}: {source}")]
    Scene { spec: String, source: SceneError },
    #[error("cannot pose the scene at {time} s: {source}")]
    Pose { time: f32, source: SceneError },
    #[error(
        "cannot open a window ({0}); dirt view needs a display (DISPLAY, e.g. under Xvfb); dirt render needs none"
    )]
    NoDisplay(String),
    #[error(
        "no usable GPU adapter to present with ({0}); the window needs a wgpu surface (a Vulkan driver: a GPU's, or Mesa's lavapipe); dirt render needs none"
    )]
    NoGpu(String),
    #[error("the window's surface: {0}")]
    Surface(String),
    #[error("{0}")]
    Options(String),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Trace(#[from] CoreError),
    #[error(transparent)]
    Cpu(#[from] CpuError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("internal error: {0}")]
    Internal(String),
}

/// Which DIRT traces the viewer's rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// DIRT on the GPU on a hardware adapter; on a software one (lavapipe),
    /// DIRT on the CPU, which is faster there.
    #[default]
    Auto,
    /// DIRT on the GPU, a software adapter too (the CPU if that fails).
    Gpu,
    /// DIRT on the CPU; the image is uploaded each frame.
    Cpu,
}

/// How the structure's parameters are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ads {
    /// Exactly these.
    Fixed(AdsParams),
    /// The cost model's cheapest candidate for a sample pass
    /// (`dirt_cpu::cost::auto_within`, within the GPU's bindings there),
    /// keeping these parameters' tile and centre.
    Auto(AdsParams),
}

/// What `dirt view` was asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewOptions {
    /// A built-in scene name or a .gltf/.glb/.obj path.
    pub scene: String,
    /// The window's inner size in pixels.
    pub width: u32,
    pub height: u32,
    /// Window pixels per rendered pixel: the image is rendered at the window
    /// size divided by this, then drawn nearest-texel.
    pub scale: f32,
    pub bounces: u32,
    pub mode: Mode,
    pub seed: u64,
    pub backend: Backend,
    /// With DIRT on the GPU: shade on the host (the image uploaded each
    /// frame) instead of on the GPU (`dirt_render::gpu`, nothing read back).
    pub host_shading: bool,
    pub traversal: Traversal,
    pub ads: Ads,
    /// Camera overrides; the rest as `dirt render` places it.
    pub eye: Option<Vec3>,
    pub target: Option<Vec3>,
    pub fov: Option<f32>,
    /// Exit after this many displayed frames (scripts).
    pub frames: Option<u64>,
    /// Stop adding samples at this many per pixel (the image stays).
    pub max_samples: Option<u32>,
    /// A stdout line every this many frames (0: none).
    pub print_every: u64,
    /// Start with the animation playing.
    pub play: bool,
    /// Exposure in stops, as `dirt render --exposure`.
    pub exposure: f32,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            scene: dirt_scene::DEFAULT_SCENE.to_string(),
            width: 640,
            height: 480,
            scale: 2.0,
            bounces: Settings::default().bounces,
            mode: Mode::Pt,
            seed: Settings::default().seed,
            backend: Backend::Auto,
            host_shading: false,
            traversal: Traversal::default(),
            ads: Ads::Auto(AdsParams::default()),
            eye: None,
            target: None,
            fov: None,
            frames: None,
            max_samples: None,
            print_every: 1,
            play: true,
            exposure: 0.0,
        }
    }
}

impl ViewOptions {
    /// The rendered image's size for a window of `width` x `height`.
    pub fn internal_size(&self, width: u32, height: u32) -> (u32, u32) {
        let side =
            |s: u32| ((s as f32 / self.scale).round() as u32).clamp(1, dirt_render::MAX_SIDE);
        (side(width), side(height))
    }

    /// The render settings of one sample pass at `width` x `height`.
    pub fn settings(&self, width: u32, height: u32) -> Settings {
        Settings {
            width,
            height,
            spp: 1,
            bounces: self.bounces,
            mode: self.mode,
            seed: self.seed,
            ..Settings::default()
        }
    }

    /// Checks what the command line cannot.
    pub fn validate(&self) -> Result<(), ViewError> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(ViewError::Options(format!(
                "--scale must be a positive number, got {}",
                self.scale
            )));
        }
        if self.width == 0 || self.height == 0 {
            return Err(ViewError::Options(format!(
                "the window must have a size, got {}x{}",
                self.width, self.height
            )));
        }
        if self.max_samples == Some(0) {
            return Err(ViewError::Options(
                "--max-samples must be at least 1".into(),
            ));
        }
        if !self.exposure.is_finite() {
            return Err(ViewError::Options("--exposure must be finite".into()));
        }
        let (w, h) = self.internal_size(self.width, self.height);
        self.settings(w, h).validate()?;
        Ok(())
    }
}

/// The starting camera: the scene's (or a framing of it), with the
/// overrides, as `dirt render` places it; the orbit's target is on the view
/// axis at the depth of the scene's centre.
pub fn start_camera(
    options: &ViewOptions,
    scene: &dirt_scene::Scene,
    aspect: f32,
) -> Result<orbit::Orbit, ViewError> {
    Ok(orbit::Orbit::for_scene(
        scene,
        aspect,
        options.eye,
        options.target,
        options.fov,
    )?)
}

/// Parameters for the scene's triangles: fixed, or the cost model's choice
/// for frames of `rays_per_frame` rays (with the CPU structure it built).
fn choose_ads(
    options: &ViewOptions,
    scene: &dirt_scene::Scene,
    rays_per_frame: u64,
    limits: Option<dirt_core::BindingLimits>,
) -> Result<(AdsParams, Option<dirt_cpu::Ads>), ViewError> {
    let base = match options.ads {
        Ads::Fixed(p) => return Ok((p, None)),
        Ads::Auto(p) => p,
    };
    let candidates: Vec<AdsParams> = dirt_cpu::cost::candidates_all(&base, &scene.triangles)
        .into_iter()
        .map(|c| AdsParams {
            tile: base.tile,
            ..c
        })
        .filter(|c| c.validate().is_ok())
        .collect();
    let sample = dirt_cpu::cost::sample_rays(&scene.triangles, 1000, 1);
    let mut choice = dirt_cpu::cost::auto_within(
        &scene.triangles,
        &sample,
        rays_per_frame,
        Traversal::HiZ,
        &dirt_cpu::cost::CostModel::CALIBRATED,
        &candidates,
        limits,
    )?;
    let best = choice.best.params;
    eprintln!(
        "ads: {} views, resolution {}, B {}, S {}: the cost model's choice for {rays_per_frame} rays a frame",
        best.views, best.resolution, best.buckets, best.tile
    );
    Ok((best, choice.best_ads.take()))
}

/// The viewer's tracer: DIRT on the GPU is kept by its type, so that the
/// image can be shaded there too (`dirt_render::gpu`).
pub(crate) enum ViewTracer<'g> {
    Gpu(Box<DirtGpu<'g>>),
    Cpu(Box<DirtCpu>),
}

impl ViewTracer<'_> {
    pub(crate) fn as_tracer(&mut self) -> &mut dyn Tracer {
        match self {
            ViewTracer::Gpu(t) => t.as_mut(),
            ViewTracer::Cpu(t) => t.as_mut(),
        }
    }

    pub(crate) fn name(&self) -> String {
        match self {
            ViewTracer::Gpu(t) => t.name(),
            ViewTracer::Cpu(t) => t.name(),
        }
    }
}

/// The tracer: DIRT built once for the scene on the GPU (`gpu`) or the CPU.
fn tracer<'g>(
    options: &ViewOptions,
    scene: &dirt_scene::Scene,
    gpu: Option<&'g Gpu>,
) -> Result<ViewTracer<'g>, ViewError> {
    let (w, h) = options.internal_size(options.width, options.height);
    let rays = options.settings(w, h).max_rays();
    let tris = &scene.triangles;
    let start = std::time::Instant::now();
    let tracer = match gpu {
        Some(g) => {
            let (params, _) = choose_ads(options, scene, rays, Some(g.binding_limits()))?;
            ViewTracer::Gpu(Box::new(DirtGpu::built(
                g,
                tris,
                &params,
                options.traversal,
            )?))
        }
        None => {
            let (params, built) = choose_ads(options, scene, rays, None)?;
            ViewTracer::Cpu(Box::new(match built {
                Some(ads) => DirtCpu::from_ads(ads, tris, options.traversal),
                None => DirtCpu::built(tris, &params, options.traversal)?,
            }))
        }
    };
    eprintln!(
        "scene {}: {} triangles; tracer {} (built in {:.1} ms)",
        scene.name,
        tris.len(),
        tracer.name(),
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(tracer)
}

/// Opens the window and runs the viewer until it is closed (Esc, Q, the
/// window's close button) or `options.frames` frames were displayed.
pub fn run(options: &ViewOptions) -> Result<(), ViewError> {
    options.validate()?;
    let scene = dirt_scene::open_animated(&options.scene).map_err(|source| ViewError::Scene {
        spec: options.scene.clone(),
        source,
    })?;
    for w in &scene.scene.warnings {
        eprintln!("warning: {}: {w}", scene.scene.name);
    }
    // The window comes first: without a display there is nothing to build for.
    let event_loop =
        winit::event_loop::EventLoop::new().map_err(|e| ViewError::NoDisplay(e.to_string()))?;
    let device = present::Device::open(event_loop.owned_display_handle())?;
    let use_gpu = match options.backend {
        Backend::Cpu => false,
        Backend::Gpu => true,
        Backend::Auto if device.is_software() => {
            eprintln!(
                "dirt view: the GPU adapter is software ({}); DIRT on the CPU is faster there, using it (--backend gpu forces the GPU); the image is uploaded each frame",
                device.describe()
            );
            false
        }
        Backend::Auto => true,
    };
    let gpu = if use_gpu {
        match Gpu::from_device(&device.device, &device.queue, &GpuOptions::from_env()) {
            Ok(g) => {
                eprintln!(
                    "dirt view: DIRT on the GPU: {} ({})",
                    g.describe(),
                    g.exactness
                );
                Some(g)
            }
            Err(e) => {
                eprintln!("dirt view: cannot run DIRT on the GPU ({e}); using the CPU");
                None
            }
        }
    } else {
        None
    };
    eprintln!("dirt view: presenting on {}", device.describe());
    let tracer = tracer(options, &scene.scene, gpu.as_ref())?;
    let mut app = app::App::new(options.clone(), scene, tracer, &device)?;
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewError::NoDisplay(e.to_string()))?;
    app.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_checked() {
        let ok = ViewOptions::default();
        assert!(ok.validate().is_ok());
        assert_eq!(ok.internal_size(640, 480), (320, 240));
        let bad = |o: ViewOptions| o.validate().map(|_| ()).expect_err("refused");
        bad(ViewOptions {
            scale: 0.0,
            ..ok.clone()
        });
        bad(ViewOptions {
            scale: f32::NAN,
            ..ok.clone()
        });
        bad(ViewOptions {
            width: 0,
            ..ok.clone()
        });
        bad(ViewOptions {
            max_samples: Some(0),
            ..ok.clone()
        });
        bad(ViewOptions {
            bounces: dirt_render::MAX_BOUNCES + 1,
            ..ok.clone()
        });
    }

    #[test]
    fn the_start_camera_is_render_s_camera_and_takes_overrides() {
        let scene = dirt_scene::open("cornell").expect("cornell");
        let o = ViewOptions::default();
        let orbit = start_camera(&o, &scene, 4.0 / 3.0).expect("camera");
        let base = dirt_render::Camera::for_scene(&scene, 4.0 / 3.0).expect("base");
        let cam = orbit.camera().expect("camera");
        assert!((cam.eye - base.eye).length() < 1e-5);
        assert!((cam.forward - base.forward).length() < 1e-4);
        let o = ViewOptions {
            eye: Some(Vec3::new(0.0, 1.0, 4.0)),
            target: Some(Vec3::new(0.0, 1.0, 0.0)),
            fov: Some(30.0),
            ..o
        };
        let orbit = start_camera(&o, &scene, 1.0).expect("camera");
        assert_eq!(
            (orbit.eye, orbit.target, orbit.fov),
            (Vec3::new(0.0, 1.0, 4.0), Vec3::new(0.0, 1.0, 0.0), 30.0)
        );
    }

    #[test]
    fn a_cpu_tracer_is_built_for_the_scene() {
        let scene = dirt_scene::open("cornell").expect("cornell");
        let o = ViewOptions {
            ads: Ads::Fixed(AdsParams::default()),
            ..ViewOptions::default()
        };
        let mut t = tracer(&o, &scene, None).expect("tracer");
        let (w, h) = (16, 12);
        let orbit = start_camera(&o, &scene, w as f32 / h as f32).expect("camera");
        let r =
            dirt_render::Renderer::new(&scene, orbit.camera().expect("camera"), o.settings(w, h))
                .expect("renderer");
        let pass = r.render_sample(t.as_tracer(), 0).expect("pass");
        assert_eq!(pass.radiance.len(), (w * h) as usize);
        assert!(pass.rays >= u64::from(w * h));
    }
}
