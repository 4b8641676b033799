//! `dirt bench`: build and trace of every backend side by side, on one scene,
//! one set of parameters and one set of generated rays (the generator of
//! `dirt rays`), with each setting's error against brute force.
//!
//! A benchmark, not a test: it fails only on bad input. Figures are medians of
//! at least `--repeat` runs, and of more while a measurement has taken under
//! 30 ms (`dirt_eval::measure::timed_steady`); brute force traces only the first `--brute-rays` rays and
//! its rate is reported as measured on that many. The table goes to stdout,
//! progress to stderr, the same figures optionally to a JSON file.
//!
//! Every backend is a `dirt_core::Tracer` measured by `dirt_eval::measure`,
//! the measuring path of `dirt eval`: the rows are its `BuildRow` and
//! `TraceRow`, and the JSON is them, serialized.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_cpu::brute_force::Brute;
use dirt_eval::measure::{
    self, BuildRow, PerRay, Setting, StatsPass, Structure, Subject, TraceMeasure, TraceRow,
};
use dirt_eval::rays::{self, Camera, RayKind};
use dirt_eval::{Disagreement, Match, compare};
use dirt_gpu::{DirtGpu, Gpu};
use dirt_math::{Hit, Ray, RayStats, Triangle};
use serde::Serialize;

use crate::args::{AdsArgs, SceneArg};
use crate::commands::trace::Backend;

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(flatten)]
    scene: SceneArg,
    #[command(flatten)]
    pub ads: AdsArgs,
    /// Number of rays, made by the generator of `dirt rays`.
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    rays: usize,
    /// Seed of the ray generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Which rays (as `dirt rays --kind`).
    #[arg(long, value_enum, default_value = "mixed")]
    kind: RayKind,
    /// Backends to measure, comma-separated.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_values_t = [Backend::Cpu, Backend::Gpu, Backend::Brute]
    )]
    backends: Vec<Backend>,
    /// Builds and traces per setting, at least; more (up to 11) while a measurement has
    /// taken under 30 ms. Medians are reported.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    /// Rays brute force traces (the first ones): the ground truth of the mismatch counts.
    #[arg(long, value_name = "N", default_value_t = 20_000)]
    brute_rays: usize,
    /// Also write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Rays whose statistics differ from the cpu's, out of the rays compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
struct StatsMismatch {
    compared: usize,
    differ: usize,
}

/// One line of the table: the evaluation's trace row (its `compared`,
/// `differ` and `differ_prim` are against brute force) and what only the
/// bench compares.
#[derive(Clone, Debug, Serialize)]
struct Row {
    #[serde(flatten)]
    trace: TraceRow,
    /// Hits that differ from the cpu's (same traversal), over all rays.
    mismatches_vs_cpu: Option<Disagreement>,
    /// Rays whose statistics differ from the cpu's (same traversal).
    stats_mismatches_vs_cpu: Option<StatsMismatch>,
}

/// What became of the GPU.
#[derive(Debug)]
enum GpuState {
    NotRequested,
    Unavailable(String),
    Used { adapter: String, exact: bool },
}

/// The rays, the ground truth and what every row shares.
struct Bench<'a> {
    tris: &'a [Triangle],
    rays: &'a [Ray],
    /// Brute force's hits of the first rays (`None` with `--brute-rays 0`).
    truth: Option<Vec<Hit>>,
    scene: &'a str,
    params: AdsParams,
    /// The rays' kind, as the rows' `ray_type`.
    kind: &'a str,
    repeat: u32,
}

impl Bench<'_> {
    fn subject(&self, backend: Backend, setting: Setting) -> Subject {
        Subject {
            scene: self.scene.to_owned(),
            triangles: self.tris.len(),
            backend: backend.to_string(),
            setting,
            traversal: None,
        }
    }

    /// The row of a trace, judged against brute force.
    fn row(&self, subject: &Subject, m: &TraceMeasure) -> Row {
        let vs_brute = self
            .truth
            .as_ref()
            .map_or_else(Disagreement::default, |t| compare(&m.hits, t, Match::Bits));
        Row {
            trace: TraceRow::new(subject, self.kind, m, vs_brute),
            mismatches_vs_cpu: None,
            stats_mismatches_vs_cpu: None,
        }
    }

    /// Builds `tracer` `repeat` times: the build row.
    fn build(&self, tracer: &mut dyn Tracer, subject: &Subject) -> Result<measure::BuildMeasure> {
        eprintln!("{}: build x {}", subject.backend, self.repeat);
        measure::build(tracer, self.tris, self.repeat).with_context(|| {
            format!(
                "cannot build the acceleration structure of {} ({:?})",
                self.scene, self.params
            )
        })
    }
}

fn kind_name(kind: RayKind) -> String {
    kind.to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_owned())
}

pub fn bench(args: &BenchArgs) -> Result<()> {
    if args.rays == 0 {
        bail!("--rays must be at least 1");
    }
    let scene = args.scene.open()?;
    let tris = &scene.triangles;
    let rays = rays::generate(
        tris,
        Camera::of_scene(&scene),
        args.kind,
        args.rays,
        args.seed,
    )
    .with_context(|| format!("cannot make rays for scene {}", scene.name))?;
    // The GPU first, when asked for: the cost model's choice must fit its bindings.
    let opened = args.backends.contains(&Backend::Gpu).then(Gpu::open);
    let limits = match &opened {
        Some(Ok(g)) => Some(g.binding_limits()),
        _ => None,
    };
    let (params, _) = args
        .ads
        .choose_within(&scene, rays.len() as u64, Some(&rays), limits)?;
    params
        .validate()
        .with_context(|| format!("cannot build the acceleration structure ({params:?})"))?;
    let k = args.repeat;
    let threads = rayon::current_num_threads();
    let mut backends = Vec::new();
    for b in &args.backends {
        if !backends.contains(b) {
            backends.push(*b);
        }
    }
    eprintln!(
        "bench {}: {} triangles, {} rays, backends {}, median of {k}",
        scene.name,
        tris.len(),
        rays.len(),
        backends
            .iter()
            .map(Backend::to_string)
            .collect::<Vec<_>>()
            .join(",")
    );

    let kind = kind_name(args.kind);
    let mut bench = Bench {
        tris,
        rays: &rays,
        truth: None,
        scene: &scene.name,
        params,
        kind: &kind,
        repeat: k,
    };
    let mut rows = Vec::new();
    let mut builds = Vec::new();

    // Ground truth on the first rays.
    let n_brute = args.brute_rays.min(rays.len());
    let subset = &rays[..n_brute];
    let mut brute = Brute::new(tris);
    if n_brute > 0 && backends.contains(&Backend::Brute) {
        eprintln!("brute force: {n_brute} rays x {k}");
        let mut m = measure::trace(&mut brute, subset, k, StatsPass::Prefix(0))?;
        m.per_ray = PerRay::every_triangle(tris.len());
        bench.truth = Some(m.hits.clone());
        rows.push(bench.row(&bench.subject(Backend::Brute, Setting::default()), &m));
    } else if n_brute > 0 {
        eprintln!("brute force: {n_brute} rays once (ground truth, not timed)");
        bench.truth = Some(brute.trace(subset)?);
    }

    // CPU.
    let setting = Setting::dirt(&params, false);
    let mut cpu_results: Vec<Option<TraceMeasure>> = vec![None, None];
    if backends.contains(&Backend::Cpu) {
        let subject = bench.subject(Backend::Cpu, setting.clone());
        let mut cpu = DirtCpu::new(params, Traversal::Linear);
        let built = bench.build(&mut cpu, &subject)?;
        let structure = cpu.ads().map(Structure::of_cpu).unwrap_or_default();
        builds.push(BuildRow::new(&subject, &built, &structure));
        for (slot, traversal) in cpu_results.iter_mut().zip(Traversal::ALL) {
            eprintln!("cpu: trace {traversal} x {k}");
            cpu.traversal = traversal;
            let m = measure::trace(&mut cpu, &rays, k, StatsPass::Prefix(rays.len()))?;
            rows.push(bench.row(&subject.with_traversal(traversal), &m));
            *slot = Some(m);
        }
    }

    // GPU.
    let gpu_state = if let Some(opened) = opened {
        match opened {
            Ok(gpu) => {
                eprintln!("{}", crate::gpu::gpu_line(&gpu));
                let adapter = gpu.describe();
                let exact = gpu.exact;
                let subject = bench.subject(Backend::Gpu, setting);
                match bench_gpu(&gpu, &bench, &subject, &cpu_results) {
                    Ok((gpu_builds, gpu_rows)) => {
                        builds.extend(gpu_builds);
                        rows.extend(gpu_rows);
                        GpuState::Used { adapter, exact }
                    }
                    Err(e) => {
                        let reason = format!("{e:#}");
                        eprintln!(
                            "dirt: the GPU ({adapter}) failed: {reason}; benchmarking the other backends"
                        );
                        GpuState::Unavailable(format!("{adapter} failed: {reason}"))
                    }
                }
            }
            Err(reason) => {
                eprintln!("dirt: no usable GPU ({reason}); benchmarking the other backends");
                GpuState::Unavailable(reason)
            }
        }
    } else {
        GpuState::NotRequested
    };

    // Rows in a fixed order: cpu, gpu, brute.
    let order = |b: &str| match b {
        "cpu" => 0,
        "gpu" => 1,
        _ => 2,
    };
    rows.sort_by_key(|r| order(&r.trace.backend));

    let p = params;
    let (gpu, gpu_exact, gpu_error) = match &gpu_state {
        GpuState::NotRequested => (None, None, None),
        GpuState::Unavailable(reason) => (None, None, Some(reason.clone())),
        GpuState::Used { adapter, exact } => (Some(adapter.clone()), Some(*exact), None),
    };
    let report = Report {
        scene: &scene.name,
        triangles: tris.len(),
        rays: rays.len(),
        kind: &kind,
        seed: args.seed,
        params: Params {
            views: p.views.to_string(),
            resolution: p.resolution,
            buckets: p.buckets,
            tile: p.tile,
            center: p.center.map(|c| c.to_array()),
        },
        repeat: k,
        brute_rays: n_brute,
        cpu_threads: threads,
        gpu,
        gpu_exact,
        gpu_error,
        builds,
        rows,
        gpu_state,
    };
    print!("{}", report.markdown());
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report).context("cannot write the JSON")?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// Builds and traces on the GPU; rows for both traversals, compared with the
/// cpu's. Two build rows: `gpu`, the host build (views on the host, each
/// stage waited for), and `gpu-frame`, the build recorded into one
/// submission (`DirtGpu::frame_builds`), whose hits are checked too.
fn bench_gpu(
    gpu: &Gpu,
    bench: &Bench<'_>,
    subject: &Subject,
    cpu_results: &[Option<TraceMeasure>],
) -> Result<(Vec<BuildRow>, Vec<Row>)> {
    let k = bench.repeat;
    let mut framed = DirtGpu::new(gpu, bench.params, Traversal::Linear);
    framed.frame_builds = true;
    let frame_subject = Subject {
        backend: "gpu-frame".into(),
        ..subject.clone()
    };
    // The first frame build sizes the ids from its count (once, untimed), as a frame loop would.
    framed
        .build(bench.tris)
        .context("cannot build in a frame")?;
    let frame_built = bench.build(&mut framed, &frame_subject)?;
    let frame_structure = framed.ads().map(Structure::of_gpu).unwrap_or_default();
    let m = measure::trace(&mut framed, bench.rays, 1, StatsPass::Timed)
        .context("cannot trace the frame build")?;
    if let Some(Some(c)) = cpu_results.first() {
        report_differences(Traversal::Linear, bench.tris, bench.rays, &m.hits, &c.hits);
    }
    drop(framed);
    let mut tracer = DirtGpu::new(gpu, bench.params, Traversal::Linear);
    let built = bench.build(&mut tracer, subject)?;
    let structure = tracer.ads().map(Structure::of_gpu).unwrap_or_default();
    let build = vec![
        BuildRow::new(subject, &built, &structure),
        BuildRow::new(&frame_subject, &frame_built, &frame_structure),
    ];
    let mut rows = Vec::new();
    for (cpu, traversal) in cpu_results.iter().zip(Traversal::ALL) {
        eprintln!("gpu: trace {traversal} x {k}");
        tracer.traversal = traversal;
        // The GPU's statistics come back with its hits: count them in the timed traces.
        let m =
            measure::trace(&mut tracer, bench.rays, k, StatsPass::Timed).context("cannot trace")?;
        if m.continuation_rounds > 0 {
            eprintln!(
                "gpu: rays that spent a dispatch's work budget took {} continuation rounds on the GPU (included in the time)",
                m.continuation_rounds
            );
        }
        let mut row = bench.row(&subject.with_traversal(traversal), &m);
        if let Some(c) = cpu {
            report_differences(traversal, bench.tris, bench.rays, &m.hits, &c.hits);
            report_stats_differences(traversal, &m.stats, &c.stats);
            row.mismatches_vs_cpu = Some(compare(&m.hits, &c.hits, Match::Bits));
            row.stats_mismatches_vs_cpu = Some(StatsMismatch {
                compared: m.stats.len(),
                differ: m.stats.iter().zip(&c.stats).filter(|(a, b)| a != b).count(),
            });
        }
        rows.push(row);
    }
    Ok((build, rows))
}

/// A hit with its words as the hits file holds them.
fn hit_words(h: &Hit) -> String {
    format!(
        "prim {:#010x} t {:?} u {:?} v {:?} (words {:08x} {:08x} {:08x} {:08x})",
        h.prim,
        h.t,
        h.u,
        h.v,
        h.prim,
        h.t.to_bits(),
        h.u.to_bits(),
        h.v.to_bits()
    )
}

/// The first rays where the gpu's hit differs from the cpu's, with brute force's, on stderr.
fn report_differences(
    traversal: Traversal,
    tris: &[Triangle],
    rays: &[Ray],
    gpu: &[Hit],
    cpu: &[Hit],
) {
    const SHOWN: usize = 5;
    let differ: Vec<usize> = (0..gpu.len().min(cpu.len()))
        .filter(|&i| bytemuck::bytes_of(&gpu[i]) != bytemuck::bytes_of(&cpu[i]))
        .collect();
    if differ.is_empty() {
        return;
    }
    eprintln!(
        "gpu {}: {} ray(s) differ from cpu; the first {}:",
        Traversal::name(traversal),
        differ.len(),
        differ.len().min(SHOWN)
    );
    for &i in differ.iter().take(SHOWN) {
        let row = dirt_cli::npy::row_from_ray(&rays[i]);
        let bits: Vec<String> = row.iter().map(|x| format!("{:08x}", x.to_bits())).collect();
        eprintln!("  ray {i}: {row:?} (words {})", bits.join(" "));
        eprintln!("    cpu   {}", hit_words(&cpu[i]));
        eprintln!("    gpu   {}", hit_words(&gpu[i]));
        eprintln!(
            "    brute {}",
            hit_words(&dirt_cpu::brute_force::trace_ray(tris, &rays[i]))
        );
    }
}

/// The first rays whose gpu statistics differ from the cpu's, on stderr.
fn report_stats_differences(traversal: Traversal, gpu: &[RayStats], cpu: &[RayStats]) {
    const SHOWN: usize = 5;
    let differ: Vec<usize> = (0..gpu.len().min(cpu.len()))
        .filter(|&i| gpu[i] != cpu[i])
        .collect();
    if differ.is_empty() {
        return;
    }
    eprintln!(
        "gpu {}: {} ray(s) have statistics that differ from cpu; the first {}:",
        Traversal::name(traversal),
        differ.len(),
        differ.len().min(SHOWN)
    );
    let words = |s: &RayStats| {
        format!(
            "views {} tiles {} buckets {} tests {}",
            s.views, s.tiles, s.buckets, s.tests
        )
    };
    for &i in differ.iter().take(SHOWN) {
        eprintln!("  ray {i}: cpu {}; gpu {}", words(&cpu[i]), words(&gpu[i]));
    }
}

/// The structure's parameters, as the JSON gives them.
#[derive(Debug, Serialize)]
struct Params {
    views: String,
    resolution: u32,
    buckets: u32,
    tile: u32,
    center: Option<[f32; 3]>,
}

/// Everything the table and the JSON say; the JSON is this, serialized.
#[derive(Debug, Serialize)]
struct Report<'a> {
    scene: &'a str,
    triangles: usize,
    rays: usize,
    kind: &'a str,
    seed: u64,
    params: Params,
    repeat: u32,
    brute_rays: usize,
    cpu_threads: usize,
    /// The adapter, when the GPU was used.
    gpu: Option<String>,
    gpu_exact: Option<bool>,
    /// Why the GPU was not used, when it was asked for.
    gpu_error: Option<String>,
    builds: Vec<BuildRow>,
    rows: Vec<Row>,
    #[serde(skip)]
    gpu_state: GpuState,
}

fn fixed(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "—".to_owned()
    }
}

/// `x` with at least `digits` significant digits (and at least two decimals).
fn significant(x: f64, digits: i32) -> String {
    if !x.is_finite() {
        return "—".to_owned();
    }
    let magnitude = if x == 0.0 {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    fixed(x, (digits - 1 - magnitude).clamp(2, 12) as usize)
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "—".to_owned(), |x| fixed(x, digits))
}

fn count_cell(d: Option<(usize, usize)>) -> String {
    d.map_or_else(|| "—".to_owned(), |(differ, of)| format!("{differ} / {of}"))
}

impl Report<'_> {
    fn gpu_words(&self) -> String {
        match &self.gpu_state {
            GpuState::NotRequested => "not benchmarked".to_owned(),
            GpuState::Unavailable(reason) => format!("not available ({reason})"),
            GpuState::Used { adapter, exact } => format!(
                "{adapter}{}",
                if *exact {
                    ", exact"
                } else {
                    ", not exact (plain WGSL)"
                }
            ),
        }
    }

    fn params_words(&self) -> String {
        let p = &self.params;
        let center = p.center.map_or_else(
            || "bounds centre".to_owned(),
            |c| dirt_math::Vec3::from_array(c).to_string(),
        );
        format!(
            "{} views, resolution {}, {} buckets, tile {}, centre {center}",
            p.views, p.resolution, p.buckets, p.tile
        )
    }

    fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "dirt bench: scene {}, {} triangles, {} {} rays (seed {}); {}; median of {}; {} CPU threads; GPU: {}",
            self.scene,
            self.triangles,
            self.rays,
            self.kind,
            self.seed,
            self.params_words(),
            self.repeat,
            self.cpu_threads,
            self.gpu_words()
        );
        s.push('\n');
        s.push_str(
            "| backend | traversal | build ms | trace ms | Mrays/s | rays | tiles/ray | buckets/ray | tests/ray | mismatches vs brute | mismatches vs cpu | stats ≠ cpu |\n",
        );
        s.push_str("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
        let has_truth = self.brute_rays > 0;
        for r in &self.rows {
            let t = &r.trace;
            let build_ms = self
                .builds
                .iter()
                .find(|b| b.backend == t.backend)
                .and_then(|b| b.stages_ms);
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                t.backend,
                if t.traversal.is_empty() {
                    "—"
                } else {
                    &t.traversal
                },
                opt(build_ms, 2),
                fixed(t.trace_ms, 2),
                significant(t.mrays_per_s, 4),
                t.rays,
                opt(t.tiles_per_ray, 2),
                opt(t.buckets_per_ray, 2),
                opt(t.tests_per_ray, 2),
                if t.backend == "brute" {
                    "reference".to_owned()
                } else {
                    count_cell(has_truth.then_some((t.differ, t.compared)))
                },
                count_cell(r.mismatches_vs_cpu.map(|d| (d.differ, d.compared))),
                count_cell(r.stats_mismatches_vs_cpu.map(|d| (d.differ, d.compared)))
            );
        }
        if !self.builds.is_empty() {
            s.push('\n');
            s.push_str(
                "| build | fill_depth ms | mip_depth ms | fill_primitives ms | total ms | wall ms | list nodes |\n",
            );
            s.push_str("|---|--:|--:|--:|--:|--:|--:|\n");
            for b in &self.builds {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    b.backend,
                    opt(b.fill_depth_ms, 2),
                    opt(b.mip_depth_ms, 2),
                    opt(b.fill_primitives_ms, 2),
                    opt(b.stages_ms, 2),
                    fixed(b.build_ms, 2),
                    b.nodes.map_or_else(|| "—".to_owned(), |n| n.to_string())
                );
            }
        }
        s.push('\n');
        let _ = write!(
            s,
            "Medians of at least {} run(s), and of more (up to {}) until a measurement has taken \
             {} ms. build ms: the three stages (wall ms: the whole build call, \
             checks, views and uploads included). trace ms: wall time of the whole trace \
             (gpu: uploads, dispatches and read-back included). ",
            self.repeat,
            measure::STEADY_RUNS,
            measure::STEADY_MS
        );
        let brute_timed = self.rows.iter().any(|r| r.trace.backend == "brute");
        if self.brute_rays == 0 {
            s.push_str("No ground truth (--brute-rays 0). ");
        } else {
            let _ = write!(
                s,
                "Brute force traces the first {} rays only{}. ",
                self.brute_rays,
                if brute_timed {
                    "; its Mrays/s is measured on those"
                } else {
                    " (ground truth, not timed)"
                }
            );
        }
        let _ = writeln!(
            s,
            "Mismatches: rays whose hit differs in any bit, vs brute on those {} rays, \
             vs cpu (same traversal) on all rays. stats ≠ cpu: rays whose tiles, buckets, \
             tests or views differ from the cpu's.",
            self.brute_rays
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::{Cli, Command};
    use clap::Parser;

    fn parse(args: &[&str]) -> BenchArgs {
        let cli = Cli::try_parse_from(args).expect("parse");
        let Command::Bench(b) = cli.command else {
            panic!("not bench")
        };
        b
    }

    #[test]
    fn bench_options_parse() {
        let b = parse(&["dirt", "bench"]);
        assert_eq!(b.scene.scene, dirt_scene::DEFAULT_SCENE);
        assert_eq!(
            (b.rays, b.seed, b.repeat, b.brute_rays),
            (200_000, 1, 3, 20_000)
        );
        assert_eq!(b.kind, RayKind::Mixed);
        assert_eq!(b.backends, [Backend::Cpu, Backend::Gpu, Backend::Brute]);
        assert_eq!(b.ads.params(), dirt_core::AdsParams::default());
        assert!(b.json.is_none());
        let b = parse(&[
            "dirt",
            "bench",
            "layers",
            "--rays",
            "100",
            "--backends",
            "brute,cpu",
            "--repeat",
            "5",
            "--kind",
            "camera",
            "--tile",
            "2",
            "--json",
            "b.json",
        ]);
        assert_eq!(b.backends, [Backend::Brute, Backend::Cpu]);
        assert_eq!((b.rays, b.repeat, b.ads.tile), (100, 5, 2));
        assert_eq!(b.kind, RayKind::Camera);
        assert!(Cli::try_parse_from(["dirt", "bench", "--repeat", "0"]).is_err());
        assert!(Cli::try_parse_from(["dirt", "bench", "--backends", "cpu,tpu"]).is_err());
    }

    #[test]
    fn rates_keep_their_significant_digits() {
        assert_eq!(significant(0.000956, 4), "0.0009560");
        assert_eq!(significant(0.4263, 4), "0.4263");
        assert_eq!(significant(12.345, 4), "12.35");
        assert_eq!(significant(12345.6, 4), "12345.60");
        assert_eq!(significant(0.0, 4), "0.000");
        assert_eq!(significant(f64::INFINITY, 4), "—");
    }

    #[test]
    fn json_rows_are_the_evaluation_rows_and_the_cpu_comparisons() {
        let m = TraceMeasure {
            rays: 4,
            trace_ms: 2.0,
            ..TraceMeasure::default()
        };
        let subject = Subject {
            backend: "gpu".into(),
            ..Subject::default()
        }
        .with_traversal(Traversal::HiZ);
        let row = Row {
            trace: TraceRow::new(&subject, "mixed", &m, Disagreement::default()),
            mismatches_vs_cpu: Some(Disagreement::default()),
            stats_mismatches_vs_cpu: None,
        };
        let v = serde_json::to_value(&row).expect("serializes");
        assert_eq!(v["backend"], "gpu");
        assert_eq!(v["traversal"], "hiz");
        assert_eq!(v["ray_type"], "mixed");
        assert_eq!(v["mrays_per_s"], 0.002);
        assert_eq!(v["differ"], 0);
        assert_eq!(v["mismatches_vs_cpu"]["compared"], 0);
        assert!(v["stats_mismatches_vs_cpu"].is_null());
    }
}
