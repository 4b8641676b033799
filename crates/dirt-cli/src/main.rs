//! `dirt`: the command line of DIRT (Deferred Image-based Ray Tracing).
//!
//! ```text
//! dirt rays      SCENE --out RAYS.npy [--count N] [--seed S] [--kind mixed|camera|random|inside]
//! dirt trace     SCENE --rays RAYS.npy --out HITS.npy [--backend cpu|gpu|brute] [ADS options] [--traversal linear|hiz]
//! dirt bench     SCENE [ADS options] [--rays N] [--seed S] [--kind K] [--backends cpu,gpu,brute] [--repeat K] [--json FILE]
//! dirt triangles SCENE --out TRIS.npy
//! dirt info      SCENE [ADS options]
//! ADS options:   [--views cube|single] [--resolution N] [--buckets B] [--tile S] [--center X,Y,Z]
//! ```
//!
//! File formats are described in [`npy`]. Timings and counts go to stderr,
//! `dirt info` and `dirt bench` print to stdout.

mod bench;
mod eval;
mod explain;
mod raygen;
mod render;

use dirt_cli::npy;

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use dirt_core::{AdsParams, BuildTimings, Traversal, ViewsKind};
use dirt_cpu::Ads;
use dirt_gpu::{Gpu, GpuAds};
use dirt_math::{Hit, Ray, Vec3};
use dirt_scene::{CameraKind, Scene};

use crate::raygen::RayKind;

#[derive(Debug, Parser)]
#[command(
    name = "dirt",
    version,
    about = "DIRT: Deferred Image-based Ray Tracing",
    long_about = "DIRT: Deferred Image-based Ray Tracing.\n\n\
        Traces a buffer of rays (float32 .npy, one row `ox oy oz tmin dx dy dz tmax` per ray) \
        against a scene and writes the closest hits (uint32 .npy, one row `prim t u v` per ray, \
        floats as bits, prim = 0xFFFFFFFF for a miss).",
    after_help = "Typical use:\n  \
        dirt rays cornell --out rays.npy\n  \
        dirt trace cornell --rays rays.npy --out hits.npy\n  \
        dirt trace cornell --rays rays.npy --out gpu.npy --backend gpu\n  \
        dirt trace cornell --rays rays.npy --out truth.npy --backend brute\n  \
        dirt bench cornell --rays 200000 --repeat 3"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Trace a rays file against a scene and write the closest hits.
    Trace(TraceArgs),
    /// Write the scene's world-space triangles (float32, shape (T, 9)) in the flattened order.
    Triangles(TrianglesArgs),
    /// Print the triangle count, the bounds and the acceleration structure's statistics and memory.
    Info(InfoArgs),
    /// Write a file of test rays for a scene (deterministic for a seed).
    Rays(RaysArgs),
    /// Benchmark build and trace of every backend side by side on generated rays,
    /// with their errors against brute force (a Markdown table on stdout).
    Bench(bench::BenchArgs),
    /// Evaluate DIRT against brute force, obvhs and Embree over scenes and a parameter
    /// grid; write CSV, JSON, plots and a Markdown report.
    Eval(eval::EvalArgs),
    /// Render an image: a path tracer whose every ray is traced through DIRT
    /// (or the reference BVH, or brute force); tone-mapped PNG, linear EXR.
    Render(render::RenderArgs),
}

/// The positional scene argument shared by every subcommand.
#[derive(Debug, Args)]
struct SceneArg {
    /// A built-in scene (cornell, layers, foliage, spheres) or a .gltf/.glb/.obj file.
    #[arg(value_name = "SCENE", default_value = dirt_scene::DEFAULT_SCENE)]
    scene: String,
}

#[derive(Debug, Args)]
struct TraceArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Rays: float32 .npy of shape (N, 8), rows `ox oy oz tmin dx dy dz tmax`, C order.
    #[arg(long, value_name = "RAYS.npy")]
    rays: PathBuf,
    /// Where to write the hits: uint32 .npy of shape (N, 4), rows `prim, bits(t), bits(u), bits(v)`.
    #[arg(long, value_name = "HITS.npy")]
    out: PathBuf,
    /// Which tracer runs the rays.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    backend: Backend,
    #[command(flatten)]
    ads: AdsArgs,
    /// How the cpu and gpu backends walk the tiles a ray crosses.
    #[arg(long, value_enum, default_value_t = TraversalArg::from(Traversal::default()))]
    traversal: TraversalArg,
}

#[derive(Debug, Args)]
struct TrianglesArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Where to write the triangles: float32 .npy of shape (T, 9), rows `v0 v1 v2`.
    #[arg(long, value_name = "TRIS.npy")]
    out: PathBuf,
}

#[derive(Debug, Args)]
struct InfoArgs {
    #[command(flatten)]
    scene: SceneArg,
    #[command(flatten)]
    ads: AdsArgs,
    /// Also say what the structure leaves out for this scene and why, what it
    /// chose and why (with the cost model's ranking), measured against building every view.
    #[arg(long)]
    explain: bool,
    /// Rays per frame the cost model of --explain and --auto predicts for.
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    rays_per_frame: u64,
}

#[derive(Debug, Args)]
struct RaysArgs {
    #[command(flatten)]
    scene: SceneArg,
    /// Where to write the rays: float32 .npy of shape (N, 8).
    #[arg(long, value_name = "RAYS.npy")]
    out: PathBuf,
    /// Number of rays.
    #[arg(long, default_value_t = 100_000)]
    count: usize,
    /// Seed of the generator: the same seed gives the same file.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Which rays: `mixed` interleaves every family (random, axis-aligned, aimed at vertices
    /// and edge midpoints, grazing along triangle planes, tmax-limited segments, bounces, camera).
    #[arg(long, value_enum, default_value = "mixed")]
    kind: RayKind,
}

/// Build parameters of the acceleration structure; defaults are `AdsParams::default()`.
#[derive(Debug, Args)]
struct AdsArgs {
    /// Views covering the scene.
    #[arg(long, value_enum, default_value_t = ViewsArg::from(AdsParams::default().views))]
    views: ViewsArg,
    /// Face resolution in pixels (square faces).
    #[arg(long, value_name = "N", default_value_t = AdsParams::default().resolution)]
    resolution: u32,
    /// Depth buckets per tile.
    #[arg(long, value_name = "B", default_value_t = AdsParams::default().buckets)]
    buckets: u32,
    /// Tile size in pixels.
    #[arg(long, value_name = "S", default_value_t = AdsParams::default().tile)]
    tile: u32,
    /// Centre of the views as "X,Y,Z" [default: centre of the scene bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_center, allow_hyphen_values = true)]
    center: Option<Vec3>,
    /// Choose the views (cube or single, both exact without --center), resolution and B
    /// not given on the command line with the cost model (dirt_cpu::cost), from a
    /// sample of rays; the hits are the same.
    #[arg(long)]
    auto: bool,
    /// Which of the options above were given on the command line.
    #[arg(skip)]
    given: explain::Given,
}

impl AdsArgs {
    /// Records which options the command line gave (the rest are defaults).
    fn note_given(&mut self, m: &ArgMatches) {
        let given = |id: &str| m.value_source(id) == Some(ValueSource::CommandLine);
        self.given = explain::Given {
            views: given("views"),
            resolution: given("resolution"),
            buckets: given("buckets"),
            tile: given("tile"),
        };
    }

    /// The parameters for `scene`: [`AdsArgs::params`], or with `--auto` the
    /// cost model's cheapest candidate among those that keep every given option.
    fn params_for(&self, scene: &Scene, rays_per_frame: u64) -> Result<AdsParams> {
        let base = self.params();
        if !self.auto {
            return Ok(base);
        }
        let g = self.given;
        let cands: Vec<AdsParams> = dirt_cpu::cost::candidates(&base, !g.views)
            .into_iter()
            .map(|c| AdsParams {
                resolution: if g.resolution {
                    base.resolution
                } else {
                    c.resolution
                },
                buckets: if g.buckets { base.buckets } else { c.buckets },
                tile: base.tile,
                ..c
            })
            .filter(|c| c.validate().is_ok())
            .collect();
        let mut uniq: Vec<AdsParams> = Vec::new();
        for c in cands {
            if !uniq.contains(&c) {
                uniq.push(c);
            }
        }
        let sample = raygen::generate(&scene.triangles, None, RayKind::Mixed, 2000, 1)
            .map_err(anyhow::Error::msg)
            .context("--auto: cannot make the ray sample")?;
        let ranked = dirt_cpu::cost::choose(
            &scene.triangles,
            &sample,
            rays_per_frame,
            Traversal::HiZ,
            &dirt_cpu::cost::CostModel::CALIBRATED,
            &uniq,
        )
        .context("--auto: cannot build the candidates")?;
        let best = ranked.first().map_or(base, |c| c.params);
        eprintln!(
            "--auto: {:?} views, resolution {}, B = {}, S = {} (cheapest predicted frame of {rays_per_frame} rays among {} candidates)",
            best.views,
            best.resolution,
            best.buckets,
            best.tile,
            ranked.len()
        );
        Ok(best)
    }

    fn params(&self) -> AdsParams {
        AdsParams {
            views: self.views.into(),
            resolution: self.resolution,
            buckets: self.buckets,
            tile: self.tile,
            center: self.center,
        }
    }
}

/// The tracer behind `dirt trace`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// DIRT on the CPU (dirt-cpu).
    Cpu,
    /// DIRT on the GPU (dirt-gpu, wgpu; set WGPU_BACKEND=vulkan). Without a usable
    /// adapter it says so and runs the cpu backend, whose hits are the same bits.
    Gpu,
    /// Every ray against every triangle with the same triangle test: the ground truth.
    Brute,
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
            Backend::Brute => "brute",
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ViewsArg {
    /// Six 90° views around the centre.
    Cube,
    /// One view outside the scene, fitted to its bounds.
    Single,
}

impl From<ViewsKind> for ViewsArg {
    fn from(v: ViewsKind) -> Self {
        match v {
            ViewsKind::Cube => ViewsArg::Cube,
            ViewsKind::Single => ViewsArg::Single,
        }
    }
}

impl From<ViewsArg> for ViewsKind {
    fn from(v: ViewsArg) -> Self {
        match v {
            ViewsArg::Cube => ViewsKind::Cube,
            ViewsArg::Single => ViewsKind::Single,
        }
    }
}

impl fmt::Display for ViewsArg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ViewsArg::Cube => "cube",
            ViewsArg::Single => "single",
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum TraversalArg {
    /// Conservative 2D DDA over the finest tiles.
    Linear,
    /// Hierarchical stepping over the Hi-Z pyramid.
    #[value(name = "hiz")]
    HiZ,
}

impl From<Traversal> for TraversalArg {
    fn from(t: Traversal) -> Self {
        match t {
            Traversal::Linear => TraversalArg::Linear,
            Traversal::HiZ => TraversalArg::HiZ,
        }
    }
}

impl From<TraversalArg> for Traversal {
    fn from(t: TraversalArg) -> Self {
        match t {
            TraversalArg::Linear => Traversal::Linear,
            TraversalArg::HiZ => Traversal::HiZ,
        }
    }
}

impl fmt::Display for TraversalArg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TraversalArg::Linear => "linear",
            TraversalArg::HiZ => "hiz",
        })
    }
}

/// Parses `--center X,Y,Z`.
fn parse_center(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers X,Y,Z (e.g. 0,1,0.5), got {} value(s) in {s:?}",
            parts.len()
        ));
    }
    let mut c = [0.0f32; 3];
    for ((slot, part), axis) in c.iter_mut().zip(&parts).zip(["X", "Y", "Z"]) {
        let v: f32 = part.parse().map_err(|_| {
            format!("{axis} = {part:?} is not a number; expected X,Y,Z (e.g. 0,1,0.5)")
        })?;
        if !v.is_finite() {
            return Err(format!("{axis} = {part:?} is not finite"));
        }
        *slot = v;
    }
    Ok(Vec3::from_array(c))
}

fn main() -> ExitCode {
    let matches = Cli::command().get_matches();
    let mut cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    if let Some((_, sub)) = matches.subcommand() {
        match &mut cli.command {
            Command::Trace(a) => a.ads.note_given(sub),
            Command::Info(a) => a.ads.note_given(sub),
            _ => {}
        }
    }
    let result = match cli.command {
        Command::Trace(args) => trace(&args),
        Command::Triangles(args) => triangles(&args),
        Command::Info(args) => info(&args),
        Command::Rays(args) => rays(&args),
        Command::Bench(args) => bench::bench(&args),
        Command::Eval(args) => eval::eval(&args),
        Command::Render(args) => render::render(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn open_scene(spec: &str) -> Result<Scene> {
    let scene = dirt_scene::open(spec).with_context(|| format!("cannot open scene {spec:?}"))?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    Ok(scene)
}

fn millis(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn build_ads(scene: &Scene, ads: &AdsArgs) -> Result<(Ads, Duration)> {
    let params = ads.params_for(scene, 1_000_000)?;
    let start = Instant::now();
    let built = Ads::build(&scene.triangles, &params).with_context(|| {
        format!(
            "cannot build the acceleration structure of {} ({params:?})",
            scene.name
        )
    })?;
    Ok((built, start.elapsed()))
}

fn trace(args: &TraceArgs) -> Result<()> {
    let scene = open_scene(&args.scene.scene)?;
    let rays = npy::read_rays(&args.rays)?;
    eprintln!(
        "scene {}: {} triangles; {} rays from {}; backend {}",
        scene.name,
        scene.triangles.len(),
        rays.len(),
        args.rays.display(),
        args.backend
    );
    let traversal = Traversal::from(args.traversal);
    let (hits, build, trace_time) = match args.backend {
        Backend::Cpu => trace_cpu(&scene, &args.ads, &rays, traversal)?,
        Backend::Gpu => match open_gpu() {
            Ok(gpu) => {
                eprintln!("{}", gpu_line(&gpu));
                trace_gpu(&gpu, &scene, &args.ads, &rays, traversal)?
            }
            Err(reason) => {
                eprintln!("{}", fallback_line(&reason));
                trace_cpu(&scene, &args.ads, &rays, traversal)?
            }
        },
        Backend::Brute => {
            let start = Instant::now();
            let hits = dirt_cpu::brute_force::trace(&scene.triangles, &rays);
            (hits, None, start.elapsed())
        }
    };
    check_hit_count(&rays, &hits, args.backend)?;
    npy::write_hits(&args.out, &hits)?;

    match build {
        Some((d, stages)) => eprintln!(
            "build: {:.3} ms (fill_depth {:.3} ms, mip_depth {:.3} ms, fill_primitives {:.3} ms)",
            millis(d),
            millis(stages.fill_depth),
            millis(stages.mip_depth),
            millis(stages.fill_primitives)
        ),
        None => eprintln!("build: none (brute force)"),
    }
    let secs = trace_time.as_secs_f64();
    let mrays = if secs > 0.0 {
        rays.len() as f64 / secs / 1e6
    } else {
        f64::INFINITY
    };
    eprintln!("trace: {:.3} ms, {mrays:.3} Mrays/s", millis(trace_time));
    let hit_count = hits.iter().filter(|h| h.is_hit()).count();
    let percent = if rays.is_empty() {
        0.0
    } else {
        100.0 * hit_count as f64 / rays.len() as f64
    };
    eprintln!("hits: {hit_count} of {} rays ({percent:.2} %)", rays.len());
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

/// Hits, the build's wall time and stage times (none for brute force), and the trace's wall time.
type Traced = (Vec<Hit>, Option<(Duration, BuildTimings)>, Duration);

fn trace_cpu(scene: &Scene, ads: &AdsArgs, rays: &[Ray], traversal: Traversal) -> Result<Traced> {
    let (ads, build_time) = build_ads(scene, ads)?;
    let start = Instant::now();
    let hits = dirt_cpu::trace(&ads, &scene.triangles, rays, traversal);
    Ok((hits, Some((build_time, ads.timings)), start.elapsed()))
}

fn trace_gpu(
    gpu: &Gpu,
    scene: &Scene,
    ads: &AdsArgs,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<Traced> {
    let (gpu_ads, build_time) = build_gpu_ads(gpu, scene, ads)?;
    let start = Instant::now();
    let traced = dirt_gpu::trace::trace_report(gpu, &gpu_ads, rays, traversal)
        .with_context(|| format!("cannot trace on the GPU ({})", gpu.describe()))?;
    if traced.cpu_finished > 0 {
        eprintln!(
            "gpu: {} rays spent their GPU work budget and were finished by the CPU reference",
            traced.cpu_finished
        );
    }
    let hits = traced.hits;
    let t = gpu_ads.timings;
    let stages = BuildTimings {
        fill_depth: t.fill_depth,
        mip_depth: t.mip_depth,
        fill_primitives: t.fill_primitives,
    };
    Ok((hits, Some((build_time, stages)), start.elapsed()))
}

fn build_gpu_ads(gpu: &Gpu, scene: &Scene, ads: &AdsArgs) -> Result<(GpuAds, Duration)> {
    let params = ads.params_for(scene, 1_000_000)?;
    let start = Instant::now();
    let built = GpuAds::build(gpu, &scene.triangles, &params).with_context(|| {
        format!(
            "cannot build the acceleration structure of {} on the GPU ({params:?})",
            scene.name
        )
    })?;
    Ok((built, start.elapsed()))
}

/// Opens the GPU; the error is the reason in words. A panic inside the driver
/// stack counts as no usable GPU, not as a crash.
fn open_gpu() -> std::result::Result<Gpu, String> {
    match std::panic::catch_unwind(Gpu::new) {
        Ok(Ok(gpu)) => Ok(gpu),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .map_or_else(
                || "the GPU stack panicked".to_owned(),
                |m| format!("the GPU stack panicked: {m}"),
            )),
    }
}

/// The line naming the adapter when the GPU is used.
fn gpu_line(gpu: &Gpu) -> String {
    format!(
        "gpu adapter: {}; {}",
        gpu.describe(),
        if gpu.exact {
            "exact (NoContraction SPIR-V: the CPU's bits are promised)"
        } else {
            "not exact (plain WGSL: hits may differ from the CPU's in the last bits)"
        }
    )
}

/// The line saying that the GPU is not used, and why.
fn fallback_line(reason: &str) -> String {
    format!("dirt: no usable GPU ({reason}); falling back to the CPU backend")
}

/// A backend must answer every ray exactly once.
fn check_hit_count(rays: &[Ray], hits: &[Hit], backend: Backend) -> Result<()> {
    if hits.len() != rays.len() {
        bail!(
            "backend {backend} returned {} hits for {} rays",
            hits.len(),
            rays.len()
        );
    }
    Ok(())
}

fn triangles(args: &TrianglesArgs) -> Result<()> {
    let scene = open_scene(&args.scene.scene)?;
    npy::write_triangles(&args.out, &scene.triangles)?;
    eprintln!(
        "scene {}: wrote {} triangles to {}",
        scene.name,
        scene.triangles.len(),
        args.out.display()
    );
    Ok(())
}

fn info(args: &InfoArgs) -> Result<()> {
    let scene = open_scene(&args.scene.scene)?;
    let bounds = scene.bounds();
    println!("scene: {}", scene.name);
    println!("triangles: {}", scene.triangles.len());
    if bounds.is_empty() {
        println!("bounds: empty");
    } else {
        println!(
            "bounds: min {} max {} (extent {})",
            bounds.min,
            bounds.max,
            bounds.extent()
        );
    }
    let params = args.ads.params_for(&scene, args.rays_per_frame)?;
    let center = params.center.map_or_else(
        || format!("{} (bounds centre)", bounds.center()),
        |c| c.to_string(),
    );
    println!(
        "ads: {} views, resolution {}, {} buckets, tile {}, centre {center}",
        args.ads.views, params.resolution, params.buckets, params.tile
    );
    let start = Instant::now();
    let ads = Ads::build(&scene.triangles, &params)
        .with_context(|| format!("cannot build the acceleration structure ({params:?})"))?;
    println!("build: {:.3} ms", millis(start.elapsed()));
    println!("stats:\n{}", ads.stats());
    println!("memory:\n{}", ads.memory());
    if args.explain {
        print!(
            "{}",
            explain::explain(&scene, &params, args.ads.given, args.rays_per_frame)?
        );
    }
    Ok(())
}

fn scene_camera(scene: &Scene) -> Option<raygen::Camera> {
    let cam = scene.cameras.first()?;
    match cam.kind {
        CameraKind::Perspective => raygen::Camera::perspective(
            cam.position,
            cam.forward,
            cam.up,
            cam.yfov_radians,
            cam.aspect.unwrap_or(4.0 / 3.0),
        ),
        CameraKind::Orthographic { xmag, ymag } => {
            raygen::Camera::orthographic(cam.position, cam.forward, cam.up, xmag, ymag)
        }
    }
}

fn rays(args: &RaysArgs) -> Result<()> {
    let scene = open_scene(&args.scene.scene)?;
    let rays = raygen::generate(
        &scene.triangles,
        scene_camera(&scene),
        args.kind,
        args.count,
        args.seed,
    )
    .map_err(anyhow::Error::msg)
    .with_context(|| format!("cannot make rays for scene {}", scene.name))?;
    write_rays(&args.out, &rays)?;
    eprintln!(
        "scene {}: wrote {} {} rays (seed {}) to {}",
        scene.name,
        rays.len(),
        args.kind
            .to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_owned()),
        args.seed,
        args.out.display()
    );
    Ok(())
}

fn write_rays(path: &Path, rays: &[Ray]) -> Result<()> {
    npy::write_rays(path, rays)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn center_parses() {
        assert_eq!(parse_center("1,2,3"), Ok(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(
            parse_center(" -1.5, 0 ,2e-3"),
            Ok(Vec3::new(-1.5, 0.0, 2e-3))
        );
    }

    #[test]
    fn center_errors_are_clear() {
        let err = parse_center("1,2").expect_err("two values");
        assert!(
            err.contains("three comma-separated") && err.contains("2 value(s)"),
            "{err}"
        );
        let err = parse_center("1,2,3,4").expect_err("four values");
        assert!(err.contains("4 value(s)"), "{err}");
        let err = parse_center("1,y,3").expect_err("not a number");
        assert!(err.contains("Y = \"y\" is not a number"), "{err}");
        let err = parse_center("1,2,inf").expect_err("inf");
        assert!(err.contains("Z = \"inf\" is not finite"), "{err}");
        let err = parse_center("").expect_err("empty");
        assert!(err.contains("1 value(s)"), "{err}");
    }

    #[test]
    fn defaults_come_from_ads_params() {
        let cli = Cli::try_parse_from(["dirt", "info", "cornell"]).expect("parse");
        let Command::Info(args) = cli.command else {
            panic!("not info")
        };
        assert_eq!(args.ads.params(), AdsParams::default());
        let cli = Cli::try_parse_from(["dirt", "trace", "--rays", "r.npy", "--out", "h.npy"])
            .expect("parse");
        let Command::Trace(args) = cli.command else {
            panic!("not trace")
        };
        assert_eq!(args.scene.scene, dirt_scene::DEFAULT_SCENE);
        assert_eq!(args.backend, Backend::Cpu);
        assert_eq!(Traversal::from(args.traversal), Traversal::default());
    }

    #[test]
    fn ads_options_parse() {
        let cli = Cli::try_parse_from([
            "dirt",
            "trace",
            "layers",
            "--rays",
            "r.npy",
            "--out",
            "h.npy",
            "--backend",
            "brute",
            "--views",
            "single",
            "--resolution",
            "64",
            "--buckets",
            "4",
            "--tile",
            "2",
            "--traversal",
            "hiz",
            "--center",
            "-1,0.5,2",
        ])
        .expect("parse");
        let Command::Trace(args) = cli.command else {
            panic!("not trace")
        };
        assert_eq!(args.backend, Backend::Brute);
        assert_eq!(Traversal::from(args.traversal), Traversal::HiZ);
        let p = args.ads.params();
        assert_eq!(p.views, ViewsKind::Single);
        assert_eq!((p.resolution, p.buckets, p.tile), (64, 4, 2));
        assert_eq!(p.center, Some(Vec3::new(-1.0, 0.5, 2.0)));
    }

    #[test]
    fn bad_center_is_a_usage_error() {
        let err =
            Cli::try_parse_from(["dirt", "info", "--center", "1;2;3"]).expect_err("bad centre");
        assert!(err.to_string().contains("X,Y,Z"), "{err}");
    }
}
