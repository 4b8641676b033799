//! `dirt render`: a scene in, a path-traced image out (tone-mapped PNG,
//! optionally linear EXR), every ray traced through the chosen tracer.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use dirt_core::{Tracer, Traversal};
use dirt_cpu::{DirtCpu, brute_force::Brute};
use dirt_gpu::{DirtGpu, Gpu};
use dirt_math::Vec3;
use dirt_render::reference::Reference;
use dirt_render::{Camera, Mode, Renderer, Settings};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::args::{AdsArgs, SceneArg};
use crate::gpu::{fallback_line, gpu_line};

#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Where to write the image: tone-mapped 8-bit sRGB PNG.
    #[arg(short, long, value_name = "OUT.png")]
    out: PathBuf,
    /// Also write the linear radiance as a 32-bit float OpenEXR file.
    #[arg(long, value_name = "OUT.exr")]
    exr: Option<PathBuf>,
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = Settings::default().spp)]
    spp: u32,
    /// Scattering events per path at most (path tracing).
    #[arg(long, value_name = "K", default_value_t = Settings::default().bounces)]
    bounces: u32,
    #[arg(long, value_name = "W", default_value_t = Settings::default().width)]
    width: u32,
    #[arg(long, value_name = "H", default_value_t = Settings::default().height)]
    height: u32,
    /// What each pixel estimates.
    #[arg(long, value_enum, default_value_t = Mode::default())]
    mode: Mode,
    /// Ambient-occlusion distance [default: a quarter of the scene's diagonal].
    #[arg(long, value_name = "R")]
    ao_radius: Option<f32>,
    /// Seed of the random numbers: the same seed gives the same image.
    #[arg(long, value_name = "S", default_value_t = Settings::default().seed)]
    seed: u64,
    /// Which tracer traces the rays. `auto`: DIRT on a hardware GPU when there
    /// is one, else DIRT on the CPU.
    #[arg(long, value_enum, default_value_t = RenderBackend::Auto)]
    backend: RenderBackend,
    /// How DIRT walks the tiles a ray crosses.
    #[arg(long, value_enum, default_value_t = Traversal::default())]
    traversal: Traversal,
    #[command(flatten)]
    ads: AdsArgs,
    /// Camera position "X,Y,Z" [default: the scene's first camera, else a framing of the bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = crate::args::parse_point, allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// Point the camera looks at, "X,Y,Z".
    #[arg(long, value_name = "X,Y,Z", value_parser = crate::args::parse_point, allow_hyphen_values = true)]
    target: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEG")]
    fov: Option<f32>,
    /// A linear EXR of the same size (e.g. a high-spp render) to print the
    /// root-mean-square error against.
    #[arg(long, value_name = "REF.exr")]
    reference: Option<PathBuf>,
    /// Exposure of the PNG in stops (the EXR is not scaled).
    #[arg(
        long,
        value_name = "STOPS",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    exposure: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum RenderBackend {
    /// DIRT on a hardware GPU if there is one, otherwise DIRT on the CPU.
    Auto,
    /// DIRT on the GPU (a software adapter too); without any, the CPU.
    Gpu,
    /// DIRT on the CPU.
    Cpu,
    /// The obvhs BVH with the same triangle test (same hits as brute force).
    Reference,
    /// Every ray against every triangle.
    Brute,
}

/// The camera: the scene's (or a framing), with the command line's overrides.
fn camera(args: &RenderArgs, scene: &dirt_scene::Scene) -> Result<Camera> {
    let base = Camera::for_scene(scene, args.width as f32 / args.height.max(1) as f32)
        .context("cannot place a camera")?;
    if args.eye.is_none() && args.target.is_none() && args.fov.is_none() {
        return Ok(base);
    }
    let eye = args.eye.unwrap_or(base.eye);
    let target = args.target.unwrap_or(base.eye + base.forward);
    let fov = args
        .fov
        .unwrap_or_else(|| (base.tan_half_fov.atan() * 2.0).to_degrees());
    Ok(Camera::look_at(eye, target, fov)?)
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let scene = args.scene.open()?;
    let settings = Settings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        bounces: args.bounces,
        mode: args.mode,
        seed: args.seed,
        ao_radius: args.ao_radius,
        ..Settings::default()
    };
    settings.validate()?;
    let cam = camera(args, &scene)?;
    let renderer = Renderer::new(&scene, cam, settings)
        .with_context(|| format!("cannot render scene {}", scene.name))?;
    if renderer.lights.is_empty() {
        eprintln!(
            "scene {}: no emitters and no punctual lights; lit by a white sky",
            scene.name
        );
    }
    let gpu = match args.backend {
        RenderBackend::Auto | RenderBackend::Gpu => match Gpu::open() {
            Ok(g) => {
                // The adapter's type by name: wgpu is not a dependency of the CLI.
                let software = g.is_llvmpipe() || format!("{:?}", g.info.device_type) == "Cpu";
                if args.backend == RenderBackend::Auto && software {
                    eprintln!(
                        "dirt: the GPU adapter is software ({}); DIRT on the CPU is faster there, using it (--backend gpu forces the GPU)",
                        g.describe()
                    );
                    None
                } else {
                    eprintln!("{}", gpu_line(&g));
                    Some(g)
                }
            }
            Err(reason) => {
                eprintln!("{}", fallback_line(&reason));
                None
            }
        },
        _ => None,
    };
    // A frame is the whole render.
    let (params, mut chosen) = match args.backend {
        // These build no DIRT structure: nothing to choose.
        RenderBackend::Reference | RenderBackend::Brute => (args.ads.params(), None),
        // On the GPU the choice must fit the device's bindings.
        _ => args.ads.choose_within(
            &scene,
            settings.max_rays(),
            None,
            gpu.as_ref().map(|g| g.binding_limits()),
        )?,
    };
    let mut kept = None;
    let traversal = args.traversal;
    let tris = &scene.triangles;
    let build = std::time::Instant::now();
    let mut tracer: Box<dyn Tracer + '_> = match (args.backend, &gpu) {
        (RenderBackend::Auto | RenderBackend::Gpu, Some(g)) => Box::new(
            DirtGpu::built(g, tris, &params, traversal)
                .with_context(|| format!("cannot build DIRT on the GPU ({params:?})"))?,
        ),
        (RenderBackend::Auto | RenderBackend::Gpu | RenderBackend::Cpu, _) => {
            Box::new(match chosen.take() {
                // The structure the cost model built while choosing.
                Some(ads) => {
                    kept = Some(ads.timings.total());
                    DirtCpu::from_ads(ads, tris, traversal)
                }
                None => DirtCpu::built(tris, &params, traversal)
                    .with_context(|| format!("cannot build DIRT ({params:?})"))?,
            })
        }
        (RenderBackend::Reference, _) => Box::new(Reference::new(tris)),
        (RenderBackend::Brute, _) => Box::new(Brute::new(tris)),
    };
    let build_time = build.elapsed();
    eprintln!(
        "scene {}: {} triangles; {}x{}, {} spp, {} bounces, mode {:?}; tracer {} ({})",
        scene.name,
        tris.len(),
        settings.width,
        settings.height,
        settings.spp,
        settings.bounces,
        settings.mode,
        tracer.name(),
        match kept {
            Some(t) => format!(
                "built in {:.1} ms while the cost model chose, and kept",
                t.as_secs_f64() * 1e3
            ),
            None => format!("built in {:.1} ms", build_time.as_secs_f64() * 1e3),
        }
    );
    let left_out: Vec<String> = dirt_render::features(&scene, &settings)
        .into_iter()
        .filter(|f| !f.used)
        .map(|f| format!("{} ({})", f.name, f.why))
        .collect();
    if !left_out.is_empty() {
        eprintln!("left out: {}", left_out.join("; "));
    }

    let target = if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(u64::from(settings.spp)), target);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} spp  {msg}",
        )
        .context("progress template")?,
    );
    let rendered = renderer.render(tracer.as_mut(), &mut |p| {
        let secs = p.elapsed.as_secs_f64();
        let mrays = if secs > 0.0 {
            p.rays as f64 / secs / 1e6
        } else {
            0.0
        };
        bar.set_position(u64::from(p.samples_done));
        bar.set_message(format!(
            "{:.2} M rays, {mrays:.3} Mrays/s",
            p.rays as f64 / 1e6
        ));
    })?;
    bar.finish_and_clear();

    rendered
        .image
        .write_png(&args.out, args.exposure)
        .context("cannot write the PNG")?;
    let mut wrote = args.out.display().to_string();
    if let Some(exr) = &args.exr {
        rendered
            .image
            .write_exr(exr)
            .context("cannot write the EXR")?;
        wrote = format!("{wrote}, {}", exr.display());
    }
    if rendered
        .image
        .pixels
        .iter()
        .flatten()
        .any(|c| !c.is_finite())
    {
        bail!("the image has non-finite pixels");
    }
    let secs = rendered.elapsed.as_secs_f64();
    let trace_secs = rendered.trace_time.as_secs_f64();
    eprintln!(
        "render: {:.2} s, {} rays, {:.3} Mrays/s overall, {:.3} Mrays/s in the tracer ({:.2} s), tracer {}; primary hits: {} confirmed from the raster, {} traced in full; wrote {wrote}",
        secs,
        rendered.rays,
        rendered.rays as f64 / secs.max(1e-9) / 1e6,
        rendered.rays as f64 / trace_secs.max(1e-9) / 1e6,
        trace_secs,
        rendered.tracer,
        rendered.visibility.confirmed,
        rendered.visibility.fallback,
    );
    if let Some(path) = &args.reference {
        let reference = dirt_render::Image::read_exr(path)
            .with_context(|| format!("cannot read the reference {}", path.display()))?;
        let e = dirt_render::metrics::rmse(&rendered.image, &reference)
            .with_context(|| format!("cannot compare with {}", path.display()))?;
        eprintln!("rmse against {}: {e:.6}", path.display());
    }
    Ok(())
}
