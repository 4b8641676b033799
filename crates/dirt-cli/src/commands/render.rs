//! `dirt render`: a scene in, a path-traced image out (tone-mapped PNG,
//! optionally linear EXR), every ray traced through the chosen tracer.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use dirt_core::{Tracer, Traversal};
use dirt_cpu::{DirtCpu, brute_force::Brute};
use dirt_gpu::{DirtGpu, Gpu};
use dirt_render::reference::Reference;
use dirt_render::{Camera, Mode, Renderer, Settings};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::args::{AdsArgs, SceneArg};
use crate::gpu::{fallback_line, gpu_line};

#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Where to write the image: tone-mapped 8-bit sRGB PNG. With --frames or
    /// --frame, a pattern such as out/frame_%04d.png (%d, %0Nd: the frame number).
    #[arg(short, long, value_name = "OUT.png")]
    out: PathBuf,
    /// Also write the linear radiance as a 32-bit float OpenEXR file (a
    /// pattern like --out's with --frames or --frame).
    #[arg(long, value_name = "OUT.exr")]
    exr: Option<PathBuf>,
    /// Render the frames A to B of the scene's animation (both included):
    /// DIRT is rebuilt for every frame of a moving scene, each frame's build
    /// and trace time is printed, and an animated GIF preview is written beside
    /// the frames (OUT's pattern with "preview" for the number, .gif).
    #[arg(long, value_name = "A..B", value_parser = parse_frames, conflicts_with_all = ["frame", "reference"])]
    frames: Option<(u32, u32)>,
    /// Render frame N of the animation and nothing else: the same image as
    /// frame N of --frames, so each machine of a farm can render one frame.
    #[arg(long, value_name = "N", conflicts_with = "reference")]
    frame: Option<u32>,
    /// Frames per second: frame n shows the animation at n / F seconds.
    #[arg(long, value_name = "F", default_value_t = 24.0)]
    fps: f32,
    /// Which of the file's animations plays (see `dirt info`).
    #[arg(long, value_name = "K", default_value_t = 0)]
    animation: usize,
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
    /// With DIRT on the GPU: shade on the host (the CPU renderer, one
    /// round trip per trace) instead of on the GPU.
    #[arg(long)]
    host_shading: bool,
    /// How DIRT walks the tiles a ray crosses [default: on the CPU at the
    /// cost model's choice, the faster on a sample of rays; else linear]
    #[arg(long, value_enum)]
    traversal: Option<Traversal>,
    #[command(flatten)]
    pub ads: AdsArgs,
    #[command(flatten)]
    camera: crate::args::CameraArgs,
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

/// The tracer of a render: DIRT on the GPU is kept by its type, so that the
/// image can be shaded on the GPU too (`dirt_render::gpu`).
enum RenderTracer<'g> {
    Gpu(Box<DirtGpu<'g>>),
    Other(Box<dyn Tracer + 'g>),
}

impl RenderTracer<'_> {
    fn as_tracer(&mut self) -> &mut dyn Tracer {
        match self {
            RenderTracer::Gpu(t) => t.as_mut(),
            RenderTracer::Other(t) => t.as_mut(),
        }
    }
}

/// Whether the image is shaded on the GPU, and the GPU renderer kept from
/// frame to frame (`GpuRenderer::reuse`): the next frame rewrites its
/// camera, and its scene's tables when the scene moves; nothing is compiled
/// or made again.
struct Shading<'g> {
    on_gpu: bool,
    moving: bool,
    kept: Option<dirt_render::gpu::GpuRenderer<'g>>,
}

/// Renders every sample: on the GPU when the tracer is DIRT on the GPU and
/// shading there was not declined (`shading.on_gpu`), else through the CPU
/// renderer.
fn render_image<'g>(
    renderer: &Renderer,
    tracer: &mut RenderTracer<'g>,
    shading: &mut Shading<'g>,
    progress: &mut dyn FnMut(&dirt_render::Progress),
) -> Result<dirt_render::Rendered> {
    if let (RenderTracer::Gpu(t), true) = (&mut *tracer, shading.on_gpu) {
        let gpu = t.gpu();
        let traversal = t.traversal;
        let ads = t.built_ads()?;
        let kept =
            dirt_render::gpu::GpuRenderer::reuse(&mut shading.kept, gpu, renderer, shading.moving)
                .context("cannot set up the GPU renderer")?;
        let g = shading
            .kept
            .as_mut()
            .context("the GPU renderer was not made")?;
        let before = g.transfers();
        let rendered = g.render(ads, traversal, progress)?;
        let x = g.transfers().since(before);
        eprintln!(
            "shaded on the GPU{}: {} submissions, {} read-back ({} bytes), {} bytes written after the upload",
            match (kept, shading.moving) {
                (true, true) => " (the renderer kept, its scene tables rewritten)",
                (true, false) => " (the renderer kept, its camera rewritten)",
                (false, _) => "",
            },
            x.submissions,
            x.read_backs,
            x.bytes_read,
            x.bytes_written
        );
        return Ok(rendered);
    }
    Ok(renderer.render(tracer.as_tracer(), progress)?)
}

/// The camera: the scene's (or a framing), with the command line's overrides.
fn camera(args: &RenderArgs, scene: &dirt_scene::Scene) -> Result<Camera> {
    let base = Camera::for_scene(scene, args.width as f32 / args.height.max(1) as f32)
        .context("cannot place a camera")?;
    if args.camera.eye.is_none() && args.camera.target.is_none() && args.camera.fov.is_none() {
        return Ok(base);
    }
    let eye = args.camera.eye.unwrap_or(base.eye);
    let target = args.camera.target.unwrap_or(base.eye + base.forward);
    let fov = args
        .camera
        .fov
        .unwrap_or_else(|| (base.tan_half_fov.atan() * 2.0).to_degrees());
    Ok(Camera::look_at(eye, target, fov)?)
}

/// `A..B` (both included) as a frame range.
fn parse_frames(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("{s:?} is not a frame range A..B (e.g. 0..47)"))?;
    let num = |x: &str| {
        x.trim()
            .parse::<u32>()
            .map_err(|_| format!("{x:?} in {s:?} is not a frame number"))
    };
    let (a, b) = (num(a)?, num(b.trim_start_matches('='))?);
    if b < a {
        return Err(format!("frame range {s:?} ends before it starts"));
    }
    Ok((a, b))
}

/// `template` with its `%d` or `%0Nd` replaced by `frame` (a number) or by
/// `preview`; `None` when it has no such pattern.
fn frame_path(template: &Path, frame: Option<u32>) -> Option<PathBuf> {
    let t = template.to_str()?;
    let start = t.find('%')?;
    let rest = &t[start + 1..];
    let digits = rest.find('d')?;
    let spec = &rest[..digits];
    if !spec.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    let width: usize = spec.parse().unwrap_or(0);
    let number = match frame {
        Some(n) if spec.starts_with('0') => format!("{n:0width$}"),
        Some(n) => format!("{n:width$}"),
        None => "preview".to_string(),
    };
    Some(PathBuf::from(format!(
        "{}{number}{}",
        &t[..start],
        &rest[digits + 1..]
    )))
}

/// The frames to render: `None` for a plain image.
fn frame_list(args: &RenderArgs) -> Result<Option<Vec<u32>>> {
    let list: Vec<u32> = match (args.frames, args.frame) {
        (Some((a, b)), _) => (a..=b).collect(),
        (None, Some(n)) => vec![n],
        (None, None) => return Ok(None),
    };
    if !(args.fps.is_finite() && args.fps > 0.0) {
        bail!("--fps {} must be a positive number", args.fps);
    }
    if list.len() > 1 {
        for (p, flag) in
            std::iter::once((&args.out, "-o")).chain(args.exr.iter().map(|e| (e, "--exr")))
        {
            if frame_path(p, Some(0)).is_none() {
                bail!(
                    "{flag} {} has no frame number pattern: with --frames give one such as out/frame_%04d.png",
                    p.display()
                );
            }
        }
    }
    Ok(Some(list))
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let frames = frame_list(args)?;
    let mut scene = match frames {
        Some(_) => {
            let spec = &args.scene.scene;
            let mut a = dirt_scene::open_animated(spec)
                .with_context(|| format!("cannot open scene {spec:?}"))?;
            for w in &a.scene.warnings {
                eprintln!("warning: {}: {w}", a.scene.name);
            }
            let clips = a.clips();
            if !clips.is_empty() && !a.set_clip(args.animation) {
                bail!(
                    "scene {} has {} animations; --animation {} names none",
                    a.scene.name,
                    clips.len(),
                    args.animation
                );
            }
            if !a.is_animated() {
                eprintln!(
                    "scene {}: nothing in it moves; every frame is the same image, from one build",
                    a.scene.name
                );
            }
            a
        }
        None => dirt_scene::AnimatedScene::fixed(args.scene.open()?),
    };
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
    // The framing of a scene without a camera of its own is chosen once, on
    // the pose at time 0, so that every frame (and a lone --frame N) shares it.
    let first_cam = camera(args, &scene.scene)?;
    let follow_camera = !scene.scene.cameras.is_empty();
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
    let frame_time = |n: u32| n as f32 / args.fps;
    if let Some(list) = &frames {
        // The structure's setting is chosen on the first frame and kept.
        scene.pose(frame_time(list[0]))?;
    }
    // The cost model chooses on the first frame; later frames keep its setting.
    let (params, mut chosen) = match args.backend {
        // These build no DIRT structure: nothing to choose.
        RenderBackend::Reference | RenderBackend::Brute => (args.ads.params(), None),
        // On the GPU the choice must fit the device's bindings.
        _ => args.ads.choose_within(
            &scene.scene,
            settings.max_rays(),
            None,
            gpu.as_ref().map(|g| g.binding_limits()),
        )?,
    };
    let mut kept = None;
    // DIRT on the CPU at the cost model's choice walks with the faster traversal.
    let on_cpu = chosen.as_ref().filter(|_| gpu.is_none());
    let traversal = args
        .ads
        .traversal(args.traversal, on_cpu, &scene.scene, None)?;
    let build = std::time::Instant::now();
    let mut tracer: RenderTracer<'_> = {
        let tris = &scene.scene.triangles;
        match (args.backend, &gpu) {
            (RenderBackend::Auto | RenderBackend::Gpu, Some(g)) => RenderTracer::Gpu(Box::new(
                DirtGpu::built(g, tris, &params, traversal)
                    .with_context(|| format!("cannot build DIRT on the GPU ({params:?})"))?,
            )),
            (RenderBackend::Auto | RenderBackend::Gpu | RenderBackend::Cpu, _) => {
                RenderTracer::Other(Box::new(match chosen.take() {
                    // The structure the cost model built while choosing.
                    Some(ads) => {
                        kept = Some(ads.timings.total());
                        DirtCpu::from_ads(ads, tris, traversal)
                    }
                    None => DirtCpu::built(tris, &params, traversal)
                        .with_context(|| format!("cannot build DIRT ({params:?})"))?,
                }))
            }
            (RenderBackend::Reference, _) => RenderTracer::Other(Box::new(Reference::new(tris))),
            (RenderBackend::Brute, _) => RenderTracer::Other(Box::new(Brute::new(tris))),
        }
    };
    let mut shading = Shading {
        on_gpu: matches!(tracer, RenderTracer::Gpu(_)) && !args.host_shading,
        moving: scene.is_animated(),
        kept: None,
    };
    let first_build = kept.unwrap_or_else(|| build.elapsed());
    eprintln!(
        "scene {}: {} triangles; {}x{}, {} spp, {} bounces, mode {:?}; tracer {} ({})",
        scene.scene.name,
        scene.scene.len(),
        settings.width,
        settings.height,
        settings.spp,
        settings.bounces,
        settings.mode,
        tracer.as_tracer().name(),
        match kept {
            Some(t) => format!(
                "built in {:.1} ms while the cost model chose, and kept",
                t.as_secs_f64() * 1e3
            ),
            None => format!("built in {:.1} ms", first_build.as_secs_f64() * 1e3),
        }
    );
    let left_out: Vec<String> = dirt_render::features(&scene.scene, &settings)
        .into_iter()
        .filter(|f| !f.used)
        .map(|f| format!("{} ({})", f.name, f.why))
        .collect();
    if !left_out.is_empty() {
        eprintln!("left out: {}", left_out.join("; "));
    }

    let Some(list) = frames else {
        let renderer = Renderer::new(&scene.scene, first_cam, settings)
            .with_context(|| format!("cannot render scene {}", scene.scene.name))?;
        return render_one(
            args,
            &renderer,
            &mut tracer,
            &mut shading,
            &args.out,
            args.exr.as_deref(),
        );
    };
    let moving = scene.is_animated();
    // A sequence's folder is made for it (a single image's folder must exist).
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the folder {}", dir.display()))?;
    }
    let mut previews = Vec::new();
    for (i, &n) in list.iter().enumerate() {
        let t = frame_time(n);
        let build_ms = if i == 0 {
            first_build.as_secs_f64() * 1e3
        } else if moving {
            scene.pose(t)?;
            let b = std::time::Instant::now();
            tracer
                .as_tracer()
                .build(&scene.scene.triangles)
                .with_context(|| format!("cannot rebuild DIRT for frame {n}"))?;
            b.elapsed().as_secs_f64() * 1e3
        } else {
            0.0
        };
        let cam = if follow_camera {
            camera(args, &scene.scene)?
        } else {
            first_cam
        };
        let renderer = Renderer::new(&scene.scene, cam, settings)
            .with_context(|| format!("cannot render scene {}", scene.scene.name))?;
        let out = frame_path(&args.out, Some(n)).unwrap_or_else(|| args.out.clone());
        let exr = args
            .exr
            .as_ref()
            .map(|e| frame_path(e, Some(n)).unwrap_or_else(|| e.clone()));
        let rendered = render_quiet(
            &renderer,
            &mut tracer,
            &mut shading,
            &out,
            exr.as_deref(),
            args.exposure,
        )?;
        eprintln!(
            "frame {n}: t {t:.3} s, build {build_ms:.1} ms{}, trace {:.1} ms ({} rays), render {:.2} s; wrote {}",
            if i > 0 && !moving {
                " (static: kept)"
            } else {
                ""
            },
            rendered.trace_time.as_secs_f64() * 1e3,
            rendered.rays,
            rendered.elapsed.as_secs_f64(),
            out.display()
        );
        if list.len() > 1 {
            previews.push(rendered.image.to_srgb8(args.exposure));
        }
    }
    if list.len() > 1
        && let Some(mut gif) = frame_path(&args.out, None)
    {
        gif.set_extension("gif");
        write_gif(&gif, &previews, settings.width, settings.height, args.fps)?;
        eprintln!(
            "preview: wrote {} ({} frames)",
            gif.display(),
            previews.len()
        );
    }
    Ok(())
}

/// Renders one frame without a progress bar, writes it, and returns it.
fn render_quiet<'g>(
    renderer: &Renderer,
    tracer: &mut RenderTracer<'g>,
    shading: &mut Shading<'g>,
    out: &Path,
    exr: Option<&Path>,
    exposure: f32,
) -> Result<dirt_render::Rendered> {
    let rendered = render_image(renderer, tracer, shading, &mut |_| {})?;
    write_images(&rendered, out, exr, exposure)?;
    Ok(rendered)
}

fn write_images(
    rendered: &dirt_render::Rendered,
    out: &Path,
    exr: Option<&Path>,
    exposure: f32,
) -> Result<()> {
    rendered
        .image
        .write_png(out, exposure)
        .context("cannot write the PNG")?;
    if let Some(exr) = exr {
        rendered
            .image
            .write_exr(exr)
            .context("cannot write the EXR")?;
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
    Ok(())
}

/// An animated GIF of tone-mapped RGB frames, looping.
fn write_gif(path: &Path, frames: &[Vec<u8>], width: u32, height: u32, fps: f32) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    enc.set_repeat(Repeat::Infinite)
        .context("cannot write the GIF")?;
    let delay = image::Delay::from_numer_denom_ms(1000, (fps.round() as u32).max(1));
    for rgb in frames {
        let rgba: Vec<u8> = rgb
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        let img = image::RgbaImage::from_raw(width, height, rgba)
            .context("a frame's size does not match the image")?;
        enc.encode_frame(image::Frame::from_parts(img, 0, 0, delay))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

/// A single image with a progress bar and the summary line.
fn render_one<'g>(
    args: &RenderArgs,
    renderer: &Renderer,
    tracer: &mut RenderTracer<'g>,
    shading: &mut Shading<'g>,
    out: &Path,
    exr: Option<&Path>,
) -> Result<()> {
    let settings = renderer.settings;
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
    let rendered = render_image(renderer, tracer, shading, &mut |p| {
        let secs = p.elapsed.as_secs_f64();
        let mrays = if secs > 0.0 {
            p.rays as f64 / secs / 1e6
        } else {
            0.0
        };
        bar.set_position(u64::from(p.samples_done));
        bar.set_message(if p.rays == 0 {
            // Shaded on the GPU: the rays are counted there, read at the end.
            "samples submitted to the GPU".to_string()
        } else {
            format!("{:.2} M rays, {mrays:.3} Mrays/s", p.rays as f64 / 1e6)
        });
    })?;
    bar.finish_and_clear();
    write_images(&rendered, out, exr, args.exposure)?;
    let mut wrote = out.display().to_string();
    if let Some(exr) = exr {
        wrote = format!("{wrote}, {}", exr.display());
    }
    let secs = rendered.elapsed.as_secs_f64();
    let trace_secs = rendered.trace_time.as_secs_f64();
    // A render shaded on the GPU traces and shades in one submission per
    // sample: there is no tracer time of its own to report.
    let in_tracer = if rendered.trace_time.is_zero() {
        "traced and shaded in the same submissions".to_string()
    } else {
        format!(
            "{:.3} Mrays/s in the tracer ({trace_secs:.2} s)",
            rendered.rays as f64 / trace_secs.max(1e-9) / 1e6
        )
    };
    eprintln!(
        "render: {:.2} s, {} rays, {:.3} Mrays/s overall, {in_tracer}, tracer {}; primary hits: {} confirmed from the raster, {} traced in full; wrote {wrote}",
        secs,
        rendered.rays,
        rendered.rays as f64 / secs.max(1e-9) / 1e6,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns_expand() {
        let p = |s: &str, n| frame_path(Path::new(s), n).map(|p| p.display().to_string());
        assert_eq!(
            p("out/frame_%04d.png", Some(7)).as_deref(),
            Some("out/frame_0007.png")
        );
        assert_eq!(p("f%d.png", Some(12)).as_deref(), Some("f12.png"));
        assert_eq!(p("f%d.png", None).as_deref(), Some("fpreview.png"));
        assert_eq!(p("plain.png", Some(1)), None);
        assert_eq!(p("odd%x.png", Some(1)), None);
        assert_eq!(parse_frames("2..5"), Ok((2, 5)));
        assert_eq!(parse_frames("3..=3"), Ok((3, 3)));
        assert!(parse_frames("5..2").is_err());
        assert!(parse_frames("a..b").is_err());
        assert!(parse_frames("7").is_err());
    }
}
