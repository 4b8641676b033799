//! SVG plots of a run with `plotters`: a Pareto plot per scene (error against
//! time over the grid, the peers and the approximate methods, the frontier
//! drawn), the approximate methods' error against each knob, build and trace
//! time against B and S,
//! and the per-frame cost of the deforming scene.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;

use crate::EvalError;
use crate::harness::EvalResults;
use crate::measure::TraceRow;

/// A written plot: its title and file name (inside the output folder).
#[derive(Clone, Debug)]
pub struct Plot {
    pub title: String,
    pub file: String,
    /// The scene it belongs to, if one.
    pub scene: Option<String>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn plot_err(path: &Path, e: impl std::fmt::Display) -> EvalError {
    EvalError::Output {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// A tick label with a few significant digits.
fn short(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2e}")
    }
}

/// One point of a Pareto plot.
#[derive(Clone, Debug)]
pub struct ParetoPoint {
    pub series: String,
    pub label: String,
    /// Build + trace of every ray type, ms.
    pub time_ms: f64,
    /// Rays whose primitive (or hit/miss) differs from brute force's, in %
    /// of the compared rays (`t` errors are tabled in the report).
    pub error_pct: f64,
}

/// The points of one scene: every (setting, traversal) of DIRT on the CPU,
/// every peer, every density of the grid and every setting of the
/// approximate methods, each with its build plus the trace of all ray types.
pub fn pareto_points(res: &EvalResults, scene: &str) -> Vec<ParetoPoint> {
    let mut groups: BTreeMap<(String, String, String), Vec<&TraceRow>> = BTreeMap::new();
    for t in res.traces.iter().filter(|t| t.scene == scene) {
        if t.backend == "brute" || t.backend == "dirt-gpu" {
            continue;
        }
        groups
            .entry((t.backend.clone(), t.setting.clone(), t.traversal.clone()))
            .or_default()
            .push(t);
    }
    groups
        .into_iter()
        .filter_map(|((backend, setting, traversal), rows)| {
            let build = res
                .builds
                .iter()
                .find(|b| b.scene == scene && b.backend == backend && b.setting == setting)?
                .build_ms;
            let trace: f64 = rows.iter().map(|r| r.trace_ms).sum();
            let compared: usize = rows.iter().map(|r| r.compared).sum();
            let differ: usize = rows.iter().map(|r| r.differ_prim).sum();
            // The grid's densities are one method; its label says the density.
            let (series, label) = if backend == "dirt-cpu" {
                (format!("dirt-cpu {traversal}"), setting)
            } else if let Some(density) = backend.strip_prefix("grid ") {
                ("grid".to_string(), density.to_string())
            } else {
                (backend.clone(), setting)
            };
            Some(ParetoPoint {
                series,
                label,
                time_ms: build + trace,
                error_pct: 100.0 * differ as f64 / compared.max(1) as f64,
            })
        })
        .collect()
}

/// Writes every plot into `dir`.
pub fn write_all(res: &EvalResults, dir: &Path) -> Result<Vec<Plot>, EvalError> {
    let mut plots = Vec::new();
    for s in &res.scenes {
        let file = format!("pareto_{}.svg", s.name);
        let title = format!("{}: error vs build + trace time", s.name);
        pareto(&pareto_points(res, &s.name), &title, &dir.join(&file))?;
        plots.push(Plot {
            title,
            file,
            scene: Some(s.name.clone()),
        });
    }
    for (knob, file) in [("B", "sweep_buckets.svg"), ("S", "sweep_tile.svg")] {
        if sweep(res, knob, &dir.join(file))? {
            plots.push(Plot {
                title: format!(
                    "build and trace time against {knob}, relative to the default (cube, r128)"
                ),
                file: file.into(),
                scene: None,
            });
        }
    }
    for method in [
        crate::approx::Method::Mmrt,
        crate::approx::Method::SingleLayer,
    ] {
        let file = format!("knobs_{}.svg", method.name());
        if approx_knobs(res, method, &dir.join(&file))? {
            plots.push(Plot {
                title: format!(
                    "{}: error against each knob, the others at their defaults",
                    method.name()
                ),
                file,
                scene: None,
            });
        }
    }
    if !res.renders.is_empty() {
        let file = "renders.svg";
        renders(res, &dir.join(file))?;
        plots.push(Plot {
            title: "path tracing: image error against wall time as samples accumulate".into(),
            file: file.into(),
            scene: None,
        });
    }
    if !res.dynamic.is_empty() {
        let file = "dynamic.svg";
        dynamic(res, &dir.join(file))?;
        plots.push(Plot {
            title: "deforming scene: rebuild + trace per frame".into(),
            file: file.into(),
            scene: None,
        });
    }
    Ok(plots)
}

fn pareto(points: &[ParetoPoint], title: &str, path: &Path) -> Result<(), EvalError> {
    let root = SVGBackend::new(path, (720, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let xmax = points.iter().map(|p| p.time_ms).fold(1e-3, f64::max) * 1.3;
    let xmin = points.iter().map(|p| p.time_ms).fold(xmax, f64::min) / 1.3;
    let ymax = points.iter().map(|p| p.error_pct).fold(0.0, f64::max);
    let ymax = if ymax > 0.0 { ymax * 1.15 } else { 1.0 };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((xmin..xmax).log_scale(), -0.02 * ymax..ymax)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("build + trace of all ray types, ms (log)")
        .x_label_formatter(&|v| short(*v))
        .y_desc("rays with another primitive or hit/miss, %")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    let mut series: Vec<&str> = points.iter().map(|p| p.series.as_str()).collect();
    series.dedup();
    series.sort_unstable();
    series.dedup();
    for (i, s) in series.iter().enumerate() {
        let c = COLORS[i % COLORS.len()];
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| p.series == *s)
                    .map(|p| Circle::new((p.time_ms, p.error_pct), 4, c.filled())),
            )
            .map_err(|e| plot_err(path, e))?
            .label(*s)
            .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
    }
    // The frontier: no other point is both faster and no worse.
    let mut sorted: Vec<&ParetoPoint> = points.iter().collect();
    sorted.sort_by(|a, b| a.time_ms.total_cmp(&b.time_ms));
    let mut frontier = Vec::new();
    let mut best = f64::INFINITY;
    for p in sorted {
        if p.error_pct < best {
            best = p.error_pct;
            frontier.push((p.time_ms, p.error_pct));
        }
    }
    chart
        .draw_series(LineSeries::new(frontier, BLACK.stroke_width(1)))
        .map_err(|e| plot_err(path, e))?
        .label("Pareto frontier")
        .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], BLACK));
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Build and trace (all ray types, linear) against B (S 1) or S (B 8), cube
/// r128, one line per scene. Returns false when the grid has no such sweep.
fn sweep(res: &EvalResults, knob: &str, path: &Path) -> Result<bool, EvalError> {
    // (scene, x) -> (build ms, trace ms)
    let mut lines: BTreeMap<String, Vec<(f64, f64, f64)>> = BTreeMap::new();
    for b in res
        .builds
        .iter()
        .filter(|b| b.backend == "dirt-cpu" && b.views == "cube" && b.resolution == Some(128))
    {
        let (Some(buckets), Some(tile)) = (b.buckets, b.tile) else {
            continue;
        };
        let x = match knob {
            "B" if tile == 1 => buckets,
            "S" if buckets == 8 => tile,
            _ => continue,
        };
        let trace: f64 = res
            .traces
            .iter()
            .filter(|t| {
                t.scene == b.scene
                    && t.backend == "dirt-cpu"
                    && t.setting == b.setting
                    && t.traversal == "linear"
            })
            .map(|t| t.trace_ms)
            .sum();
        lines
            .entry(b.scene.clone())
            .or_default()
            .push((f64::from(x), b.build_ms, trace));
    }
    lines.retain(|_, v| v.len() >= 2);
    if lines.is_empty() {
        return Ok(false);
    }
    // Each scene relative to its own value at the default (B 8, S 1), so
    // scenes of very different sizes share one linear axis.
    let base = if knob == "B" { 8.0 } else { 1.0 };
    for v in lines.values_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(&(_, b0, t0)) = v.iter().find(|p| p.0 == base) {
            for p in v.iter_mut() {
                p.1 /= b0;
                p.2 /= t0;
            }
        } else {
            v.clear();
        }
    }
    lines.retain(|_, v| !v.is_empty());
    if lines.is_empty() {
        return Ok(false);
    }
    let root = SVGBackend::new(path, (960, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let (left, right) = root.split_horizontally(480);
    let xmax = lines.values().flatten().map(|p| p.0).fold(1.0, f64::max);
    for (area, which, name) in [
        (left, 1usize, "build"),
        (right, 2usize, "trace, all ray types (linear)"),
    ] {
        let val = |p: &(f64, f64, f64)| if which == 1 { p.1 } else { p.2 };
        let ymax = lines.values().flatten().map(val).fold(1.0, f64::max) * 1.45;
        let mut chart = ChartBuilder::on(&area)
            .caption(format!("{name} vs {knob}"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(0.0..xmax * 1.05, 0.0..ymax)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc(knob)
            .y_desc(format!("time / time at {knob} = {base}"))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (i, (scene, pts)) in lines.iter().enumerate() {
            let c = COLORS[i % COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.0, val(p))),
                    c.stroke_width(2),
                ))
                .map_err(|e| plot_err(path, e))?
                .label(scene.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], c));
            chart
                .draw_series(
                    pts.iter()
                        .map(|p| Circle::new((p.0, val(p)), 3, c.filled())),
                )
                .map_err(|e| plot_err(path, e))?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(true)
}

fn dynamic(res: &EvalResults, path: &Path) -> Result<(), EvalError> {
    let root = SVGBackend::new(path, (720, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    // The grid's first ray count's frames (every scene and count is in the
    // report's tables).
    let first = res.dynamic.first().map_or(0, |r| r.rays);
    let rows: Vec<&crate::dynamic::DynamicRow> = res
        .dynamic
        .iter()
        .filter(|r| r.rays == first && r.scene == crate::dynamic::WAVE)
        .collect();
    let mut backends: Vec<&str> = rows.iter().map(|r| r.backend.as_str()).collect();
    backends.sort_unstable();
    backends.dedup();
    let frames = rows.iter().map(|r| r.frame).max().unwrap_or(0) as f64;
    let ymax = rows.iter().map(|r| r.frame_ms).fold(1e-3, f64::max) * 1.5;
    let ymin = rows
        .iter()
        .map(|r| r.frame_ms)
        .fold(ymax, f64::min)
        .max(1e-3)
        / 1.5;
    let tris = rows.first().map_or(0, |r| r.triangles);
    let rays = rows.first().map_or(0, |r| r.rays);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("deforming grid, {tris} triangles, {rays} rays: rebuild + trace per frame"),
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(-0.2..frames + 0.2, (ymin..ymax).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc("ms per frame (log)")
        .y_label_formatter(&|v| short(*v))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (i, b) in backends.iter().enumerate() {
        let c = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.backend == *b)
            .map(|r| (r.frame as f64, r.frame_ms))
            .collect();
        chart
            .draw_series(LineSeries::new(pts, c.stroke_width(2)))
            .map_err(|e| plot_err(path, e))?
            .label(*b)
            .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], c));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// RMSE and FLIP against wall time, one line per tracer.
/// The value of knob `key` (`r`, `B`, `th`, `steps`) in an approximate
/// method's setting label, e.g. `r128 B8 th1e-2`; `steps` is 0 when absent.
fn knob(label: &str, key: &str) -> Option<f64> {
    let v = label
        .split(' ')
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.parse::<f64>().ok()));
    if key == "steps" {
        return Some(v.unwrap_or(0.0));
    }
    v
}

/// Error (% of rays with another primitive or hit/miss, all ray types) of an
/// approximate method against each of its knobs, the other knobs at the
/// method's default, one line per scene. Returns false when nothing was swept.
fn approx_knobs(
    res: &EvalResults,
    method: crate::approx::Method,
    path: &Path,
) -> Result<bool, EvalError> {
    use crate::approx::{MMRT_DEFAULT, Method, SINGLE_LAYER_DEFAULT};
    let default = match method {
        Method::Mmrt => MMRT_DEFAULT,
        Method::SingleLayer => SINGLE_LAYER_DEFAULT,
    }
    .setting()
    .label;
    let knobs: &[(&str, &str)] = match method {
        Method::Mmrt => &[
            ("r", "resolution"),
            ("B", "buckets B"),
            ("th", "thickness / diagonal"),
            ("steps", "steps per view (0: unbounded)"),
        ],
        Method::SingleLayer => &[
            ("r", "resolution"),
            ("th", "thickness / diagonal"),
            ("steps", "steps per view (0: unbounded)"),
        ],
    };
    // (scene, label) -> error %.
    let mut err: BTreeMap<(String, String), (usize, usize)> = BTreeMap::new();
    for t in res.traces.iter().filter(|t| t.backend == method.name()) {
        let e = err.entry((t.scene.clone(), t.setting.clone())).or_default();
        e.0 += t.differ_prim;
        e.1 += t.compared;
    }
    if err.len() < 2 {
        return Ok(false);
    }
    // The walk (a word, not a number) changes time, not error: its rows are left out here.
    let walk = |label: &str| label.ends_with(" hiz") || label.ends_with(" linear");
    let others_default = |label: &str, key: &str| {
        walk(label) == walk(&default)
            && knobs
                .iter()
                .filter(|(k, _)| *k != key)
                .all(|(k, _)| knob(label, k) == knob(&default, k))
    };
    let root = SVGBackend::new(path, (360 * knobs.len() as u32, 340)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let areas = root.split_evenly((1, knobs.len()));
    let scenes: Vec<&str> = res.scenes.iter().map(|s| s.name.as_str()).collect();
    for (area, (key, name)) in areas.iter().zip(knobs) {
        // scene -> (knob value, error %), sorted by value.
        let mut lines: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
        for ((scene, label), (d, c)) in &err {
            if let (Some(x), true) = (knob(label, key), others_default(label, key)) {
                let pct = 100.0 * *d as f64 / (*c).max(1) as f64;
                lines.entry(scene.as_str()).or_default().push((x, pct));
            }
        }
        for l in lines.values_mut() {
            l.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        let xs = lines.values().flatten().map(|p| p.0);
        let xmin = xs.clone().fold(f64::INFINITY, f64::min);
        let xmax = xs.fold(f64::NEG_INFINITY, f64::max);
        if !(xmin.is_finite() && xmax > xmin) {
            continue;
        }
        let ymax = lines.values().flatten().map(|p| p.1).fold(1.0, f64::max) * 1.1;
        let log = *key != "steps" && *key != "B" && xmin > 0.0;
        let (x0, x1) = if log {
            (xmin / 1.2, xmax * 1.2)
        } else {
            (xmin - 0.05 * (xmax - xmin), xmax + 0.05 * (xmax - xmin))
        };
        let caption = (format!("{}: {name}", method.name()), ("sans-serif", 14));
        let mut builder = ChartBuilder::on(area);
        builder
            .caption(caption.0, caption.1)
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(45);
        // One drawing path for both scales: plotters' log and linear axes are different types.
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart.map_err(|e| plot_err(path, e))?;
                chart
                    .configure_mesh()
                    .x_desc(*name)
                    .y_desc("another primitive or hit/miss, %")
                    .x_label_formatter(&|v| short(*v))
                    .draw()
                    .map_err(|e| plot_err(path, e))?;
                for (scene, pts) in &lines {
                    let i = scenes.iter().position(|s| s == scene).unwrap_or(0);
                    let c = COLORS[i % COLORS.len()];
                    chart
                        .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                        .map_err(|e| plot_err(path, e))?
                        .label(*scene)
                        .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], c));
                    chart
                        .draw_series(pts.iter().map(|p| Circle::new(*p, 3, c.filled())))
                        .map_err(|e| plot_err(path, e))?;
                }
                chart
                    .configure_series_labels()
                    .border_style(BLACK)
                    .background_style(WHITE.mix(0.8))
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(|e| plot_err(path, e))?;
            }};
        }
        if log {
            draw!(builder.build_cartesian_2d((x0..x1).log_scale(), 0.0..ymax));
        } else {
            draw!(builder.build_cartesian_2d(x0..x1, 0.0..ymax));
        }
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(true)
}

fn renders(res: &EvalResults, path: &Path) -> Result<(), EvalError> {
    let root = SVGBackend::new(path, (960, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let (left, right) = root.split_horizontally(480);
    let mut tracers: Vec<&str> = res.renders.iter().map(|r| r.tracer.as_str()).collect();
    tracers.sort_unstable();
    tracers.dedup();
    let xmax = res.renders.iter().map(|r| r.wall_ms).fold(1e-3, f64::max) * 1.5;
    let xmin = res
        .renders
        .iter()
        .map(|r| r.wall_ms)
        .fold(xmax, f64::min)
        .max(1e-3)
        / 1.5;
    for (area, which) in [(left, 0usize), (right, 1usize)] {
        let val = |r: &crate::renders::RenderRow| if which == 0 { r.rmse } else { r.flip };
        let ymax = res.renders.iter().map(val).fold(1e-9, f64::max) * 1.5;
        let ymin = res.renders.iter().map(val).fold(ymax, f64::min).max(1e-9) / 1.5;
        let name = if which == 0 { "RMSE" } else { "mean FLIP" };
        let mut chart = ChartBuilder::on(&area)
            .caption(format!("{name} vs wall time"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("render wall time, ms (log)")
            .y_desc(format!("{name} (log)"))
            .x_label_formatter(&|v| short(*v))
            .y_label_formatter(&|v| short(*v))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (i, t) in tracers.iter().enumerate() {
            let c = COLORS[i % COLORS.len()];
            let pts: Vec<(f64, f64)> = res
                .renders
                .iter()
                .filter(|r| r.tracer == *t)
                .map(|r| (r.wall_ms, val(r)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(|e| plot_err(path, e))?
                .label(*t)
                .legend(move |(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], c));
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))
                .map_err(|e| plot_err(path, e))?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}
