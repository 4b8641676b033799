//! The evaluation run: scenes × parameter grid × ray types × traversals, the
//! peers, the grid's densities, the approximate methods ([`crate::approx`])
//! and the GPU backend beside DIRT on the CPU, all against brute force.
//!
//! Every tracer is measured through [`crate::measure`] as a `&mut dyn Tracer`;
//! the peers come from [`crate::peers::available`] (where a new tracer's one
//! line goes). This module uses [`crate::dynamic`], [`crate::leave_out`] and
//! [`crate::renders`]; they never use it.

use std::path::PathBuf;
use std::time::Instant;

use dirt_core::{AdsParams, CoreError, Tracer, Traversal, ViewsKind};
use dirt_cpu::brute_force::Brute;
use dirt_cpu::screen_space::ScreenSpace;
use dirt_cpu::{Ads, DirtCpu};
use dirt_gpu::DirtGpu;
use dirt_math::{Hit, Ray, Triangle};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;

use crate::approx::ApproxPoint;
use crate::dynamic::{DynamicConfig, DynamicRow};
use crate::measure::{self, BuildRow, PerRay, Setting, StatsPass, Structure, Subject, TraceRow};
use crate::peers::Peer;
use crate::rays::{self, RayType};
use crate::renders::{RenderConfig, RenderReference, RenderRow};
use crate::{EvalError, Match, compare};

/// One point of the parameter grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPoint {
    pub params: AdsParams,
    /// Place the single view at the scene camera's eye (the paper's
    /// camera-centred setting; not exact: hits outside its frustum are lost).
    pub at_camera: bool,
}

impl GridPoint {
    pub fn new(views: ViewsKind, resolution: u32, buckets: u32, tile: u32) -> GridPoint {
        GridPoint {
            params: AdsParams {
                views,
                resolution,
                buckets,
                tile,
                center: None,
                axis: None,
            },
            at_camera: false,
        }
    }

    /// What the reports call it.
    pub fn setting(&self) -> Setting {
        Setting::dirt(&self.params, self.at_camera)
    }

    /// A short name, e.g. `cube r128 B8 S1`.
    pub fn label(&self) -> String {
        self.setting().label
    }
}

/// Which scenes the GPU backend (lavapipe here) runs on, and how many rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuConfig {
    /// Scenes with more triangles are skipped.
    pub max_triangles: usize,
    /// Scenes whose default structure has more list nodes are skipped
    /// (lavapipe's build time grows with them: `layers` takes ~30 s).
    pub max_nodes: usize,
    /// Rays per ray type.
    pub rays: usize,
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct EvalConfig {
    /// `(label, spec)`: a built-in name or a glTF/OBJ path.
    pub scenes: Vec<(String, String)>,
    pub grid: Vec<GridPoint>,
    pub traversals: Vec<Traversal>,
    /// Rays per ray type.
    pub rays: usize,
    /// Brute-force budget per ray type in ray/triangle tests: the first
    /// `budget / triangles` rays (at least 200) are compared with brute force.
    pub truth_tests: u64,
    /// Builds and traces per measurement; medians are reported.
    pub repeat: u32,
    pub gpu: Option<GpuConfig>,
    /// The peers measured beside DIRT (default: [`crate::peers::available`]).
    pub peers: Vec<Peer>,
    /// Alternated rounds of DIRT at the headline's setting beside each peer
    /// ([`crate::side`]); 0 leaves them out.
    pub side_rounds: u32,
    /// Densities (cells per triangle) of the compact grid measured besides
    /// the peer's ([`crate::peers::GRID`]): its knob, swept.
    pub grid_densities: Vec<f32>,
    /// The approximate methods' settings ([`crate::approx`]).
    pub approx: Vec<ApproxPoint>,
    pub dynamic: Option<DynamicConfig>,
    pub render: Option<RenderConfig>,
    pub seed: u64,
    /// Whether a progress bar may be drawn (only ever on a terminal).
    pub progress: bool,
    /// Describes the grid in the report.
    pub grid_name: String,
}

/// The default parameters (`AdsParams::default()`): cube, 128, B 8, S 1.
pub fn default_point() -> GridPoint {
    GridPoint {
        params: AdsParams::default(),
        at_camera: false,
    }
}

impl EvalConfig {
    /// A tiny grid for CI and a first look: the default setting, B 1 and 32,
    /// S 2, a single view; no GPU; a small deforming scene.
    pub fn quick() -> EvalConfig {
        let d = default_point();
        let mut grid = vec![d];
        for b in [1, 32] {
            grid.push(GridPoint::new(ViewsKind::Cube, 128, b, 1));
        }
        grid.push(GridPoint::new(ViewsKind::Cube, 128, 8, 2));
        grid.push(GridPoint::new(ViewsKind::Single, 128, 8, 1));
        EvalConfig {
            scenes: vec![
                ("cornell".into(), "cornell".into()),
                ("foliage".into(), "foliage".into()),
            ],
            grid,
            traversals: vec![Traversal::Linear, Traversal::HiZ],
            rays: 4000,
            truth_tests: 20_000_000,
            repeat: 1,
            gpu: None,
            peers: crate::peers::available(),
            side_rounds: 2,
            grid_densities: Vec::new(),
            approx: crate::approx::quick(),
            dynamic: Some(DynamicConfig {
                grid: 32,
                animated: true,
                frames: 3,
                rays: 4000,
                rays_large: None,
            }),
            render: Some(RenderConfig {
                scene: "cornell".into(),
                width: 48,
                height: 36,
                bounces: 3,
                reference_spp: 64,
                spp: vec![1, 4, 16],
                approx: vec![
                    crate::approx::MMRT_DEFAULT,
                    crate::approx::SINGLE_LAYER_DEFAULT,
                ],
            }),
            seed: 1,
            progress: true,
            grid_name: "quick: cube r128 with B {1, 8, 32} and S {1, 2}, single r128 B8 S1".into(),
        }
    }

    /// The grid of the committed results: around the default (cube, r128,
    /// B 8, S 1) the full B × S cross at r128, resolutions 64 and 256, a
    /// single view outside the scene and one at the camera; GPU (default
    /// setting) on scenes of at most 5 000 triangles and 1.5 M list nodes.
    pub fn full() -> EvalConfig {
        let mut grid = Vec::new();
        for s in [1, 2, 4] {
            for b in [1, 4, 8, 16, 32] {
                grid.push(GridPoint::new(ViewsKind::Cube, 128, b, s));
            }
        }
        // The papers' reduced configurations: lower resolutions, fewer views.
        for r in [32, 64, 256] {
            grid.push(GridPoint::new(ViewsKind::Cube, r, 8, 1));
        }
        grid.push(GridPoint::new(ViewsKind::Single, 128, 8, 1));
        for r in [32, 128] {
            let mut at_camera = GridPoint::new(ViewsKind::Single, r, 8, 1);
            at_camera.at_camera = true;
            grid.push(at_camera);
        }
        EvalConfig {
            scenes: ["cornell", "layers", "foliage", "spheres"]
                .iter()
                .map(|s| (s.to_string(), s.to_string()))
                .collect(),
            grid,
            traversals: vec![Traversal::Linear, Traversal::HiZ],
            rays: 5_000,
            truth_tests: 400_000_000,
            repeat: 2,
            gpu: Some(GpuConfig {
                max_triangles: 5_000,
                max_nodes: 1_500_000,
                rays: 2_000,
            }),
            peers: crate::peers::available(),
            side_rounds: 5,
            grid_densities: vec![1.0, 2.0, 8.0],
            approx: crate::approx::sweep(),
            dynamic: Some(DynamicConfig {
                grid: 128,
                animated: true,
                // Every frame is built and traced once, and on a shared
                // machine one frame's time can be half again another's
                // (the default at the grid, 5,000 rays: 3.65 to 6.99 ms
                // over frames 2-7 of one run): 8 frames left the medians
                // at the noise of one or two of them, the default's two
                // choice frames among them. 24 took the run 347 -> 388 s.
                frames: 24,
                rays: 5_000,
                rays_large: Some(100_000),
            }),
            render: Some(RenderConfig {
                scene: "cornell".into(),
                width: 128,
                height: 96,
                bounces: 4,
                reference_spp: 256,
                spp: vec![1, 2, 4, 8, 16, 32, 64],
                approx: vec![crate::approx::MMRT_DEFAULT, crate::approx::SINGLE_LAYER_DEFAULT],
            }),
            seed: 1,
            progress: true,
            grid_name: "full: cube r128 with B {1, 4, 8, 16, 32} x S {1, 2, 4}; cube r32, r64 and r256 (B8 S1); single r128 B8 S1 outside the scene; single r32 and r128 B8 S1 at the camera".into(),
        }
    }
}

/// The machine the run was measured on.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Machine {
    pub cpu: String,
    pub cores: usize,
    /// Threads of rayon's pool: DIRT's CPU stages, brute force, peers' traces.
    pub rayon_threads: usize,
    /// The GPU adapter, when the GPU backend ran.
    pub gpu: Option<String>,
    pub os: String,
    /// UTC time of the run.
    pub date: String,
    /// Whether this binary was built with optimisations.
    pub release: bool,
    /// 1-minute load average at the start and the end of the run: above the
    /// core count, other work shared the machine and timings are noisier.
    pub load_start: Option<f64>,
    pub load_end: Option<f64>,
}

/// The 1-minute load average, where the system says.
pub fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

impl Machine {
    pub fn detect() -> Machine {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split(':').nth(1))
                    .map(|m| m.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        let os = std::fs::read_to_string("/etc/os-release")
            .ok()
            .and_then(|s| {
                s.lines().find(|l| l.starts_with("PRETTY_NAME=")).map(|l| {
                    l.trim_start_matches("PRETTY_NAME=")
                        .trim_matches('"')
                        .to_string()
                })
            })
            .unwrap_or_else(|| std::env::consts::OS.to_string());
        Machine {
            cpu,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            rayon_threads: rayon::current_num_threads(),
            gpu: None,
            os,
            date: utc_now(),
            release: !cfg!(debug_assertions),
            load_start: load_average(),
            load_end: None,
        }
    }
}

/// `YYYY-MM-DD HH:MM UTC` from the system clock.
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}

/// Everything one run measured.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EvalResults {
    pub machine: Machine,
    pub grid: String,
    pub rays_per_type: usize,
    pub repeat: u32,
    pub scenes: Vec<SceneInfo>,
    pub builds: Vec<BuildRow>,
    pub traces: Vec<TraceRow>,
    pub dynamic: Vec<DynamicRow>,
    /// Per scene, the cost model's choice for a frame of all its rays (the headline's setting).
    pub choices: Vec<ChoiceRow>,
    /// Time and memory saved by leaving out what a scene does not need.
    pub leave_out: Vec<crate::leave_out::LeaveOutRow>,
    /// DIRT at the headline's setting beside each peer, in alternated rounds.
    pub side: Vec<crate::side::SideRow>,
    pub renders: Vec<RenderRow>,
    pub render_reference: Option<RenderReference>,
    pub render_settings_bounces: u32,
    /// Whole `dirt trace` processes on a large scene, per backend (filled by
    /// the command line, which runs its own binary).
    pub processes: Vec<ProcessRow>,
    /// What was skipped, and why.
    pub notes: Vec<String>,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// The converged reference render (written as a PNG beside the plots).
    #[serde(skip)]
    pub render_image: Option<dirt_render::output::Image>,
}

/// Whole `dirt trace` processes of one backend on one scene and ray file:
/// loading the scene, building, tracing and writing the hits, as a user
/// runs it.
#[derive(Clone, Debug, Serialize)]
pub struct ProcessRow {
    pub scene: String,
    pub triangles: usize,
    pub rays: usize,
    /// `dirt trace --backend` value (`cpu` is DIRT at the cost model's choice).
    pub backend: String,
    /// Wall seconds of each run, in run order.
    pub runs_s: Vec<f64>,
    /// Hits that differ from DIRT's (another primitive, or `t` more than
    /// 1e-4 relative away; DIRT's own row compares nothing), of `rays`.
    pub differ: usize,
}

/// The cost model's one-off choice (`dirt_cpu::cost::auto`) for one scene:
/// what the command line builds for a frame of these rays (the library's
/// `DirtCpu::auto` searches further, `cost::KEPT_BUDGET`).
#[derive(Clone, Debug, Serialize)]
pub struct ChoiceRow {
    pub scene: String,
    /// The chosen setting's label, e.g. `cube r32 B4 S1`.
    pub setting: String,
    pub rays_per_frame: usize,
    /// Candidates built and measured, and those pruned unbuilt.
    pub built: usize,
    pub skipped: usize,
    /// Wall time of choosing (candidate builds and sample traces).
    pub choose_ms: f64,
    /// The model's predicted frame time of the choice.
    pub predicted_frame_ms: f64,
}

/// Rays of a scene's run the cost model measures its candidates with.
pub const CHOICE_SAMPLE: usize = 1000;

#[derive(Clone, Debug, Serialize)]
pub struct SceneInfo {
    pub name: String,
    pub spec: String,
    pub triangles: usize,
    /// Rays per type compared with brute force.
    pub compared: usize,
}

/// The progress bar: drawn only on a terminal (indicatif hides itself otherwise).
fn progress_bar(len: u64, enabled: bool) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// The ground truth and the rays of one scene.
struct Prepared {
    name: String,
    tris: Vec<Triangle>,
    rays: Vec<(RayType, Vec<Ray>)>,
    truth: Vec<Vec<Hit>>,
    camera_eye: Option<dirt_math::Vec3>,
    /// The eye of the primary rays' camera (the scene's, else one in front of it).
    primary_eye: dirt_math::Vec3,
    /// List nodes of the default structure.
    nodes: usize,
}

impl Prepared {
    /// Rays per type compared with brute force (the length of each truth).
    fn compared(&self) -> usize {
        self.truth.first().map_or(0, Vec::len)
    }

    /// What a row of `backend` in `setting` on this scene is about.
    fn subject(&self, backend: &str, setting: Setting) -> Subject {
        Subject {
            scene: self.name.clone(),
            triangles: self.tris.len(),
            backend: backend.to_string(),
            setting,
            traversal: None,
        }
    }

    fn build_err(&self) -> impl Fn(CoreError) -> EvalError + '_ {
        EvalError::build_of(&self.name)
    }

    fn trace_err(&self) -> impl Fn(CoreError) -> EvalError + '_ {
        EvalError::trace_of(&self.name)
    }
}

/// How one tracer's rays are traced and judged.
#[derive(Clone, Copy, Debug)]
struct Plan {
    /// Trace only the first `n` rays of each type.
    rays: Option<usize>,
    repeat: u32,
    stats: StatsPass,
    /// Statistics known without counting (brute force: every ray tests every triangle).
    per_ray: Option<PerRay>,
    how: Match,
}

/// Traces every ray type of `prep` through `tracer` as `plan` says, one row
/// per type, judged against brute force.
fn trace_types(
    prep: &Prepared,
    tracer: &mut dyn Tracer,
    subject: &Subject,
    plan: Plan,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    for ((ty, rays), truth) in prep.rays.iter().zip(&prep.truth) {
        let rays = &rays[..plan.rays.unwrap_or(rays.len()).min(rays.len())];
        let mut m =
            measure::trace(tracer, rays, plan.repeat, plan.stats).map_err(prep.trace_err())?;
        if let Some(p) = plan.per_ray {
            m.per_ray = p;
        }
        let d = compare(&m.hits, truth, plan.how);
        res.traces.push(TraceRow::new(subject, ty.name(), &m, d));
    }
    Ok(())
}

/// Runs the whole evaluation.
pub fn run(cfg: &EvalConfig) -> Result<EvalResults, EvalError> {
    if cfg.rays == 0 {
        return Err(EvalError::Config("rays per type must be at least 1".into()));
    }
    if cfg.grid.is_empty() || cfg.traversals.is_empty() {
        return Err(EvalError::Config(
            "the grid and the traversals must not be empty".into(),
        ));
    }
    let start = Instant::now();
    let mut res = EvalResults {
        machine: Machine::detect(),
        grid: cfg.grid_name.clone(),
        rays_per_type: cfg.rays,
        repeat: cfg.repeat,
        ..EvalResults::default()
    };
    let threads = rayon::current_num_threads();
    let gpu = match cfg.gpu {
        Some(gc) => match dirt_gpu::Gpu::new() {
            Ok(g) => {
                res.machine.gpu = Some(g.describe());
                res.notes.push(format!(
                    "GPU backend: the default setting only, the first {} rays of each type, on scenes of at most {} triangles and {} list nodes{}",
                    gc.rays,
                    gc.max_triangles,
                    gc.max_nodes,
                    if g.is_llvmpipe() { " (lavapipe: a software rasteriser on the CPU cores, far slower than a GPU)" } else { "" }
                ));
                Some(g)
            }
            Err(e) => {
                res.notes.push(format!("GPU backend skipped: {e}"));
                None
            }
        },
        None => {
            res.notes
                .push("GPU backend not run (not requested in this grid)".into());
            None
        }
    };
    let per_scene = cfg.grid.len()
        + cfg.peers.len()
        + cfg.grid_densities.len()
        + cfg.approx.len()
        + usize::from(gpu.is_some())
        + usize::from(cfg.side_rounds > 0)
        + 3;
    let dyn_steps = cfg.dynamic.map_or(0, |d| d.frames * d.ray_counts().len())
        + usize::from(cfg.render.is_some());
    let pb = progress_bar(
        (cfg.scenes.len() * per_scene + dyn_steps) as u64,
        cfg.progress,
    );

    for (label, spec) in &cfg.scenes {
        pb.set_message(format!("{label}: rays and ground truth"));
        let scene = match dirt_scene::open(spec) {
            Ok(s) => s,
            Err(source) => {
                return Err(EvalError::Scene {
                    spec: spec.clone(),
                    source,
                });
            }
        };
        let prep = prepare(label, &scene, cfg)?;
        pb.inc(1);
        res.scenes.push(SceneInfo {
            name: prep.name.clone(),
            spec: spec.clone(),
            triangles: prep.tris.len(),
            compared: prep.compared(),
        });
        // Brute force itself, for scale, on the compared rays.
        let mut brute = Brute::new(&prep.tris);
        let plan = Plan {
            rays: Some(prep.compared()),
            repeat: 1,
            stats: StatsPass::Prefix(0),
            per_ray: Some(PerRay::every_triangle(prep.tris.len())),
            how: Match::Bits,
        };
        let subject = prep.subject("brute", Setting::default());
        trace_types(&prep, &mut brute, &subject, plan, &mut res)?;
        for point in &cfg.grid {
            pb.set_message(format!("{label}: dirt-cpu {}", point.label()));
            let mut point = *point;
            if point.at_camera {
                match prep.camera_eye {
                    Some(eye) => point.params.center = Some(eye),
                    None => {
                        res.notes.push(format!(
                            "{}: {} skipped (the scene has no camera)",
                            prep.name,
                            point.label()
                        ));
                        pb.inc(1);
                        continue;
                    }
                }
            }
            measure_cpu(&prep, &point, cfg, &mut res)?;
            pb.inc(1);
        }
        let all_rays: Vec<Ray> = prep
            .rays
            .iter()
            .flat_map(|(_, r)| r.iter().copied())
            .collect();
        pb.set_message(format!("{label}: the cost model's choice"));
        let point = choose(&prep, &all_rays, &mut res)?;
        if !cfg
            .grid
            .iter()
            .any(|g| g.params == point.params && !g.at_camera)
        {
            measure_cpu(&prep, &point, cfg, &mut res)?;
        }
        pb.inc(1);
        pb.set_message(format!("{label}: leaving out against everything on"));
        let input = crate::leave_out::Input {
            scene: &prep.name,
            tris: &prep.tris,
            rays: &all_rays,
            compared: prep
                .rays
                .iter()
                .zip(&prep.truth)
                .map(|((_, r), t)| (&r[..t.len()], t.as_slice()))
                .collect(),
            camera: prep.camera_eye,
            repeat: cfg.repeat,
        };
        res.leave_out.extend(crate::leave_out::run(&input)?);
        pb.inc(1);
        for peer in &cfg.peers {
            pb.set_message(format!("{label}: {}", peer.name));
            measure_peer(&prep, peer, threads, cfg, &mut res)?;
            pb.inc(1);
        }
        if cfg.side_rounds > 0 {
            pb.set_message(format!("{label}: side by side"));
            let input = crate::side::Input {
                scene: &prep.name,
                tris: &prep.tris,
                rays: prep.rays.iter().map(|(_, r)| r.as_slice()).collect(),
                truth: prep.truth.iter().map(Vec::as_slice).collect(),
                params: point.params,
                setting: point.label(),
                traversals: &cfg.traversals,
                repeat: cfg.repeat,
                rounds: cfg.side_rounds,
            };
            for peer in &cfg.peers {
                let rows = crate::side::run(&input, peer, threads, &mut res.notes)?;
                res.side.extend(rows);
            }
            pb.inc(1);
        }
        for &density in &cfg.grid_densities {
            pb.set_message(format!("{label}: grid ρ{density}"));
            measure_grid(&prep, density, cfg, &mut res)?;
            pb.inc(1);
        }
        for point in &cfg.approx {
            pb.set_message(format!(
                "{label}: {} {}",
                point.method.name(),
                point.setting().label
            ));
            measure_approx(&prep, point, cfg, &mut res)?;
            pb.inc(1);
        }
        if let (Some(g), Some(gc)) = (&gpu, cfg.gpu) {
            pb.set_message(format!("{label}: dirt-gpu"));
            if prep.tris.len() <= gc.max_triangles && prep.nodes <= gc.max_nodes {
                measure_gpu(g, &prep, gc, cfg, &mut res)?;
            } else {
                res.notes.push(format!(
                    "{}: GPU backend skipped ({} triangles, {} list nodes; limits {} and {}: lavapipe is slow)",
                    prep.name,
                    prep.tris.len(),
                    prep.nodes,
                    gc.max_triangles,
                    gc.max_nodes
                ));
            }
            pb.inc(1);
        }
    }
    if let Some(dc) = cfg.dynamic {
        pb.set_message("dynamic scene");
        res.dynamic = crate::dynamic::run(&dc, &cfg.peers, threads, cfg.seed, &pb, &mut res.notes)?;
    }
    if let Some(rc) = &cfg.render {
        pb.set_message("renders");
        let (rows, reference, image) = crate::renders::run(rc)?;
        res.renders = rows;
        res.render_reference = Some(reference);
        res.render_settings_bounces = rc.bounces;
        res.render_image = Some(image);
        pb.inc(1);
    }
    pb.finish_and_clear();
    res.machine.load_end = load_average();
    res.wall_s = start.elapsed().as_secs_f64();
    Ok(res)
}

fn prepare(
    label: &str,
    scene: &dirt_scene::Scene,
    cfg: &EvalConfig,
) -> Result<Prepared, EvalError> {
    let tris = scene.triangles.clone();
    if tris.is_empty() {
        return Err(EvalError::Rays(format!("scene {label} has no triangles")));
    }
    // Primary hits come from DIRT with the default (exact) setting: the same
    // hits as brute force, much faster on large scenes.
    let reference =
        Ads::build(&tris, &AdsParams::default()).map_err(|source| EvalError::Build {
            scene: label.to_string(),
            source: source.into(),
        })?;
    let rays = rays::table1(scene, cfg.rays, cfg.seed, |r| {
        dirt_cpu::trace(&reference, &tris, r, Traversal::Linear)
    })?;
    let compared = ((cfg.truth_tests / tris.len() as u64) as usize)
        .max(200)
        .min(cfg.rays);
    let truth = rays
        .iter()
        .map(|(_, r)| dirt_cpu::brute_force::trace(&tris, &r[..compared]))
        .collect();
    Ok(Prepared {
        name: label.to_string(),
        camera_eye: rays::Camera::of_scene(scene).map(|c| c.eye),
        primary_eye: rays::primary_camera(scene)?.eye,
        nodes: reference.lists.ids.len(),
        tris,
        rays,
        truth,
    })
}

/// The cost model's choice for a frame of `all_rays` (measured on a stride
/// of them), recorded in `res.choices`.
fn choose(
    prep: &Prepared,
    all_rays: &[Ray],
    res: &mut EvalResults,
) -> Result<GridPoint, EvalError> {
    let sample = dirt_cpu::cost::stride_sample(all_rays, CHOICE_SAMPLE);
    let start = std::time::Instant::now();
    let choice = dirt_cpu::cost::auto(
        &prep.tris,
        &sample,
        all_rays.len() as u64,
        Traversal::HiZ,
        &dirt_cpu::cost::CostModel::CALIBRATED,
        &dirt_cpu::cost::candidates_all(&AdsParams::default(), &prep.tris),
    )
    .map_err(|e| prep.build_err()(e.into()))?;
    let choose_ms = start.elapsed().as_secs_f64() * 1e3;
    let point = GridPoint {
        params: choice.best.params,
        at_camera: false,
    };
    res.choices.push(ChoiceRow {
        scene: prep.name.clone(),
        setting: point.label(),
        rays_per_frame: all_rays.len(),
        built: choice.ranked.len(),
        skipped: choice.skipped,
        choose_ms,
        predicted_frame_ms: choice.best.frame_ms,
    });
    Ok(point)
}

fn measure_cpu(
    prep: &Prepared,
    point: &GridPoint,
    cfg: &EvalConfig,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    let subject = prep.subject("dirt-cpu", point.setting());
    let mut cpu = DirtCpu::new(point.params, Traversal::Linear);
    let built = measure::build(&mut cpu, &prep.tris, cfg.repeat).map_err(prep.build_err())?;
    let structure = cpu.ads().map(Structure::of_cpu).unwrap_or_default();
    res.builds.push(BuildRow::new(&subject, &built, &structure));
    let plan = Plan {
        rays: None,
        repeat: cfg.repeat,
        stats: StatsPass::Prefix(prep.compared()),
        per_ray: None,
        how: Match::Bits,
    };
    for &trav in &cfg.traversals {
        cpu.traversal = trav;
        trace_types(prep, &mut cpu, &subject.with_traversal(trav), plan, res)?;
    }
    Ok(())
}

fn measure_peer(
    prep: &Prepared,
    peer: &Peer,
    threads: usize,
    cfg: &EvalConfig,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    let subject = prep.subject(peer.name, Setting::default());
    let built = (peer.make)(threads).and_then(|mut tracer| {
        let b = measure::build(tracer.as_mut(), &prep.tris, cfg.repeat)?;
        Ok((tracer, b))
    });
    let (mut tracer, built) = match built {
        Ok(b) => b,
        Err(e) if crate::peers::unavailable(&e) => {
            res.notes.push(e.to_string());
            return Ok(());
        }
        Err(e) => return Err(prep.build_err()(e)),
    };
    res.builds
        .push(BuildRow::new(&subject, &built, &Structure::default()));
    let plan = Plan {
        rays: None,
        repeat: cfg.repeat,
        stats: StatsPass::Prefix(prep.compared()),
        per_ray: None,
        how: peer.how(),
    };
    trace_types(prep, tracer.as_mut(), &subject, plan, res)
}

/// The compact grid at `density` cells per triangle (exact: held to every bit).
fn measure_grid(
    prep: &Prepared,
    density: f32,
    cfg: &EvalConfig,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    let name = crate::peers::grid_name(density);
    let subject = prep.subject(&name, Setting::default());
    let mut grid = dirt_cpu::grid::Grid::new(density).map_err(prep.build_err())?;
    let built = measure::build(&mut grid, &prep.tris, cfg.repeat).map_err(prep.build_err())?;
    res.builds
        .push(BuildRow::new(&subject, &built, &Structure::default()));
    let plan = Plan {
        rays: None,
        repeat: cfg.repeat,
        stats: StatsPass::Prefix(0),
        per_ray: None,
        how: Match::Bits,
    };
    trace_types(prep, &mut grid, &subject, plan, res)
}

/// An approximate method at one setting; its error is what is measured.
fn measure_approx(
    prep: &Prepared,
    point: &ApproxPoint,
    cfg: &EvalConfig,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    // The single layer looks from the primary rays' eye, as a renderer's depth buffer would.
    let Some(params) = point.params(Some(prep.primary_eye)) else {
        return Ok(());
    };
    let subject = prep.subject(point.method.name(), point.setting());
    let mut tracer = ScreenSpace::new(params).map_err(prep.build_err())?;
    let built = match measure::build(&mut tracer, &prep.tris, cfg.repeat) {
        Ok(b) => b,
        // A setting whose A-buffer would not fit its limits is noted, not measured.
        Err(e @ CoreError::InvalidParams(_)) => {
            res.notes.push(format!(
                "{}: {} {} skipped: {e}",
                prep.name,
                point.method.name(),
                point.setting().label
            ));
            return Ok(());
        }
        Err(e) => return Err(prep.build_err()(e)),
    };
    // The A-buffer is the id buffer of 004; its model is 004's Table 2.
    let structure = Structure {
        nodes: Some(tracer.fragments() as u64),
        depth_hiz: None,
        id_buffer: Some((tracer.memory_bytes(), Some(tracer.model_bytes() as f64))),
    };
    res.builds.push(BuildRow::new(&subject, &built, &structure));
    let plan = Plan {
        rays: None,
        repeat: cfg.repeat,
        stats: StatsPass::Prefix(0),
        per_ray: None,
        how: Match::PEER,
    };
    trace_types(prep, &mut tracer, &subject, plan, res)
}

fn measure_gpu(
    gpu: &dirt_gpu::Gpu,
    prep: &Prepared,
    gc: GpuConfig,
    cfg: &EvalConfig,
    res: &mut EvalResults,
) -> Result<(), EvalError> {
    let point = default_point();
    let subject = prep.subject("dirt-gpu", point.setting());
    let mut tracer = DirtGpu::new(gpu, point.params, Traversal::Linear);
    let built =
        measure::build(&mut tracer, &prep.tris, cfg.repeat.min(2)).map_err(prep.build_err())?;
    let structure = tracer.ads().map(Structure::of_gpu).unwrap_or_default();
    res.builds.push(BuildRow::new(&subject, &built, &structure));
    // The GPU's statistics come back with its hits: count them in the timed trace.
    let plan = Plan {
        rays: Some(gc.rays),
        repeat: 1,
        stats: StatsPass::Timed,
        per_ray: None,
        how: Match::Bits,
    };
    for &trav in &cfg.traversals {
        tracer.traversal = trav;
        trace_types(prep, &mut tracer, &subject.with_traversal(trav), plan, res)?;
    }
    // The same structure built as an application's frame would (`DirtGpu::frame_builds`:
    // upload, views on the GPU, one submission, recorded again if the ids overflowed),
    // and its hits compared (Hi-Z walk).
    let frame_subject = prep.subject("dirt-gpu-frame", point.setting());
    let mut frame = DirtGpu::new(gpu, point.params, Traversal::HiZ);
    frame.frame_builds = true;
    let built =
        measure::build(&mut frame, &prep.tris, cfg.repeat.min(2)).map_err(prep.build_err())?;
    let structure = frame.ads().map(Structure::of_gpu).unwrap_or_default();
    res.builds
        .push(BuildRow::new(&frame_subject, &built, &structure));
    trace_types(
        prep,
        &mut frame,
        &frame_subject.with_traversal(Traversal::HiZ),
        plan,
        res,
    )
}

/// Where the scene list's real assets live.
pub fn engine_path() -> PathBuf {
    PathBuf::from("/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb")
}
