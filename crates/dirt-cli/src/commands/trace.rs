//! `dirt trace`: a rays file in, the closest hit of every ray out, through
//! DIRT on the CPU or the GPU, or brute force.

use std::fmt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use dirt_core::{BuildReport, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_cpu::brute_force::Brute;
use dirt_gpu::{DirtGpu, Gpu};
use dirt_math::{Hit, Ray};

use crate::args::{AdsArgs, SceneArg};
use crate::commands::millis;
use crate::gpu::{fallback_line, gpu_line};
use dirt_cli::npy;

#[derive(Debug, Args)]
pub struct TraceArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    /// Rays: float32 .npy of shape (N, 8), rows `ox oy oz tmin dx dy dz tmax`, C order.
    #[arg(long, value_name = "RAYS.npy")]
    pub rays: PathBuf,
    /// Where to write the hits: uint32 .npy of shape (N, 4), rows `prim, bits(t), bits(u), bits(v)`.
    #[arg(long, value_name = "HITS.npy")]
    pub out: PathBuf,
    /// Which tracer runs the rays.
    #[arg(long, value_enum, default_value_t = TraceBackend::Cpu)]
    pub backend: TraceBackend,
    #[command(flatten)]
    pub ads: AdsArgs,
    /// How the cpu and gpu backends walk the tiles a ray crosses [default: linear], and the
    /// mmrt and single-layer backends their pixels [default: linear for mmrt, hiz for
    /// single-layer; the same hits either way].
    #[arg(long, value_enum)]
    pub traversal: Option<Traversal>,
    /// Cells per triangle of the grid backend.
    #[arg(long, value_name = "RHO", default_value_t = dirt_cpu::grid::DEFAULT_DENSITY)]
    pub density: f32,
    /// Thickness behind every fragment of the mmrt and single-layer backends,
    /// as a fraction of the scene's diagonal.
    #[arg(long, value_name = "F", default_value_t = dirt_cpu::screen_space::DEFAULT_THICKNESS)]
    pub thickness: f32,
    /// Most pixels the mmrt and single-layer backends march per view (0: unbounded).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub steps: u32,
    /// Eye of the single-layer backend's view [default: the scene's first camera].
    #[arg(long, value_name = "X,Y,Z", value_parser = crate::args::parse_point, allow_hyphen_values = true)]
    pub eye: Option<dirt_math::Vec3>,
}

/// The tracer behind `dirt trace` and `dirt bench`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// DIRT on the CPU (dirt-cpu).
    Cpu,
    /// DIRT on the GPU (dirt-gpu, wgpu; set WGPU_BACKEND=vulkan). Without a usable
    /// adapter it says so and runs the cpu backend, whose hits are the same bits.
    Gpu,
    /// Every ray against every triangle with the same triangle test: the ground truth.
    Brute,
}

/// The tracers of `dirt trace`: DIRT's backends, brute force, and the
/// evaluation's peers (BVHs with their own triangle tests: their hits may
/// differ from DIRT's in the last bits, or on a shared edge), so that whole
/// processes can be compared on the same files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TraceBackend {
    /// DIRT on the CPU (dirt-cpu).
    Cpu,
    /// DIRT on the GPU (dirt-gpu, wgpu; set WGPU_BACKEND=vulkan). Without a usable
    /// adapter it says so and runs the cpu backend, whose hits are the same bits.
    Gpu,
    /// Every ray against every triangle with the same triangle test: the ground truth.
    Brute,
    /// obvhs's CWBVH (a peer of the evaluation; its own triangle test).
    Obvhs,
    /// Embree 3 (a peer of the evaluation; its own triangle test; only in a `dirt`
    /// built with the `embree` feature, as scripts/eval builds it).
    Embree,
    /// The compact uniform grid (Lagae and Dutré; `--density` cells per
    /// triangle), with DIRT's triangle test: the same hits as brute force.
    Grid,
    /// APPROXIMATE: the multiview multilayer A-buffer of MMRT (fragments at
    /// pixel centres of the cubemap, `--resolution`, `--buckets`, hits within
    /// `--thickness`, `--steps` per view). Its hits may differ from brute force's.
    Mmrt,
    /// APPROXIMATE: one depth layer seen from `--eye` (screen-space tracing,
    /// `--resolution`, `--thickness`, `--steps`): what the view does not see is missed.
    SingleLayer,
}

impl fmt::Display for TraceBackend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TraceBackend::Cpu => "cpu",
            TraceBackend::Gpu => "gpu",
            TraceBackend::Brute => "brute",
            TraceBackend::Obvhs => "obvhs",
            TraceBackend::Embree => "embree",
            TraceBackend::Grid => "grid",
            TraceBackend::Mmrt => "mmrt",
            TraceBackend::SingleLayer => "single-layer",
        })
    }
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

pub fn trace(args: &TraceArgs) -> Result<()> {
    let scene = args.scene.open()?;
    let rays = npy::read_rays(&args.rays)?;
    eprintln!(
        "scene {}: {} triangles; {} rays from {}; backend {}",
        scene.name,
        scene.triangles.len(),
        rays.len(),
        args.rays.display(),
        args.backend
    );
    let tris = &scene.triangles;
    // A peer: the evaluation's tracer of that name, if this build has it.
    let peer = match args.backend {
        TraceBackend::Obvhs | TraceBackend::Embree => {
            let name = args.backend.to_string();
            let Some(p) = dirt_eval::peers::available()
                .into_iter()
                .find(|p| p.name == name)
            else {
                anyhow::bail!(
                    "this dirt was built without the {name} peer (build with `cargo build --release -p dirt-cli --features embree`)"
                );
            };
            Some(
                (p.make)(rayon::current_num_threads())
                    .with_context(|| format!("cannot start {name}"))?,
            )
        }
        TraceBackend::Grid => Some(Box::new(
            dirt_cpu::grid::Grid::new(args.density).context("--density")?,
        ) as Box<dyn Tracer>),
        TraceBackend::Mmrt | TraceBackend::SingleLayer => {
            Some(Box::new(screen_space(args, &scene)?) as Box<dyn Tracer>)
        }
        _ => None,
    };
    let gpu = match args.backend {
        TraceBackend::Gpu => match Gpu::open() {
            Ok(gpu) => {
                eprintln!("{}", gpu_line(&gpu));
                Some(gpu)
            }
            Err(reason) => {
                eprintln!("{}", fallback_line(&reason));
                None
            }
        },
        _ => None,
    };
    // Brute force builds nothing, so it has no parameters (and no cost model).
    let (params, chosen) = match args.backend {
        TraceBackend::Brute
        | TraceBackend::Obvhs
        | TraceBackend::Embree
        | TraceBackend::Grid
        | TraceBackend::Mmrt
        | TraceBackend::SingleLayer => (None, None),
        _ => {
            // On the GPU the choice must fit the device's bindings.
            let limits = gpu.as_ref().map(|g| g.binding_limits());
            let (p, ads) =
                args.ads
                    .choose_within(&scene, rays.len() as u64, Some(&rays), limits)?;
            (Some(p), ads)
        }
    };
    // DIRT on the CPU at the cost model's choice walks with the faster traversal.
    let on_cpu = chosen.as_ref().filter(|_| gpu.is_none());
    let traversal = args
        .ads
        .traversal(args.traversal, on_cpu, &scene, Some(&rays))?;
    let (mut tracer, built, build_time): (Box<dyn Tracer + '_>, BuildReport, Duration) =
        match (params, &gpu, chosen) {
            // The cost model built the CPU structure of its choice: keep it.
            (Some(_), None, Some(ads)) => {
                let built = BuildReport {
                    stages: ads.timings.stages(),
                    memory: Some(ads.memory().total()),
                };
                let time = ads.timings.total();
                eprintln!("build: the structure the cost model built while choosing is kept");
                (
                    Box::new(DirtCpu::from_ads(ads, tris, traversal)),
                    built,
                    time,
                )
            }
            (params, gpu, _) => {
                let mut tracer: Box<dyn Tracer + '_> = match (params, gpu) {
                    (None, _) => match peer {
                        Some(peer) => peer,
                        None => Box::new(Brute::default()),
                    },
                    (Some(p), Some(g)) => Box::new(DirtGpu::new(g, p, traversal)),
                    (Some(p), None) => Box::new(DirtCpu::new(p, traversal)),
                };
                let start = Instant::now();
                let built = tracer.build(tris).with_context(|| {
                    format!(
                        "cannot build the acceleration structure of {} with {} ({params:?})",
                        scene.name,
                        tracer.name()
                    )
                })?;
                (tracer, built, start.elapsed())
            }
        };
    let start = Instant::now();
    let mut hits = vec![Hit::MISS; rays.len()];
    let report = tracer
        .trace_into(&rays, &mut hits, None)
        .with_context(|| format!("cannot trace ({})", tracer.name()))?;
    let trace_time = start.elapsed();
    if report.continuation_rounds > 0 {
        eprintln!(
            "gpu: rays that spent a dispatch's work budget took {} continuation rounds on the GPU",
            report.continuation_rounds
        );
    }
    npy::write_hits(&args.out, &hits)?;
    print_build(&built, build_time, args.backend);
    print_trace(&rays, &hits, trace_time);
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

/// The approximate screen-space tracer the arguments ask for.
fn screen_space(
    args: &TraceArgs,
    scene: &dirt_scene::Scene,
) -> Result<dirt_cpu::screen_space::ScreenSpace> {
    use dirt_cpu::screen_space::{ScreenSpace, ScreenSpaceParams};
    let mut params = if args.backend == TraceBackend::Mmrt {
        ScreenSpaceParams::mmrt(args.ads.resolution, args.ads.buckets, args.thickness)
    } else {
        let Some(eye) = args
            .eye
            .or_else(|| scene.cameras.first().map(|c| c.position))
        else {
            anyhow::bail!(
                "--backend single-layer needs --eye X,Y,Z: the scene {} has no camera",
                scene.name
            );
        };
        ScreenSpaceParams::single_layer(eye, args.ads.resolution, args.thickness)
    };
    params.max_steps = args.steps;
    if let Some(t) = args.traversal {
        params.hiz = t == Traversal::HiZ;
    }
    eprintln!(
        "{} is approximate: its hits may differ from brute force's ({})",
        args.backend,
        params.label()
    );
    ScreenSpace::new(params).with_context(|| format!("--backend {}", args.backend))
}

fn print_build(built: &BuildReport, total: Duration, backend: TraceBackend) {
    if backend == TraceBackend::Brute {
        eprintln!("build: none (brute force)");
        return;
    }
    if built.stages.is_empty() {
        eprintln!("build: {:.3} ms", millis(total));
        return;
    }
    let stages: Vec<String> = built
        .stages
        .iter()
        .map(|(name, d)| format!("{name} {:.3} ms", millis(*d)))
        .collect();
    eprintln!("build: {:.3} ms ({})", millis(total), stages.join(", "));
}

fn print_trace(rays: &[Ray], hits: &[Hit], trace_time: Duration) {
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
}
