//! One measuring path over `&mut dyn Tracer`, for `dirt eval` and `dirt bench`.
//!
//! * [`timed`] and [`median`]: repeats and their medians (milliseconds);
//! * [`build`]: the wall time of [`Tracer::build`] with the stages and the
//!   memory of its [`BuildReport`](dirt_core::BuildReport);
//! * [`trace`]: the wall time of [`Tracer::trace_into`], Mrays/s, the means
//!   of the per-ray statistics when the tracer [counts them](Tracer::counts_stats),
//!   and the rays it finished elsewhere;
//! * the error against ground truth is [`crate::compare`] under a [`crate::Match`];
//! * [`BuildRow`] and [`TraceRow`]: the rows of a report, made here and
//!   nowhere else ([`BuildRow::new`], [`TraceRow::new`]) from a [`Subject`]
//!   (what was measured) and the measurements. They serialize with serde.
//!
//! A leaf: it imports no other module of the harness but the error type and
//! the comparison of `lib.rs`.

use std::time::{Duration, Instant};

use dirt_core::{AdsParams, CoreError, Tracer, Traversal, ViewsKind};
use dirt_math::{Hit, Ray, RayStats, Triangle};
use serde::Serialize;

use crate::Disagreement;

/// A duration in milliseconds.
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The median (NaN for no values).
pub fn median(mut v: Vec<f64>) -> f64 {
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

/// Runs `f` until `done` says so of the run times so far (in ms); the
/// median wall time in ms and the last result.
fn timed_until<T, E>(
    mut f: impl FnMut() -> Result<T, E>,
    done: impl Fn(&[f64]) -> bool,
) -> Result<(f64, T), E> {
    let mut times = Vec::new();
    loop {
        let start = Instant::now();
        let last = f()?;
        times.push(ms(start.elapsed()));
        if done(&times) {
            return Ok((median(times), last));
        }
    }
}

/// Runs `f` `k` times (at least once); the median wall time in ms and the last result.
pub fn timed<T, E>(k: u32, f: impl FnMut() -> Result<T, E>) -> Result<(f64, T), E> {
    timed_until(f, |times| times.len() >= k.max(1) as usize)
}

/// Least wall time, in ms, that [`timed_steady`] spends on one measurement.
pub const STEADY_MS: f64 = 30.0;

/// Most runs [`timed_steady`] makes of one measurement.
pub const STEADY_RUNS: u32 = 11;

/// [`timed`], with more runs while they have taken under [`STEADY_MS`] in
/// all (at most [`STEADY_RUNS`]): on a noisy machine the median of two runs
/// of a fraction of a millisecond (a peer's build of a small scene, which
/// also starts its thread pool) is mostly the noise, and varied tenfold
/// from one evaluation to the next. Every backend is measured so.
pub fn timed_steady<T, E>(k: u32, f: impl FnMut() -> Result<T, E>) -> Result<(f64, T), E> {
    timed_until(f, |times| {
        let n = times.len() as u32;
        n >= k.max(1) && (n >= STEADY_RUNS || times.iter().sum::<f64>() >= STEADY_MS)
    })
}

/// How many times [`build`] and [`trace`] run what they time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Runs {
    /// At least this many, and more while under [`STEADY_MS`] ([`timed_steady`]).
    Steady(u32),
    /// Exactly once: a frame of a dynamic scene, built and traced once as an
    /// application does. Repeating its build would rebuild what the tracer
    /// has just built, and the median of the repeats would hide a choice
    /// made in the first of them.
    Once,
}

impl From<u32> for Runs {
    fn from(k: u32) -> Self {
        Runs::Steady(k)
    }
}

impl Runs {
    /// Times `f` as often as `self` says: the median wall time in ms and the last result.
    pub fn time<T, E>(self, f: impl FnMut() -> Result<T, E>) -> Result<(f64, T), E> {
        match self {
            Runs::Steady(k) => timed_steady(k, f),
            Runs::Once => timed(1, f),
        }
    }
}

/// Millions of rays per second for `rays` traced in `ms` milliseconds.
pub fn mrays(rays: usize, ms: f64) -> f64 {
    if ms > 0.0 {
        rays as f64 / ms / 1e3
    } else {
        f64::INFINITY
    }
}

/// What a build measurement found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildMeasure {
    /// Median wall time of the whole `build` call.
    pub build_ms: f64,
    /// Median of each stage the tracer names, in build order.
    pub stages: Vec<(&'static str, f64)>,
    /// Median of the per-build sums of the stages (`None` without stages).
    pub stages_ms: Option<f64>,
    /// Bytes of the structure, where the tracer says.
    pub memory: Option<u64>,
}

impl BuildMeasure {
    /// The median of stage `name`.
    pub fn stage(&self, name: &str) -> Option<f64> {
        self.stages.iter().find(|(n, _)| *n == name).map(|s| s.1)
    }
}

/// Builds `tracer` over `tris` as often as `runs` says (a count: at least
/// that many times, [`Runs::Steady`]): medians of the wall time and of each
/// stage. The tracer keeps the last build.
pub fn build(
    tracer: &mut dyn Tracer,
    tris: &[Triangle],
    runs: impl Into<Runs>,
) -> Result<BuildMeasure, CoreError> {
    let mut stages: Vec<(&'static str, Vec<f64>)> = Vec::new();
    let mut sums = Vec::new();
    let (build_ms, report) = runs.into().time(|| {
        let report = tracer.build(tris)?;
        for (name, d) in &report.stages {
            match stages.iter_mut().find(|(n, _)| n == name) {
                Some((_, v)) => v.push(ms(*d)),
                None => stages.push((name, vec![ms(*d)])),
            }
        }
        sums.push(report.stages.iter().map(|(_, d)| ms(*d)).sum::<f64>());
        Ok::<_, CoreError>(report)
    })?;
    let has_stages = !stages.is_empty();
    Ok(BuildMeasure {
        build_ms,
        stages: stages.into_iter().map(|(n, v)| (n, median(v))).collect(),
        stages_ms: has_stages.then(|| median(sums)),
        memory: report.memory,
    })
}

/// Means of per-ray statistics over the rays that have them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PerRay {
    pub tiles: Option<f64>,
    pub buckets: Option<f64>,
    pub tests: Option<f64>,
}

impl PerRay {
    /// Means of `stats` (all `None` for no statistics).
    pub fn of(stats: &[RayStats]) -> PerRay {
        if stats.is_empty() {
            return PerRay::default();
        }
        let n = stats.len() as f64;
        let mean =
            |f: fn(&RayStats) -> u32| stats.iter().map(|s| u64::from(f(s))).sum::<u64>() as f64 / n;
        PerRay {
            tiles: Some(mean(|s| s.tiles)),
            buckets: Some(mean(|s| s.buckets)),
            tests: Some(mean(|s| s.tests)),
        }
    }

    /// Brute force's one statistic: every ray tests every triangle.
    pub fn every_triangle(triangles: usize) -> PerRay {
        PerRay {
            tests: Some(triangles as f64),
            ..PerRay::default()
        }
    }
}

/// Where per-ray statistics are counted, for a tracer that counts them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatsPass {
    /// In one more trace, untimed, of the first `n` rays (counting costs
    /// time on the CPU, so the timed traces count nothing).
    Prefix(usize),
    /// In the timed traces themselves (the GPU's statistics come with its
    /// hits, at no extra cost).
    Timed,
}

/// What a trace measurement found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceMeasure {
    /// Rays traced (each timed trace traces all of them).
    pub rays: usize,
    /// Median wall time of the timed traces.
    pub trace_ms: f64,
    /// Means of the per-ray statistics (all `None` when the tracer counts none).
    pub per_ray: PerRay,
    /// Continuation rounds of the last timed trace (GPU; 0 for the CPU).
    pub continuation_rounds: usize,
    /// Hits of the last timed trace.
    pub hits: Vec<Hit>,
    /// The per-ray statistics counted (empty when none were).
    pub stats: Vec<RayStats>,
}

impl TraceMeasure {
    pub fn mrays_per_s(&self) -> f64 {
        mrays(self.rays, self.trace_ms)
    }
}

/// Traces `rays` through `tracer` as often as `runs` says (a count: at
/// least that many times, [`Runs::Steady`]); per-ray statistics as `pass`
/// says when the tracer counts them.
pub fn trace(
    tracer: &mut dyn Tracer,
    rays: &[Ray],
    runs: impl Into<Runs>,
    pass: StatsPass,
) -> Result<TraceMeasure, CoreError> {
    let counts = tracer.counts_stats();
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut stats = if counts && pass == StatsPass::Timed {
        vec![RayStats::default(); rays.len()]
    } else {
        Vec::new()
    };
    let (trace_ms, report) = runs.into().time(|| {
        let s = (!stats.is_empty()).then_some(stats.as_mut_slice());
        tracer.trace_into(rays, &mut hits, s)
    })?;
    if let (true, StatsPass::Prefix(n)) = (counts, pass) {
        let n = n.min(rays.len());
        let mut prefix = vec![Hit::MISS; n];
        stats = vec![RayStats::default(); n];
        tracer.trace_into(&rays[..n], &mut prefix, Some(&mut stats))?;
    }
    Ok(TraceMeasure {
        rays: rays.len(),
        trace_ms,
        per_ray: PerRay::of(&stats),
        continuation_rounds: report.continuation_rounds,
        hits,
        stats,
    })
}

/// A DIRT structure setting as reports name it; empty for the peers.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Setting {
    /// A short name, e.g. `cube r128 B8 S1`.
    pub label: String,
    /// `cube`, `single`, `single@camera`, `ortho` or `ortho2` (with `-x`,
    /// `-y` or `-z` when the axis is given, and `@x,y,z`, a point of the
    /// cut, when the split is not at the bounds' centre).
    pub views: String,
    pub resolution: Option<u32>,
    pub buckets: Option<u32>,
    pub tile: Option<u32>,
}

impl Setting {
    /// The setting of `params`; `at_camera`: the single view placed at the
    /// scene camera's eye.
    pub fn dirt(params: &AdsParams, at_camera: bool) -> Setting {
        let mut views = match (params.views, at_camera, params.axis) {
            (ViewsKind::Single, true, _) => "single@camera".to_string(),
            (v, _, Some(a)) => format!("{v}-{}", a.name()),
            (v, _, None) => v.to_string(),
        };
        // The split orthographic views' centre is a point of their cut.
        if let (ViewsKind::OrthoSplit, Some(c)) = (params.views, params.center) {
            views = format!("{views}@{:.3},{:.3},{:.3}", c.x, c.y, c.z);
        }
        Setting {
            label: format!(
                "{views} r{} B{} S{}",
                params.resolution, params.buckets, params.tile
            ),
            views,
            resolution: Some(params.resolution),
            buckets: Some(params.buckets),
            tile: Some(params.tile),
        }
    }
}

/// What was measured: the scene, the backend and its setting.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Subject {
    pub scene: String,
    pub triangles: usize,
    /// `dirt-cpu`, `dirt-gpu`, `brute`, a peer's name (`dirt bench`: its backend names).
    pub backend: String,
    pub setting: Setting,
    /// DIRT's traversal; `None` for tracers without one.
    pub traversal: Option<Traversal>,
}

impl Subject {
    /// The same subject walking with `traversal`.
    pub fn with_traversal(&self, traversal: Traversal) -> Subject {
        Subject {
            traversal: Some(traversal),
            ..self.clone()
        }
    }
}

/// What a DIRT structure says beyond its [`BuildReport`](dirt_core::BuildReport):
/// list nodes, and bytes per part beside the 001 Table 3 model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Structure {
    pub nodes: Option<u64>,
    /// `(bytes, model)` of the depth bounds with their Hi-Z levels.
    pub depth_hiz: Option<(u64, Option<f64>)>,
    /// `(bytes, model)` of the id buffer.
    pub id_buffer: Option<(u64, Option<f64>)>,
}

impl Structure {
    /// What the CPU structure says.
    pub fn of_cpu(ads: &dirt_cpu::Ads) -> Structure {
        let mem = ads.memory();
        let entry = |name: &str| {
            mem.entries
                .iter()
                .find(|e| e.name == name)
                .map(|e| (e.bytes, e.model))
        };
        Structure {
            nodes: Some(ads.lists.ids.len() as u64),
            depth_hiz: entry("depth + hi-z"),
            id_buffer: entry("id buffer"),
        }
    }

    /// What the GPU structure says.
    pub fn of_gpu(ads: &dirt_gpu::GpuAds) -> Structure {
        Structure {
            // A frame structure counts its list entries on the GPU: the feedback has them.
            nodes: Some(
                ads.feedback()
                    .map_or(u64::from(ads.nodes), |f| f.entries_needed),
            ),
            ..Structure::default()
        }
    }
}

/// One structure build.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRow {
    pub scene: String,
    pub triangles: usize,
    /// `dirt-cpu`, `dirt-gpu`, `obvhs`, `embree`.
    pub backend: String,
    /// Grid label (empty for peers).
    pub setting: String,
    pub views: String,
    pub resolution: Option<u32>,
    pub buckets: Option<u32>,
    pub tile: Option<u32>,
    pub fill_depth_ms: Option<f64>,
    pub mip_depth_ms: Option<f64>,
    pub fill_primitives_ms: Option<f64>,
    /// Median wall time of the whole build call.
    pub build_ms: f64,
    pub nodes: Option<u64>,
    pub depth_hiz_bytes: Option<u64>,
    pub depth_hiz_model_bytes: Option<f64>,
    pub id_buffer_bytes: Option<u64>,
    pub id_buffer_model_bytes: Option<f64>,
    pub total_bytes: Option<u64>,
    /// Median of the per-build sums of the stages (without the checks, views
    /// and uploads of the whole call).
    pub stages_ms: Option<f64>,
}

impl BuildRow {
    /// The row of a build of `subject`; `structure`: what a DIRT structure
    /// says beyond the tracer's report (default for other tracers).
    pub fn new(subject: &Subject, m: &BuildMeasure, structure: &Structure) -> BuildRow {
        let s = &subject.setting;
        BuildRow {
            scene: subject.scene.clone(),
            triangles: subject.triangles,
            backend: subject.backend.clone(),
            setting: s.label.clone(),
            views: s.views.clone(),
            resolution: s.resolution,
            buckets: s.buckets,
            tile: s.tile,
            fill_depth_ms: m.stage("fill_depth"),
            mip_depth_ms: m.stage("mip_depth"),
            fill_primitives_ms: m.stage("fill_primitives"),
            build_ms: m.build_ms,
            nodes: structure.nodes,
            depth_hiz_bytes: structure.depth_hiz.map(|d| d.0),
            depth_hiz_model_bytes: structure.depth_hiz.and_then(|d| d.1),
            id_buffer_bytes: structure.id_buffer.map(|d| d.0),
            id_buffer_model_bytes: structure.id_buffer.and_then(|d| d.1),
            total_bytes: m.memory,
            stages_ms: m.stages_ms,
        }
    }
}

/// One trace: a backend, a setting, a traversal and a ray type.
#[derive(Clone, Debug, Serialize)]
pub struct TraceRow {
    pub scene: String,
    pub triangles: usize,
    pub backend: String,
    pub setting: String,
    pub traversal: String,
    pub ray_type: String,
    pub rays: usize,
    /// Median wall time of tracing all `rays`.
    pub trace_ms: f64,
    pub mrays_per_s: f64,
    /// Per ray, over the rays whose statistics were counted (DIRT; brute
    /// force: tests only).
    pub tiles_per_ray: Option<f64>,
    pub buckets_per_ray: Option<f64>,
    pub tests_per_ray: Option<f64>,
    /// Rays of the first `compared` compared with brute force.
    pub compared: usize,
    pub differ: usize,
    pub differ_prim: usize,
    /// Of `differ_prim`: both hit another primitive, the truth's hit missed,
    /// a hit where the truth misses ([`Disagreement`]).
    pub other_prim: usize,
    pub missed: usize,
    pub false_hits: usize,
    /// Compared rays where both hit (any primitive).
    pub both_hit: usize,
    /// Relative error of `t` over the compared rays where both hit (none when no ray did).
    pub t_rel_mean: Option<f64>,
    pub t_rel_max: Option<f64>,
    /// Continuation rounds of the GPU's trace (rays that spent a dispatch's
    /// work budget continued in further dispatches); empty when none.
    pub continuation_rounds: Option<usize>,
}

impl TraceRow {
    /// The row of a trace of `subject` on rays of `ray_type`, with its error
    /// `d` against the ground truth.
    pub fn new(subject: &Subject, ray_type: &str, m: &TraceMeasure, d: Disagreement) -> TraceRow {
        TraceRow {
            scene: subject.scene.clone(),
            triangles: subject.triangles,
            backend: subject.backend.clone(),
            setting: subject.setting.label.clone(),
            traversal: subject
                .traversal
                .map_or_else(String::new, |t| t.name().to_string()),
            ray_type: ray_type.to_string(),
            rays: m.rays,
            trace_ms: m.trace_ms,
            mrays_per_s: m.mrays_per_s(),
            tiles_per_ray: m.per_ray.tiles,
            buckets_per_ray: m.per_ray.buckets,
            tests_per_ray: m.per_ray.tests,
            compared: d.compared,
            differ: d.differ,
            differ_prim: d.differ_prim,
            other_prim: d.other_prim,
            missed: d.missed,
            false_hits: d.false_hits,
            both_hit: d.both_hit,
            t_rel_mean: (d.both_hit > 0).then_some(d.t_rel_mean),
            t_rel_max: (d.both_hit > 0).then_some(d.t_rel_max),
            continuation_rounds: (m.continuation_rounds > 0).then_some(m.continuation_rounds),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Match, compare};
    use dirt_cpu::DirtCpu;
    use dirt_cpu::brute_force::Brute;
    use dirt_math::Vec3;

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }

    #[test]
    fn timed_runs_at_least_once_and_keeps_the_last() {
        let mut n = 0;
        let (_, last) = timed::<_, ()>(0, || {
            n += 1;
            Ok(n)
        })
        .expect("runs");
        assert_eq!((n, last), (1, 1));
        let (_, last) = timed::<_, ()>(3, || {
            n += 1;
            Ok(n)
        })
        .expect("runs");
        assert_eq!(last, 4);
        assert_eq!(mrays(2000, 2.0), 1.0);
        // Instant runs: as many as allowed; a long one: the runs asked for.
        let mut n = 0;
        timed_steady::<_, ()>(2, || {
            n += 1;
            Ok(())
        })
        .expect("runs");
        assert_eq!(n, STEADY_RUNS);
        let mut n = 0;
        timed_steady::<_, ()>(2, || {
            n += 1;
            std::thread::sleep(std::time::Duration::from_millis(STEADY_MS as u64));
            Ok(())
        })
        .expect("runs");
        assert_eq!(n, 2);
        // A frame: exactly one run, however short; a count: steady.
        let mut n = 0;
        Runs::Once
            .time::<_, ()>(|| {
                n += 1;
                Ok(())
            })
            .expect("runs");
        assert_eq!(n, 1);
        let mut n = 0;
        Runs::from(2)
            .time::<_, ()>(|| {
                n += 1;
                Ok(())
            })
            .expect("runs");
        assert_eq!(n, STEADY_RUNS);
        assert!(mrays(1, 0.0).is_infinite());
    }

    fn scene() -> (Vec<Triangle>, Vec<Ray>) {
        let tris = vec![
            Triangle::new(
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ),
            Triangle::new(
                Vec3::new(-1.0, -1.0, 1.0),
                Vec3::new(1.0, -1.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ),
        ];
        let rays = (0..20)
            .map(|i| {
                let x = -0.5 + 0.05 * i as f32;
                Ray::new(
                    Vec3::new(x, 0.0, -2.0),
                    Vec3::new(0.0, 0.0, 1.0),
                    0.0,
                    f32::INFINITY,
                )
            })
            .collect();
        (tris, rays)
    }

    #[test]
    fn one_path_measures_every_tracer() {
        let (tris, rays) = scene();
        let mut brute = Brute::default();
        let b = build(&mut brute, &tris, 2).expect("brute builds");
        assert!(b.stages.is_empty() && b.stages_ms.is_none());
        let truth = trace(&mut brute, &rays, 1, StatsPass::Prefix(5)).expect("brute traces");
        assert!(truth.stats.is_empty());
        assert_eq!(truth.per_ray, PerRay::default());
        assert!(truth.hits.iter().all(|h| h.prim == 0));

        let mut cpu = DirtCpu::new(AdsParams::default(), Traversal::HiZ);
        let b = build(&mut cpu, &tris, 3).expect("dirt builds");
        let names: Vec<&str> = b.stages.iter().map(|s| s.0).collect();
        assert_eq!(names, ["fill_depth", "mip_depth", "fill_primitives"]);
        assert!(b.stages_ms.is_some() && b.memory.is_some());
        let m = trace(&mut cpu, &rays, 2, StatsPass::Prefix(5)).expect("dirt traces");
        assert_eq!((m.rays, m.hits.len(), m.stats.len()), (20, 20, 5));
        assert!(m.per_ray.tests.is_some_and(|t| t >= 1.0));
        let timed_stats = trace(&mut cpu, &rays, 1, StatsPass::Timed).expect("dirt traces");
        assert_eq!(timed_stats.stats.len(), 20);

        let subject = Subject {
            scene: "two".into(),
            triangles: tris.len(),
            backend: "dirt-cpu".into(),
            setting: Setting::dirt(&AdsParams::default(), false),
            traversal: None,
        }
        .with_traversal(Traversal::HiZ);
        let row = BuildRow::new(&subject, &b, &Structure::of_cpu(cpu.ads().expect("built")));
        assert_eq!(row.setting, "cube r128 B8 S1");
        assert_eq!(row.views, "cube");
        assert!(row.fill_depth_ms.is_some() && row.depth_hiz_bytes.is_some());
        assert_eq!(row.total_bytes, b.memory);
        let row = TraceRow::new(
            &subject,
            "primary",
            &m,
            compare(&m.hits, &truth.hits, Match::Bits),
        );
        assert_eq!(
            (row.traversal.as_str(), row.differ, row.compared),
            ("hiz", 0, 20)
        );
        assert_eq!(row.continuation_rounds, None);
        let json = serde_json::to_value(&row).expect("serializes");
        assert_eq!(json["traversal"], "hiz");
    }

    #[test]
    fn per_ray_means_and_every_triangle() {
        let s = |tiles, buckets, tests| RayStats {
            tiles,
            buckets,
            tests,
            ..RayStats::default()
        };
        let p = PerRay::of(&[s(1, 2, 3), s(3, 4, 5)]);
        assert_eq!(
            (p.tiles, p.buckets, p.tests),
            (Some(2.0), Some(3.0), Some(4.0))
        );
        assert_eq!(PerRay::every_triangle(7).tests, Some(7.0));
        assert_eq!(PerRay::every_triangle(7).tiles, None);
    }
}
