//! `dirt view`: the interactive viewer (the window and the progressive path
//! tracing live in `dirt-view`; this parses the command line).

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use dirt_core::Traversal;
use dirt_render::{Mode, Settings};
use dirt_view::{Ads, Backend, ViewOptions};

use crate::args::{AdsArgs, SceneArg};

#[derive(Debug, Args)]
#[command(
    after_help = "Controls: left drag orbits, right or middle drag (or shift + left) pans, \
    the wheel zooms; arrow keys orbit by 10°, + and - zoom; space plays or pauses the \
    animation; R resets the camera; Esc or Q quits.\n\
    The window's title shows the samples per pixel so far and the rays per second; \
    stdout gets one line per frame: \
    `frame N samples S rays R mrays_per_s X time T camera eye=X,Y,Z target=X,Y,Z fov=DEG`."
)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Window width in pixels.
    #[arg(long, value_name = "W", default_value_t = ViewOptions::default().width)]
    width: u32,
    /// Window height in pixels.
    #[arg(long, value_name = "H", default_value_t = ViewOptions::default().height)]
    height: u32,
    /// Window pixels per rendered pixel (2: a 640x480 window renders 320x240).
    #[arg(long, value_name = "F", default_value_t = ViewOptions::default().scale)]
    scale: f32,
    /// Scattering events per path at most.
    #[arg(long, value_name = "K", default_value_t = Settings::default().bounces)]
    bounces: u32,
    /// What each pixel estimates.
    #[arg(long, value_enum, default_value_t = Mode::default())]
    mode: Mode,
    /// Seed of the random numbers (as `dirt render --seed`).
    #[arg(long, value_name = "S", default_value_t = Settings::default().seed)]
    seed: u64,
    /// Which DIRT traces. `auto`: the GPU on a hardware adapter, else the CPU.
    #[arg(long, value_enum, default_value_t = ViewBackend::Auto)]
    backend: ViewBackend,
    /// With DIRT on the GPU: shade on the host and upload the image each
    /// frame, instead of shading on the GPU and presenting the sums where
    /// they lie.
    #[arg(long)]
    host_shading: bool,
    /// How DIRT walks the tiles a ray crosses.
    #[arg(long, value_enum, default_value_t = Traversal::default())]
    traversal: Traversal,
    #[command(flatten)]
    pub ads: AdsArgs,
    #[command(flatten)]
    camera: crate::args::CameraArgs,
    /// Exit after N displayed frames (for scripts).
    #[arg(long, value_name = "N")]
    frames: Option<u64>,
    /// Stop adding samples at N per pixel; the image stays until the camera moves.
    #[arg(long, value_name = "N")]
    max_samples: Option<u32>,
    /// Print the frame line every N frames (0: never).
    #[arg(long, value_name = "N", default_value_t = 1)]
    print_every: u64,
    /// Start with the animation playing (the default).
    #[arg(long, conflicts_with = "paused")]
    play: bool,
    /// Start with the animation paused.
    #[arg(long)]
    paused: bool,
    /// Exposure in stops.
    #[arg(
        long,
        value_name = "STOPS",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    exposure: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ViewBackend {
    /// DIRT on a hardware GPU if there is one, otherwise DIRT on the CPU.
    Auto,
    /// DIRT on the GPU, a software adapter too.
    Gpu,
    /// DIRT on the CPU; the image is uploaded each frame.
    Cpu,
}

impl ViewArgs {
    /// The viewer's options from the command line.
    pub fn options(&self) -> ViewOptions {
        let given = self.ads.given;
        // The cost model chooses unless told not to; any of views, resolution
        // or B given fixes all three (the defaults for the others).
        let ads = if self.ads.fixed || given.views || given.resolution || given.buckets {
            Ads::Fixed(self.ads.params())
        } else {
            Ads::Auto(self.ads.params())
        };
        ViewOptions {
            scene: self.scene.scene.clone(),
            width: self.width,
            height: self.height,
            scale: self.scale,
            bounces: self.bounces,
            mode: self.mode,
            seed: self.seed,
            backend: match self.backend {
                ViewBackend::Auto => Backend::Auto,
                ViewBackend::Gpu => Backend::Gpu,
                ViewBackend::Cpu => Backend::Cpu,
            },
            host_shading: self.host_shading,
            traversal: self.traversal,
            ads,
            eye: self.camera.eye,
            target: self.camera.target,
            fov: self.camera.fov,
            frames: self.frames,
            max_samples: self.max_samples,
            print_every: self.print_every,
            play: self.play || !self.paused,
            exposure: self.exposure,
        }
    }
}

pub fn view(args: &ViewArgs) -> Result<()> {
    dirt_view::run(&args.options()).with_context(|| format!("dirt view {}", args.scene.scene))
}
