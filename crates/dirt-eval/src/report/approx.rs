//! The report's section on error against run time: the approximate methods
//! beside exact DIRT, with the words that say where one beats the other.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::{f, mib, ray_order};
use crate::approx::Method;
use crate::harness::EvalResults;
use crate::measure::TraceRow;

const METHODS: [Method; 2] = [Method::Mmrt, Method::SingleLayer];

fn is_approx(backend: &str) -> bool {
    METHODS.iter().any(|m| m.name() == backend)
}

/// Error counts summed over rows.
#[derive(Clone, Copy, Default)]
struct Err {
    compared: usize,
    prim: usize,
    other: usize,
    missed: usize,
    false_hits: usize,
    both: f64,
    t_sum: f64,
    t_max: f64,
}

impl Err {
    fn of<'a>(rows: impl IntoIterator<Item = &'a TraceRow>) -> Err {
        let mut e = Err::default();
        for r in rows {
            e.compared += r.compared;
            e.prim += r.differ_prim;
            e.other += r.other_prim;
            e.missed += r.missed;
            e.false_hits += r.false_hits;
            // The mean of `t`'s error is over the rays where both hit: weight by them.
            if let Some(m) = r.t_rel_mean {
                e.both += r.both_hit as f64;
                e.t_sum += m * r.both_hit as f64;
            }
            e.t_max = e.t_max.max(r.t_rel_max.unwrap_or(0.0));
        }
        e
    }

    fn pct(&self, n: usize) -> String {
        pct(100.0 * n as f64 / self.compared.max(1) as f64)
    }

    fn prim_pct(&self) -> f64 {
        100.0 * self.prim as f64 / self.compared.max(1) as f64
    }

    /// The table cells `prim % | other % | missed % | false % | t rel. mean | t rel. max`.
    fn cells(&self) -> String {
        format!(
            "{} | {} | {} | {} | {} | {}",
            pct(self.prim_pct()),
            self.pct(self.other),
            self.pct(self.missed),
            self.pct(self.false_hits),
            self.t_mean(),
            sci(self.t_max)
        )
    }

    fn t_mean(&self) -> String {
        if self.both > 0.0 {
            sci(self.t_sum / self.both)
        } else {
            "–".into()
        }
    }
}

fn pct(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x < 0.1 {
        format!("{x:.3}")
    } else {
        format!("{x:.1}")
    }
}

fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.1e}")
    }
}

/// Build ms of (scene, backend, setting).
fn build_ms(res: &EvalResults, scene: &str, backend: &str, setting: &str) -> Option<f64> {
    super::build_ms(res, scene, backend, setting)
}

/// Writes the section; nothing when no approximate method was measured.
pub(super) fn section(s: &mut String, res: &EvalResults) {
    if !res.traces.iter().any(|t| is_approx(&t.backend)) {
        return;
    }
    let _ = writeln!(s, "## Error against run time: the approximate methods\n");
    let _ = writeln!(
        s,
        "Exact DIRT has no error, so its trade is against the seeds' approximate tracers (`dirt_cpu::screen_space`), measured on the same triangles and rays:\n\n\
         - **mmrt**: the multiview multilayer A-buffer of 004 (MMRT). Over the cubemap at the bounds centre, every triangle leaves a fragment at each pixel centre it covers (depth and id), bucketed per pixel in B buckets of linear depth and sorted per bucket; a ray marches the pixels of each view and hits the first fragment it passes within the thickness behind it (McGuire and Mara). A triangle that covers no pixel centre is lost; a ray that passes behind a surface within the thickness hits it falsely.\n\
         - **1-layer**: one depth layer (the nearest fragment per pixel) in a 90° view from the primary rays' eye towards the scene centre, traced the same way through the depth buffer's Hi-Z, as screen-space reflections are: what the view does not see, or sees behind a nearer surface, is lost.\n\n\
         Their knobs are swept one at a time around each default (resolution r, buckets B, thickness `th` as a fraction of the scene's diagonal, pixels marched per view `steps`, and the walk: every pixel, `linear`, or a min/max depth pyramid, `hiz`, which finds the same hits — the single layer's default is `hiz`, MMRT's every pixel); `knobs_*.svg` draws the error against each numeric knob. Error against brute force, over the compared rays: `other` another primitive, `missed` the hit not found, `false` a hit where there is none (together: `prim`, the Pareto plots' error), and the relative error of `t` where both hit. Time: build + trace of all ray types, ms (medians of {} runs).\n",
        res.repeat
    );
    settings_table(s, res);
    per_ray_type_table(s, res);
    memory_table(s, res);
    words(s, res);
}

/// Every approximate setting on every scene, all ray types together.
fn settings_table(s: &mut String, res: &EvalResults) {
    let _ = writeln!(
        s,
        "| scene | method | setting | build ms | trace ms | fragments | MiB (model) | prim % | other % | missed % | false % | t rel. mean | t rel. max |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for b in res.builds.iter().filter(|b| is_approx(&b.backend)) {
        let rows: Vec<&TraceRow> = res
            .traces
            .iter()
            .filter(|t| t.scene == b.scene && t.backend == b.backend && t.setting == b.setting)
            .collect();
        let e = Err::of(rows.iter().copied());
        let trace: f64 = rows.iter().map(|r| r.trace_ms).sum();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} ({}) | {} |",
            b.scene,
            b.backend,
            b.setting,
            f(b.build_ms),
            f(trace),
            b.nodes.map_or_else(|| "–".into(), |n| n.to_string()),
            b.id_buffer_bytes
                .map_or_else(|| "–".into(), |x| mib(x as f64)),
            b.id_buffer_model_bytes.map_or_else(|| "–".into(), mib),
            e.cells(),
        );
    }
    let _ = writeln!(s);
}

/// Each method's default, per ray type.
fn per_ray_type_table(s: &mut String, res: &EvalResults) {
    use crate::approx::{MMRT_DEFAULT, SINGLE_LAYER_DEFAULT};
    let _ = writeln!(
        s,
        "Per ray type, each method at its default (mmrt {}, 1-layer {}):\n",
        MMRT_DEFAULT.setting().label,
        SINGLE_LAYER_DEFAULT.setting().label
    );
    let _ = writeln!(
        s,
        "| scene | ray type | method | prim % | other % | missed % | false % | t rel. mean | t rel. max |\n|---|---|---|---:|---:|---:|---:|---:|---:|"
    );
    let defaults = [
        (Method::Mmrt, MMRT_DEFAULT.setting().label),
        (Method::SingleLayer, SINGLE_LAYER_DEFAULT.setting().label),
    ];
    let mut rows: Vec<&TraceRow> = res
        .traces
        .iter()
        .filter(|t| {
            defaults
                .iter()
                .any(|(m, l)| t.backend == m.name() && t.setting == *l)
        })
        .collect();
    let scene_order = |name: &str| res.scenes.iter().position(|s| s.name == name);
    rows.sort_by_key(|t| {
        (
            scene_order(&t.scene),
            ray_order(&t.ray_type),
            t.backend.clone(),
        )
    });
    for t in rows {
        let e = Err::of([t]);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            t.scene,
            t.ray_type,
            t.backend,
            e.cells(),
        );
    }
    let _ = writeln!(s);
}

/// DIRT's id buffer against MMRT's A-buffer at equal resolution and B.
fn memory_table(s: &mut String, res: &EvalResults) {
    let mut lines = Vec::new();
    for a in res
        .builds
        .iter()
        .filter(|b| b.backend == Method::Mmrt.name())
    {
        let Some(d) = res.builds.iter().find(|d| {
            d.scene == a.scene
                && d.backend == "dirt-cpu"
                && d.views == "cube"
                && d.resolution == a.resolution
                && d.buckets == a.buckets
                && d.tile == Some(1)
        }) else {
            continue;
        };
        // One line per (scene, resolution, B): the thickness and steps do not change memory.
        if lines
            .iter()
            .any(|(sc, r, b, ..): &(String, _, _, _, _, _, _)| {
                *sc == a.scene && *r == a.resolution && *b == a.buckets
            })
        {
            continue;
        }
        lines.push((
            a.scene.clone(),
            a.resolution,
            a.buckets,
            d.id_buffer_bytes,
            d.id_buffer_model_bytes,
            a.id_buffer_bytes,
            a.id_buffer_model_bytes,
        ));
    }
    if lines.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "Memory at equal resolution and B: DIRT's id buffer (cube, S1; model: 001 Table 3) against MMRT's A-buffer (fragments and per-pixel heads; model: 004 Table 2). DIRT stores a triangle once per bucket of every pixel it may touch, MMRT once per pixel centre it covers:\n"
    );
    let _ = writeln!(
        s,
        "| scene | r | B | DIRT id buffer MiB (model) | A-buffer MiB (model) | A-buffer / DIRT |\n|---|---:|---:|---:|---:|---:|"
    );
    let o = |x: Option<u64>| x.map_or_else(|| "–".into(), |b| mib(b as f64));
    let m = |x: Option<f64>| x.map_or_else(|| "–".into(), mib);
    for (sc, r, b, di, dm, ai, am) in lines {
        let ratio = match (ai, di) {
            (Some(a), Some(d)) if d > 0 => f(a as f64 / d as f64),
            _ => "–".into(),
        };
        let _ = writeln!(
            s,
            "| {sc} | {} | {} | {} ({}) | {} ({}) | {ratio} |",
            r.unwrap_or(0),
            b.unwrap_or(0),
            o(di),
            m(dm),
            o(ai),
            m(am)
        );
    }
    let _ = writeln!(s);
}

/// One approximate setting's cost and error on one ray type.
struct Point {
    /// Build + trace, ms.
    ms: f64,
    /// Rays with another primitive or hit/miss, %.
    prim: f64,
    label: String,
}

/// For each scene and ray type: the fastest exact DIRT (build + trace of
/// that type, any exact setting and traversal) against the approximate
/// settings, and in words where an approximate one is faster and at which error.
fn words(s: &mut String, res: &EvalResults) {
    // (scene, ray type) -> (ms, label) of the fastest exact DIRT.
    let mut exact: BTreeMap<(String, String), (f64, String)> = BTreeMap::new();
    // (scene, ray type) -> every approximate setting.
    let mut approx: BTreeMap<(String, String), Vec<Point>> = BTreeMap::new();
    for t in &res.traces {
        let key = (t.scene.clone(), t.ray_type.clone());
        if t.backend == "dirt-cpu" && super::exact(&t.setting) {
            let Some(b) = build_ms(res, &t.scene, &t.backend, &t.setting) else {
                continue;
            };
            let ms = b + t.trace_ms;
            let e = exact.entry(key).or_insert((f64::INFINITY, String::new()));
            if ms < e.0 {
                *e = (ms, format!("{} {}", t.setting, t.traversal));
            }
        } else if is_approx(&t.backend) || t.backend == "dirt-cpu" {
            // The approximate methods, and DIRT's reduced configuration that
            // is not exact (the single view at the camera).
            let Some(b) = build_ms(res, &t.scene, &t.backend, &t.setting) else {
                continue;
            };
            let e = Err::of([t]);
            approx.entry(key).or_default().push(Point {
                ms: b + t.trace_ms,
                prim: e.prim_pct(),
                label: format!("{} {} {}", t.backend, t.setting, t.traversal)
                    .trim_end()
                    .to_string(),
            });
        }
    }
    let _ = writeln!(
        s,
        "Where an approximate method beats exact DIRT in time (per scene and ray type; time = build + trace of that ray type's rays, as a frame of only those rays would cost; exact DIRT: its fastest exact setting and traversal in this run; the approximate settings include DIRT's single view at the camera, which is not exact):\n"
    );
    let _ = writeln!(
        s,
        "| scene | ray type | exact DIRT ms (setting) | faster approximate settings | least error among them (prim %) | fastest approximate ms (prim %) |\n|---|---|---|---:|---|---|"
    );
    let mut keys: Vec<&(String, String)> = approx.keys().collect();
    let scene_order = |name: &str| res.scenes.iter().position(|s| s.name == name);
    keys.sort_by_key(|(sc, ty)| (scene_order(sc), ray_order(ty)));
    let (mut beaten, mut total) = (0usize, 0usize);
    let mut best_errors = Vec::new();
    let mut none = Vec::new();
    for key in keys {
        let Some((ems, elabel)) = exact.get(key) else {
            continue;
        };
        total += 1;
        let points = &approx[key];
        let faster: Vec<&Point> = points.iter().filter(|p| p.ms < *ems).collect();
        let least = faster.iter().min_by(|a, b| a.prim.total_cmp(&b.prim));
        let fastest = points.iter().min_by(|a, b| a.ms.total_cmp(&b.ms));
        let _ = writeln!(
            s,
            "| {} | {} | {} ({elabel}) | {} of {} | {} | {} |",
            key.0,
            key.1,
            f(*ems),
            faster.len(),
            points.len(),
            least.map_or_else(
                || "none is faster".into(),
                |p| format!("{} ({})", p.label, pct(p.prim))
            ),
            fastest.map_or_else(String::new, |p| format!(
                "{} ({}) {}",
                f(p.ms),
                pct(p.prim),
                p.label
            )),
        );
        match least {
            Some(p) => {
                beaten += 1;
                best_errors.push((p.prim, format!("{} {}", key.0, key.1)));
            }
            None => none.push(format!("{} {}", key.0, key.1)),
        }
    }
    let _ = writeln!(s);
    if total > 0 {
        best_errors.sort_by(|a, b| a.0.total_cmp(&b.0));
        let _ = write!(
            s,
            "In words: on {beaten} of {total} (scene, ray type) pairs some approximate setting costs less time than exact DIRT's fastest."
        );
        if let (Some(lo), Some(hi)) = (best_errors.first(), best_errors.last()) {
            let _ = write!(
                s,
                " The least error it is bought at ranges from {} % of rays on another primitive or hit/miss ({}) to {} % ({}).",
                pct(lo.0),
                lo.1,
                pct(hi.0),
                hi.1
            );
        }
        if !none.is_empty() {
            let _ = write!(
                s,
                " No approximate setting is faster than exact DIRT on: {}.",
                none.join(", ")
            );
        }
        let _ = writeln!(s, "\n");
    }
}
