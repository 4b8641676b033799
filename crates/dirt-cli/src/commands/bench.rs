//! `dirt bench`: build and trace of every backend side by side, on one scene,
//! one set of parameters and one set of generated rays (the generator of
//! `dirt rays`), with each setting's error against brute force.
//!
//! A benchmark, not a test: it fails only on bad input. Figures are medians of
//! `--repeat` runs; brute force traces only the first `--brute-rays` rays and
//! its rate is reported as measured on that many. The table goes to stdout,
//! progress to stderr, the same figures optionally to a JSON file.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use dirt_core::Traversal;
use dirt_cpu::Ads;
use dirt_gpu::{Gpu, GpuAds};
use dirt_math::{Hit, Ray, RayStats, Triangle};

use crate::args::{AdsArgs, SceneArg};
use crate::commands::millis;
use crate::commands::trace::Backend;
use dirt_eval::rays::{self, Camera, RayKind};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(flatten)]
    scene: SceneArg,
    #[command(flatten)]
    ads: AdsArgs,
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
    /// Builds and traces per setting; medians are reported.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    /// Rays brute force traces (the first ones): the ground truth of the mismatch counts.
    #[arg(long, value_name = "N", default_value_t = 20_000)]
    brute_rays: usize,
    /// Also write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

const TRAVERSALS: [Traversal; 2] = [Traversal::Linear, Traversal::HiZ];

/// Median build figures of one backend, in milliseconds.
#[derive(Clone, Debug)]
struct BuildFigures {
    backend: &'static str,
    fill_depth: f64,
    mip_depth: f64,
    fill_primitives: f64,
    /// Median of the per-build sums of the three stages.
    total: f64,
    /// Median wall time of the whole call (checks, views, uploads included).
    wall: f64,
    nodes: u64,
}

/// Mismatching rays out of the rays compared.
#[derive(Clone, Copy, Debug)]
struct Mismatch {
    differ: usize,
    of: usize,
}

/// One line of the table.
#[derive(Clone, Debug)]
struct Row {
    backend: &'static str,
    traversal: Option<&'static str>,
    build_ms: Option<f64>,
    trace_ms: f64,
    rays: usize,
    /// Average tiles, buckets and tests per ray (brute force: tests only).
    tiles: Option<f64>,
    buckets: Option<f64>,
    tests: f64,
    vs_brute: Option<Mismatch>,
    vs_cpu: Option<Mismatch>,
    /// Rays whose statistics differ from the cpu's (same traversal).
    stats_vs_cpu: Option<Mismatch>,
}

impl Row {
    fn mrays(&self) -> f64 {
        if self.trace_ms > 0.0 {
            self.rays as f64 / self.trace_ms / 1e3
        } else {
            f64::INFINITY
        }
    }
}

/// What became of the GPU.
#[derive(Debug)]
enum GpuState {
    NotRequested,
    Unavailable(String),
    Used { adapter: String, exact: bool },
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Times `k` runs of `f`; returns the median in ms and the last result.
fn timed<T>(k: u32, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..k.max(1) {
        let start = Instant::now();
        let out = f()?;
        times.push(millis(start.elapsed()));
        last = Some(out);
    }
    match last {
        Some(out) => Ok((median(times), out)),
        None => bail!("no run"),
    }
}

/// Rays whose hits differ in any bit.
fn mismatches(a: &[Hit], b: &[Hit]) -> Mismatch {
    let of = a.len().min(b.len());
    let differ = a[..of]
        .iter()
        .zip(&b[..of])
        .filter(|(x, y)| bytemuck::bytes_of(*x) != bytemuck::bytes_of(*y))
        .count()
        + a.len().abs_diff(b.len());
    Mismatch {
        differ,
        of: a.len().max(b.len()),
    }
}

/// Average tiles, buckets and tests per ray.
fn per_ray(stats: &[RayStats]) -> (f64, f64, f64) {
    let n = stats.len().max(1) as f64;
    let sum = |f: fn(&RayStats) -> u32| stats.iter().map(|s| u64::from(f(s))).sum::<u64>() as f64;
    (
        sum(|s| s.tiles) / n,
        sum(|s| s.buckets) / n,
        sum(|s| s.tests) / n,
    )
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
    let params = args.ads.params();
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

    let mut rows = Vec::new();
    let mut builds = Vec::new();

    // Ground truth on the first rays.
    let n_brute = args.brute_rays.min(rays.len());
    let subset = &rays[..n_brute];
    let truth: Option<Vec<Hit>> = if n_brute == 0 {
        None
    } else if backends.contains(&Backend::Brute) {
        eprintln!("brute force: {n_brute} rays x {k}");
        let (ms, hits) = timed(k, || Ok(dirt_cpu::brute_force::trace(tris, subset)))?;
        rows.push(Row {
            backend: "brute",
            traversal: None,
            build_ms: None,
            trace_ms: ms,
            rays: n_brute,
            tiles: None,
            buckets: None,
            tests: tris.len() as f64,
            vs_brute: None,
            vs_cpu: None,
            stats_vs_cpu: None,
        });
        Some(hits)
    } else {
        eprintln!("brute force: {n_brute} rays once (ground truth, not timed)");
        Some(dirt_cpu::brute_force::trace(tris, subset))
    };
    let vs_brute = |hits: &[Hit]| {
        truth
            .as_ref()
            .map(|t| mismatches(&hits[..n_brute.min(hits.len())], t))
    };

    // CPU.
    let mut cpu_results: Vec<Option<Traced>> = vec![None, None];
    if backends.contains(&Backend::Cpu) {
        eprintln!("cpu: build x {k}");
        let mut stage_ms = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
        let (wall, ads) = timed(k, || {
            let ads = Ads::build(tris, &params).with_context(|| {
                format!(
                    "cannot build the acceleration structure of {} ({params:?})",
                    scene.name
                )
            })?;
            let t = ads.timings;
            for (v, d) in
                stage_ms
                    .iter_mut()
                    .zip([t.fill_depth, t.mip_depth, t.fill_primitives, t.total()])
            {
                v.push(millis(d));
            }
            Ok(ads)
        })?;
        let [fd, md, fp, total] = stage_ms.map(median);
        builds.push(BuildFigures {
            backend: "cpu",
            fill_depth: fd,
            mip_depth: md,
            fill_primitives: fp,
            total,
            wall,
            nodes: ads.lists.ids.len() as u64,
        });
        for (slot, traversal) in cpu_results.iter_mut().zip(TRAVERSALS) {
            eprintln!("cpu: trace {} x {k}", Traversal::name(traversal));
            let (ms, hits) = timed(k, || Ok(dirt_cpu::trace(&ads, tris, &rays, traversal)))?;
            let (_, stats) = dirt_cpu::trace_with_stats(&ads, tris, &rays, traversal);
            let (tiles, buckets, tests) = per_ray(&stats);
            rows.push(Row {
                backend: "cpu",
                traversal: Some(Traversal::name(traversal)),
                build_ms: Some(total),
                trace_ms: ms,
                rays: rays.len(),
                tiles: Some(tiles),
                buckets: Some(buckets),
                tests,
                vs_brute: vs_brute(&hits),
                vs_cpu: None,
                stats_vs_cpu: None,
            });
            *slot = Some((hits, stats));
        }
    }

    // GPU.
    let gpu_state = if backends.contains(&Backend::Gpu) {
        match crate::gpu::open_gpu() {
            Ok(gpu) => {
                eprintln!("{}", crate::gpu::gpu_line(&gpu));
                let adapter = gpu.describe();
                let exact = gpu.exact;
                match bench_gpu(&gpu, tris, &params, &rays, k, &cpu_results, &vs_brute) {
                    Ok((build, gpu_rows)) => {
                        builds.push(build);
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
    rows.sort_by_key(|r| order(r.backend));

    let report = Report {
        scene: &scene.name,
        triangles: tris.len(),
        rays: rays.len(),
        kind: kind_name(args.kind),
        seed: args.seed,
        ads: &args.ads,
        repeat: k,
        brute_rays: n_brute,
        threads,
        gpu: &gpu_state,
        builds: &builds,
        rows: &rows,
    };
    print!("{}", report.markdown());
    if let Some(path) = &args.json {
        std::fs::write(path, report.json())
            .with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// Builds and traces on the GPU; rows for both traversals.
fn bench_gpu(
    gpu: &Gpu,
    tris: &[Triangle],
    params: &dirt_core::AdsParams,
    rays: &[Ray],
    k: u32,
    cpu_results: &[Option<Traced>],
    vs_brute: &dyn Fn(&[Hit]) -> Option<Mismatch>,
) -> Result<(BuildFigures, Vec<Row>)> {
    eprintln!("gpu: build x {k}");
    let mut stage_ms = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    let (wall, ads) = timed(k, || {
        let ads = GpuAds::build(gpu, tris, params)
            .with_context(|| format!("cannot build the acceleration structure ({params:?})"))?;
        let t = ads.timings;
        for (v, d) in stage_ms.iter_mut().zip([
            t.fill_depth,
            t.mip_depth,
            t.fill_primitives,
            t.fill_depth + t.mip_depth + t.fill_primitives,
        ]) {
            v.push(millis(d));
        }
        Ok(ads)
    })?;
    let [fd, md, fp, total] = stage_ms.map(median);
    let build = BuildFigures {
        backend: "gpu",
        fill_depth: fd,
        mip_depth: md,
        fill_primitives: fp,
        total,
        wall,
        nodes: u64::from(ads.nodes),
    };
    let mut rows = Vec::new();
    for (cpu, traversal) in cpu_results.iter().zip(TRAVERSALS) {
        eprintln!("gpu: trace {} x {k}", Traversal::name(traversal));
        let (ms, traced) = timed(k, || {
            dirt_gpu::trace::trace_report(gpu, &ads, rays, traversal).context("cannot trace")
        })?;
        if traced.cpu_finished > 0 {
            eprintln!(
                "gpu: {} of {} rays spent their GPU work budget and were finished by the CPU reference (included in the time)",
                traced.cpu_finished,
                rays.len()
            );
        }
        let (hits, stats) = (traced.hits, traced.stats);
        if hits.len() != rays.len() {
            bail!(
                "the GPU returned {} hits for {} rays",
                hits.len(),
                rays.len()
            );
        }
        if let Some((c, c_stats)) = cpu {
            report_differences(traversal, tris, rays, &hits, c);
            report_stats_differences(traversal, &stats, c_stats);
        }
        let (tiles, buckets, tests) = per_ray(&stats);
        rows.push(Row {
            backend: "gpu",
            traversal: Some(Traversal::name(traversal)),
            build_ms: Some(total),
            trace_ms: ms,
            rays: rays.len(),
            tiles: Some(tiles),
            buckets: Some(buckets),
            tests,
            vs_brute: vs_brute(&hits),
            vs_cpu: cpu.as_ref().map(|(c, _)| mismatches(&hits, c)),
            stats_vs_cpu: cpu.as_ref().map(|(_, c)| Mismatch {
                differ: stats.iter().zip(c).filter(|(a, b)| a != b).count(),
                of: stats.len(),
            }),
        });
    }
    Ok((build, rows))
}

/// Hits and statistics of one traversal.
type Traced = (Vec<Hit>, Vec<RayStats>);

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

/// Everything the table and the JSON say.
struct Report<'a> {
    scene: &'a str,
    triangles: usize,
    rays: usize,
    kind: String,
    seed: u64,
    ads: &'a AdsArgs,
    repeat: u32,
    brute_rays: usize,
    threads: usize,
    gpu: &'a GpuState,
    builds: &'a [BuildFigures],
    rows: &'a [Row],
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

fn mismatch_cell(m: Option<Mismatch>) -> String {
    m.map_or_else(|| "—".to_owned(), |m| format!("{} / {}", m.differ, m.of))
}

impl Report<'_> {
    fn gpu_words(&self) -> String {
        match self.gpu {
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
        let p = self.ads.params();
        let center = p
            .center
            .map_or_else(|| "bounds centre".to_owned(), |c| c.to_string());
        format!(
            "{} views, resolution {}, {} buckets, tile {}, centre {center}",
            self.ads.views, p.resolution, p.buckets, p.tile
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
            self.threads,
            self.gpu_words()
        );
        s.push('\n');
        s.push_str(
            "| backend | traversal | build ms | trace ms | Mrays/s | rays | tiles/ray | buckets/ray | tests/ray | mismatches vs brute | mismatches vs cpu | stats ≠ cpu |\n",
        );
        s.push_str("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
        for r in self.rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.backend,
                r.traversal.unwrap_or("—"),
                opt(r.build_ms, 2),
                fixed(r.trace_ms, 2),
                significant(r.mrays(), 4),
                r.rays,
                opt(r.tiles, 2),
                opt(r.buckets, 2),
                fixed(r.tests, 2),
                if r.backend == "brute" {
                    "reference".to_owned()
                } else {
                    mismatch_cell(r.vs_brute)
                },
                mismatch_cell(r.vs_cpu),
                mismatch_cell(r.stats_vs_cpu)
            );
        }
        if !self.builds.is_empty() {
            s.push('\n');
            s.push_str(
                "| build | fill_depth ms | mip_depth ms | fill_primitives ms | total ms | wall ms | list nodes |\n",
            );
            s.push_str("|---|--:|--:|--:|--:|--:|--:|\n");
            for b in self.builds {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    b.backend,
                    fixed(b.fill_depth, 2),
                    fixed(b.mip_depth, 2),
                    fixed(b.fill_primitives, 2),
                    fixed(b.total, 2),
                    fixed(b.wall, 2),
                    b.nodes
                );
            }
        }
        s.push('\n');
        let _ = write!(
            s,
            "Medians of {} run(s). build ms: the three stages (wall ms: the whole build call, \
             checks, views and uploads included). trace ms: wall time of the whole trace \
             (gpu: uploads, dispatches and read-back included). ",
            self.repeat
        );
        let brute_timed = self.rows.iter().any(|r| r.backend == "brute");
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

    fn json(&self) -> String {
        let p = self.ads.params();
        let center = p.center.map_or_else(
            || "null".to_owned(),
            |c| {
                format!(
                    "[{}, {}, {}]",
                    jf(c.x.into()),
                    jf(c.y.into()),
                    jf(c.z.into())
                )
            },
        );
        let (gpu, gpu_exact, gpu_error) = match self.gpu {
            GpuState::NotRequested => ("null".to_owned(), "null", "null".to_owned()),
            GpuState::Unavailable(reason) => ("null".to_owned(), "null", json_str(reason)),
            GpuState::Used { adapter, exact } => (
                json_str(adapter),
                if *exact { "true" } else { "false" },
                "null".to_owned(),
            ),
        };
        let mut s = String::new();
        let _ = writeln!(s, "{{");
        let _ = writeln!(s, "  \"scene\": {},", json_str(self.scene));
        let _ = writeln!(s, "  \"triangles\": {},", self.triangles);
        let _ = writeln!(s, "  \"rays\": {},", self.rays);
        let _ = writeln!(s, "  \"kind\": {},", json_str(&self.kind));
        let _ = writeln!(s, "  \"seed\": {},", self.seed);
        let _ = writeln!(
            s,
            "  \"params\": {{\"views\": {}, \"resolution\": {}, \"buckets\": {}, \"tile\": {}, \"center\": {center}}},",
            json_str(&self.ads.views.to_string()),
            p.resolution,
            p.buckets,
            p.tile
        );
        let _ = writeln!(s, "  \"repeat\": {},", self.repeat);
        let _ = writeln!(s, "  \"brute_rays\": {},", self.brute_rays);
        let _ = writeln!(s, "  \"cpu_threads\": {},", self.threads);
        let _ = writeln!(s, "  \"gpu\": {gpu},");
        let _ = writeln!(s, "  \"gpu_exact\": {gpu_exact},");
        let _ = writeln!(s, "  \"gpu_error\": {gpu_error},");
        let builds: Vec<String> = self
            .builds
            .iter()
            .map(|b| {
                format!(
                    "    {{\"backend\": {}, \"fill_depth_ms\": {}, \"mip_depth_ms\": {}, \"fill_primitives_ms\": {}, \"total_ms\": {}, \"wall_ms\": {}, \"nodes\": {}}}",
                    json_str(b.backend),
                    jf(b.fill_depth),
                    jf(b.mip_depth),
                    jf(b.fill_primitives),
                    jf(b.total),
                    jf(b.wall),
                    b.nodes
                )
            })
            .collect();
        let _ = writeln!(s, "  \"builds\": [\n{}\n  ],", builds.join(",\n"));
        let mism = |m: Option<Mismatch>| {
            m.map_or_else(
                || "null".to_owned(),
                |m| format!("{{\"differ\": {}, \"of\": {}}}", m.differ, m.of),
            )
        };
        let rows: Vec<String> = self
            .rows
            .iter()
            .map(|r| {
                format!(
                    "    {{\"backend\": {}, \"traversal\": {}, \"build_ms\": {}, \"trace_ms\": {}, \"mrays_per_s\": {}, \"rays\": {}, \"tiles_per_ray\": {}, \"buckets_per_ray\": {}, \"tests_per_ray\": {}, \"mismatches_vs_brute\": {}, \"mismatches_vs_cpu\": {}, \"stats_mismatches_vs_cpu\": {}}}",
                    json_str(r.backend),
                    r.traversal.map_or_else(|| "null".to_owned(), json_str),
                    r.build_ms.map_or_else(|| "null".to_owned(), jf),
                    jf(r.trace_ms),
                    jf(r.mrays()),
                    r.rays,
                    r.tiles.map_or_else(|| "null".to_owned(), jf),
                    r.buckets.map_or_else(|| "null".to_owned(), jf),
                    jf(r.tests),
                    mism(r.vs_brute),
                    mism(r.vs_cpu),
                    mism(r.stats_vs_cpu)
                )
            })
            .collect();
        let _ = writeln!(s, "  \"rows\": [\n{}\n  ]", rows.join(",\n"));
        let _ = writeln!(s, "}}");
        s
    }
}

/// A JSON number (`null` when not finite).
fn jf(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".to_owned()
    }
}

/// A JSON string literal.
fn json_str(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if u32::from(c) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
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
    fn median_of_odd_and_even() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }

    #[test]
    fn mismatches_count_any_bit() {
        let a = Hit {
            prim: 1,
            t: 1.0,
            u: 0.25,
            v: 0.5,
        };
        let mut b = a;
        b.v = f32::from_bits(a.v.to_bits() + 1);
        let m = mismatches(&[a, a, Hit::MISS], &[a, b, Hit::MISS]);
        assert_eq!((m.differ, m.of), (1, 3));
        // -0.0 == 0.0 as floats, but not as bits.
        let mut z = a;
        z.u = 0.0;
        let mut nz = a;
        nz.u = -0.0;
        assert_eq!(mismatches(&[z], &[nz]).differ, 1);
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
    fn json_strings_are_escaped() {
        assert_eq!(json_str("a\"b\\c\nd\u{1}"), "\"a\\\"b\\\\c\\nd\\u0001\"");
        assert_eq!(jf(1.5), "1.5");
        assert_eq!(jf(f64::NAN), "null");
    }
}
