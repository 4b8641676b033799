//! dirt-render: the deferred path tracer of DIRT (001 §4.2).
//!
//! A wavefront integrator: every path of a sample advances one bounce at a
//! time, so each bounce is one call of [`trace::Tracer::trace`] for the
//! continuation rays and one for the shadow rays of next-event estimation.
//! The stages, one name each (one module each):
//!
//! * [`direct_visibility`]: a z-buffer rasteriser proposes one primitive per
//!   pixel; the exact triangle test confirms it and a trace limited to its
//!   distance settles the closest hit (a full trace where it misses), so the
//!   primary hits are exactly those of traced primary rays.
//! * [`trace`]: rays in, closest hits out, through a [`trace::Tracer`]: DIRT on
//!   the CPU or the GPU, the obvhs BVH [`reference`], or brute force.
//! * [`fetch`]: only for primitives that were hit: barycentric interpolation of
//!   normals and texture coordinates, the base-colour texture lookup and the
//!   material parameters, into a [`fetch::SurfacePoint`].
//! * [`shading_buffer`]: the three path points G(k-1), G(k), G(k+1) per path,
//!   with the path's throughput and radiance.
//! * [`shade`]: the three-point form of light transport: the BSDF at G(k)
//!   between G(k-1) and G(k+1), emission found at G(k+1), next-event estimation
//!   at G(k), Russian roulette.
//! * [`shift`]: the left shift G(k-1) ← G(k) ← G(k+1).
//!
//! A render runs only the shading features its scene and mode need (no
//! texture decoding without used textures, no light sampling or shadow rays
//! without lights, a geometry-only fetch for ambient occlusion); [`features`]
//! says which and why.
//!
//! Shading runs on the host with the same code for every tracer, and random
//! numbers are a pure function of (seed, pixel, sample, bounce, dimension)
//! ([`rng`]); pixels accumulate their samples in sample order. So two tracers
//! that return the same hits (DIRT and the reference do: both are exact)
//! give images that are identical to the bit.

pub mod accum;
pub mod bsdf;
pub mod camera;
pub mod direct_visibility;
pub mod features;
pub mod fetch;
pub mod gpu;
pub mod integrator;
pub mod lights;
pub mod metrics;
pub mod orbit;
pub mod output;
pub mod reference;
pub mod rng;
pub mod shade;
pub mod shading_buffer;
pub mod shift;
pub mod trace;

pub use camera::Camera;
pub use features::{Feature, features};
pub use integrator::{Progress, Rendered, Renderer, SamplePass};
pub use output::Image;
pub use trace::{AsyncTrace, Blocking, Tracer};

use std::path::PathBuf;

/// Everything that can go wrong while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("image size {width}x{height} is invalid: both sides must be in 1..={max}")]
    BadSize { width: u32, height: u32, max: u32 },
    #[error("samples per pixel must be at least 1")]
    ZeroSamples,
    #[error("bounces must be at most {max}, got {bounces}")]
    TooManyBounces { bounces: u32, max: u32 },
    #[error("ambient-occlusion radius must be finite and > 0, got {0}")]
    BadAoRadius(f32),
    #[error("the scene has no triangles")]
    EmptyScene,
    #[error("the scene is invalid: {0}")]
    BadScene(String),
    #[error("camera: {0}")]
    BadCamera(String),
    #[error("the tracer returned {got} hits for {expected} rays")]
    HitCount { expected: usize, got: usize },
    /// A blocking entry point was given hits that were not ready: a tracer
    /// whose hits come later needs [`Renderer::render_sample_async`].
    #[error("the tracer's hits were not ready: use the async entry point")]
    NotReady,
    #[error("a sample pass of {pixels} pixels for a {width}x{height} image")]
    PassSize {
        pixels: usize,
        width: u32,
        height: u32,
    },
    /// What this build does not do (yet), in words.
    #[error("not supported: {0}")]
    Unsupported(String),
    #[error("images differ in size: {a:?} and {b:?}")]
    SizeMismatch { a: (u32, u32), b: (u32, u32) },
    #[error(transparent)]
    Trace(#[from] dirt_core::CoreError),
    #[error(transparent)]
    Cpu(#[from] dirt_cpu::CpuError),
    #[error(transparent)]
    Gpu(#[from] dirt_gpu::GpuError),
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error("cannot read {path}: {message}")]
    Read { path: PathBuf, message: String },
    /// A window's or canvas's surface refused to configure or present.
    #[error("the surface: {0}")]
    Surface(String),
}

/// What a render computes per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Mode {
    /// Path tracing with next-event estimation and Russian roulette.
    #[default]
    Pt,
    /// Ambient occlusion: the fraction of cosine-distributed rays from the
    /// primary hit that travel [`Settings::ao_radius`] without hitting anything.
    Ao,
    /// Direct light only: emission seen directly plus one scattering event
    /// (next-event estimation and the BSDF-sampled ray, combined by MIS).
    Direct,
}

/// Largest image side.
pub const MAX_SIDE: u32 = 16384;
/// Largest bounce count.
pub const MAX_BOUNCES: u32 = 1024;

/// Render settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Scattering events per path at most (path tracing); direct mode uses one.
    pub bounces: u32,
    pub mode: Mode,
    pub seed: u64,
    /// Ambient-occlusion distance; `None`: a quarter of the scene's bounding-box diagonal.
    pub ao_radius: Option<f32>,
    /// Russian roulette from this bounce on (`None`: never, every path runs
    /// `bounces` scattering events).
    pub russian_roulette: Option<u32>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            width: 320,
            height: 240,
            spp: 16,
            bounces: 4,
            mode: Mode::Pt,
            seed: 1,
            ao_radius: None,
            russian_roulette: Some(3),
        }
    }
}

impl Settings {
    /// An upper bound of the rays a render traces: per pixel and sample a
    /// primary ray, then per bounce a shadow ray and a bounce ray (paths that
    /// end early trace fewer). What a tracer's parameters are chosen for.
    pub fn max_rays(&self) -> u64 {
        u64::from(self.width)
            * u64::from(self.height)
            * u64::from(self.spp)
            * (1 + 2 * u64::from(self.bounces))
    }

    /// Checks sizes and counts.
    pub fn validate(&self) -> Result<(), RenderError> {
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(RenderError::BadSize {
                width: self.width,
                height: self.height,
                max: MAX_SIDE,
            });
        }
        if self.spp == 0 {
            return Err(RenderError::ZeroSamples);
        }
        if self.bounces > MAX_BOUNCES {
            return Err(RenderError::TooManyBounces {
                bounces: self.bounces,
                max: MAX_BOUNCES,
            });
        }
        if let Some(r) = self.ao_radius
            && !(r.is_finite() && r > 0.0)
        {
            return Err(RenderError::BadAoRadius(r));
        }
        Ok(())
    }
}
