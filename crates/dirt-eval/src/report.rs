//! Writes a run: `results.json` (everything), `builds.csv`, `traces.csv`,
//! `dynamic.csv`, `renders.csv`, `leave_out.csv`, `side.csv`, the SVG
//! plots, and a Markdown summary (`summary.md`, and the same text at
//! another path such as `docs/RESULTS.md`).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::EvalError;
use crate::dynamic::medians;
use crate::harness::EvalResults;
use crate::measure::{BuildRow, TraceRow, median, mrays};
use crate::plot::{self, Plot};
use crate::side::{SideRow, Spread};
use dirt_core::Traversal;

mod approx;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> EvalError + '_ {
    move |source| EvalError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn out_err(path: &Path, e: impl std::fmt::Display) -> EvalError {
    EvalError::Output {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<(), EvalError> {
    let mut w = csv::Writer::from_path(path).map_err(|e| out_err(path, e))?;
    for r in rows {
        w.serialize(r).map_err(|e| out_err(path, e))?;
    }
    w.flush().map_err(io(path))
}

/// Writes every output into `dir` and, if given, the Markdown report to
/// `report` (its links point into `dir`). Returns the files written.
pub fn write_all(
    res: &EvalResults,
    dir: &Path,
    report: Option<&Path>,
) -> Result<Vec<PathBuf>, EvalError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mut files = Vec::new();
    let json = dir.join("results.json");
    let text = serde_json::to_string_pretty(res).map_err(|e| out_err(&json, e))?;
    std::fs::write(&json, text + "\n").map_err(io(&json))?;
    files.push(json);
    let csvs = [
        (
            "builds.csv",
            write_csv(&dir.join("builds.csv"), &res.builds),
        ),
        (
            "traces.csv",
            write_csv(&dir.join("traces.csv"), &res.traces),
        ),
        (
            "dynamic.csv",
            write_csv(&dir.join("dynamic.csv"), &res.dynamic),
        ),
        (
            "renders.csv",
            write_csv(&dir.join("renders.csv"), &res.renders),
        ),
        (
            "leave_out.csv",
            write_csv(&dir.join("leave_out.csv"), &res.leave_out),
        ),
        ("side.csv", write_csv(&dir.join("side.csv"), &res.side)),
    ];
    for (name, written) in csvs {
        written?;
        files.push(dir.join(name));
    }
    if let Some(img) = &res.render_image {
        let p = dir.join("render_reference.png");
        img.write_png(&p, 0.0).map_err(|e| out_err(&p, e))?;
        files.push(p);
    }
    let plots = plot::write_all(res, dir)?;
    files.extend(plots.iter().map(|p| dir.join(&p.file)));
    let summary = dir.join("summary.md");
    std::fs::write(&summary, markdown(res, &plots, "")).map_err(io(&summary))?;
    files.push(summary);
    if let Some(report) = report {
        let prefix = link_prefix(report, dir);
        if let Some(parent) = report.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(io(parent))?;
        }
        std::fs::write(report, markdown(res, &plots, &prefix)).map_err(io(report))?;
        files.push(report.to_path_buf());
    }
    Ok(files)
}

/// How the report at `report` reaches files in `dir`: a relative path when
/// `dir` lies under the report's folder, else `dir` as given.
fn link_prefix(report: &Path, dir: &Path) -> String {
    let parent = report.parent().unwrap_or(Path::new(""));
    let rel = dir.strip_prefix(parent).unwrap_or(dir);
    let s = rel.to_string_lossy().replace('\\', "/");
    if s.is_empty() {
        String::new()
    } else {
        format!("{s}/")
    }
}

fn f(x: f64) -> String {
    if !x.is_finite() {
        "–".into()
    } else if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 10.0 {
        format!("{x:.1}")
    } else if x >= 0.1 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

fn mib(b: f64) -> String {
    f(b / (1024.0 * 1024.0))
}

fn opt(x: Option<f64>) -> String {
    x.map_or_else(|| "–".into(), f)
}

/// The default setting's label.
const DEFAULT: &str = "cube r128 B8 S1";

/// Build ms of a backend at a setting on one scene (`""`: the peers' setting).
fn build_ms(res: &EvalResults, scene: &str, backend: &str, setting: &str) -> Option<f64> {
    res.builds
        .iter()
        .find(|b| b.scene == scene && b.backend == backend && b.setting == setting)
        .map(|b| b.build_ms)
}

/// Total trace ms and rays (all ray types) of a backend at a setting and
/// traversal on one scene (`""`: the peers' setting and traversal).
fn trace_totals(
    res: &EvalResults,
    scene: &str,
    backend: &str,
    setting: &str,
    traversal: &str,
) -> (f64, usize) {
    totals(res.traces.iter().filter(|t| {
        t.scene == scene && t.backend == backend && t.setting == setting && t.traversal == traversal
    }))
}

/// The setting the cost model chose for a scene (the headline's), or [`DEFAULT`].
fn chosen_setting<'a>(res: &'a EvalResults, scene: &str) -> &'a str {
    res.choices
        .iter()
        .find(|c| c.scene == scene)
        .map_or(DEFAULT, |c| c.setting.as_str())
}

/// Total trace ms and rays of a backend (all ray types) for one scene.
fn totals<'a>(rows: impl Iterator<Item = &'a TraceRow>) -> (f64, usize) {
    rows.fold((0.0, 0), |(ms, n), r| (ms + r.trace_ms, n + r.rays))
}

/// Whether a DIRT setting promises brute force's hits (the camera-placed
/// single view does not: it sees only its frustum).
fn exact(setting: &str) -> bool {
    !setting.starts_with("single@camera")
}

/// The Markdown report; `prefix` is put before plot file names.
pub fn markdown(res: &EvalResults, plots: &[Plot], prefix: &str) -> String {
    let mut s = String::new();
    let m = &res.machine;
    let _ = writeln!(s, "# Results\n");
    let _ = writeln!(
        s,
        "Written by `dirt eval` (regenerate with `scripts/eval`); do not edit by hand. \
         Every figure below was measured in one run on {}.\n",
        m.date
    );
    let _ = writeln!(s, "## Machine\n");
    let _ = writeln!(s, "| | |\n|---|---|");
    let _ = writeln!(s, "| CPU | {} |", m.cpu);
    let _ = writeln!(s, "| cores | {} |", m.cores);
    let _ = writeln!(
        s,
        "| threads | rayon pool of {0}: DIRT's CPU build and trace, brute force, the peers' traces; Embree builds on {0} threads; the obvhs build is single-threaded |",
        m.rayon_threads
    );
    let _ = writeln!(
        s,
        "| GPU | {} |",
        m.gpu
            .as_deref()
            .map_or_else(|| "not used".to_string(), |g| format!("{g} (figures marked dirt-gpu are this adapter; llvmpipe is Mesa's software rasteriser on the CPU; dirt-gpu builds from host triangles, each stage waited for, dirt-gpu-frame as an application's frame: upload, views on the GPU, one submission)"))
    );
    let _ = writeln!(s, "| OS | {} |", m.os);
    let _ = writeln!(
        s,
        "| build | {} |",
        if m.release {
            "release"
        } else {
            "debug (timings not meaningful)"
        }
    );
    let load = |l: Option<f64>| l.map_or_else(|| "?".to_string(), |l| format!("{l:.1}"));
    let _ = writeln!(
        s,
        "| run | {:.0} s wall; 1-minute load average {} at the start, {} at the end (above {} means other work shared the cores: timings are noisier, ratios within the run still compare like with like only roughly) |\n",
        res.wall_s,
        load(m.load_start),
        load(m.load_end),
        m.cores
    );

    let _ = writeln!(s, "## What was measured\n");
    let _ = writeln!(s, "- Grid: {}; both traversals (linear, hiz).", res.grid);
    let _ = writeln!(
        s,
        "- Rays: {} per ray type of 001 Table 1 (primary from the scene camera; shadow to points on emitters; specular; glossy, Phong exponent {}; diffuse, cosine) at the primary hits, seed fixed.",
        res.rays_per_type,
        crate::rays::GLOSSY_EXPONENT
    );
    let _ = writeln!(
        s,
        "- Times are medians of at least {} runs, and of more (up to {}) until the runs of a measurement have taken {} ms (GPU: 1–2); builds and traces of every backend alike, but for the dynamic scenes, whose every frame is built and traced once. Trace times cover all rays of a type; Mrays/s = rays / time.",
        res.repeat,
        crate::measure::STEADY_RUNS,
        crate::measure::STEADY_MS
    );
    let _ = writeln!(
        s,
        "- Error: rays whose closest hit differs from brute force's (the same watertight test, every triangle), counted on the first rays of each type (`compared`). For DIRT any bit of `prim, t, u, v`; for the peers, which use their own triangle tests, another `prim` or a `t` more than 1e-4 (relative) away. Exact DIRT settings must show 0: anything else is a defect.",
    );
    let _ = writeln!(
        s,
        "- Peers: obvhs 0.4 (CWBVH, `fast_build` preset, its Möller–Trumbore test) and Embree 3 (default build quality, `rtcIntersect1` per ray) on the same triangles and rays; and `{}`, the compact uniform grid of Lagae and Dutré (seed 002: ρ = 4 cells per triangle, two-pass build, 3D DDA) with DIRT's triangle test, an exact baseline held to every bit like DIRT.\n",
        crate::peers::GRID
    );

    goals_table(&mut s, res);

    // Headline ratios.
    let _ = writeln!(s, "## Headline: DIRT against the peers\n");
    let _ = writeln!(
        s,
        "DIRT on the CPU at its default: the setting the cost model's one-off choice (`dirt_cpu::cost::auto`, as the command line chooses: candidate builds within a quarter of the best predicted frame) makes for a frame of all the scene's rays of the run, measured on a stride of them; the library's `DirtCpu::auto`, which keeps its choice for later frames, searches on (`cost::KEPT_BUDGET`, four frames) from rays it generates or is given, and may choose otherwise. `choose ms` is the time the one-off choice took (candidate builds and sample traces, paid once per scene, not in the build column). Ratios are dirt / peer: \
         above 1 means DIRT is slower (build, trace time) — trace ratios are of time over all ray types. The fixed setting ({DEFAULT}) follows in the next table.\n"
    );
    let peers: Vec<String> = {
        let mut p: Vec<String> = res
            .builds
            .iter()
            .filter(|b| {
                b.backend == "obvhs" || b.backend == "embree" || b.backend == crate::peers::GRID
            })
            .map(|b| b.backend.clone())
            .collect();
        p.sort();
        p.dedup();
        p
    };
    let _ = write!(
        s,
        "| scene | triangles | DIRT setting | choose ms | DIRT build ms | DIRT trace Mrays/s (linear / hiz) |"
    );
    for p in &peers {
        let _ = write!(
            s,
            " {p} build ms | {p} Mrays/s | build dirt/{p} | trace dirt/{p} (linear / hiz) |"
        );
    }
    let _ = writeln!(s);
    let _ = write!(s, "|---|---:|---|---:|---:|---:|");
    for _ in &peers {
        let _ = write!(s, "---:|---:|---:|---:|");
    }
    let _ = writeln!(s);
    for sc in &res.scenes {
        let build = |backend: &str, setting: &str| build_ms(res, &sc.name, backend, setting);
        let trace = |backend: &str, setting: &str, trav: &str| {
            trace_totals(res, &sc.name, backend, setting, trav)
        };
        let choice = res.choices.iter().find(|c| c.scene == sc.name);
        let setting = chosen_setting(res, &sc.name);
        let Some(db) = build("dirt-cpu", setting) else {
            continue;
        };
        let (lin_ms, lin_n) = trace("dirt-cpu", setting, "linear");
        let (hiz_ms, hiz_n) = trace("dirt-cpu", setting, "hiz");
        let _ = write!(
            s,
            "| {} | {} | {setting} | {} | {} | {} / {} |",
            sc.name,
            sc.triangles,
            opt(choice.map(|c| c.choose_ms)),
            f(db),
            f(mrays(lin_n, lin_ms)),
            f(mrays(hiz_n, hiz_ms))
        );
        for p in &peers {
            let pb = build(p, "");
            let (pms, pn) = trace(p, "", "");
            let _ = write!(
                s,
                " {} | {} | {} | {} |",
                opt(pb),
                f(mrays(pn, pms)),
                opt(pb.map(|pb| db / pb)),
                ratio(lin_ms, pms, hiz_ms)
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s);
    side_table(&mut s, res);
    fixed_default_table(&mut s, res, &peers);
    let mut runs: Vec<(&str, usize)> = res
        .dynamic
        .iter()
        .map(|r| (r.scene.as_str(), r.rays))
        .collect();
    runs.dedup();
    for (scene, rays) in runs {
        let rows: Vec<crate::dynamic::DynamicRow> = res
            .dynamic
            .iter()
            .filter(|r| r.rays == rays && r.scene == scene)
            .cloned()
            .collect();
        let tris = rows.first().map_or(0, |r| r.triangles);
        let frames = rows.iter().map(|r| r.frame).max().map_or(0, |f| f + 1);
        let what = match scene {
            crate::dynamic::WAVE => {
                format!("a deforming grid of {tris} triangles, every vertex moves every frame")
            }
            "twister" => format!(
                "`twister`, a generated skinned glTF tube of {tris} triangles posed by `dirt-scene` (two joints, its clip spread over the frames)"
            ),
            other => format!(
                "`{other}`, an animated glTF asset of {tris} triangles posed by `dirt-scene` (its clip spread over the frames)"
            ),
        };
        let _ = writeln!(
            s,
            "Fully dynamic scene ({what}; {frames} frames of rebuild + trace of {rays} camera rays; medians per frame; `dirt-cpu` is the library's default, `DirtCpu::auto`, whose choice is made in frame 0's build on generated rays and, once it has seen that every ray of frame 0 starts at the camera, made again in frame 1's build among the views placed there; `{}` is the same told where the rays start and given frame 0's rays to choose on from frame 0, `DirtCpu::with_origin` and `with_sample`):\n",
            crate::dynamic::AT_CAMERA
        );
        let _ = writeln!(
            s,
            "| backend | build ms | trace ms | frame ms | frame dirt/backend | differ / compared (all frames) |\n|---|---:|---:|---:|---:|---:|"
        );
        let dirt = medians(&rows, "dirt-cpu");
        let mut backends: Vec<&str> = rows.iter().map(|r| r.backend.as_str()).collect();
        backends.sort_unstable();
        backends.dedup();
        for b in backends {
            if let Some((bm, tm, fm)) = medians(&rows, b) {
                let (d, c) = rows
                    .iter()
                    .filter(|r| r.backend == b)
                    .fold((0, 0), |(d, c), r| (d + r.differ, c + r.compared));
                let _ = writeln!(
                    s,
                    "| {b} | {} | {} | {} | {} | {d} / {c} |",
                    f(bm),
                    f(tm),
                    f(fm),
                    dirt.map_or_else(|| "–".into(), |(_, _, dfm)| f(dfm / fm))
                );
            }
        }
        let _ = writeln!(s);
    }

    process_table(&mut s, res);

    // Errors.
    let _ = writeln!(s, "## Error against brute force\n");
    let dirt_bad: Vec<&TraceRow> = res
        .traces
        .iter()
        .filter(|t| t.backend.starts_with("dirt") && exact(&t.setting) && t.differ > 0)
        .collect();
    let dyn_bad: usize = res
        .dynamic
        .iter()
        .filter(|r| r.backend.starts_with("dirt"))
        .map(|r| r.differ)
        .sum();
    let dirt_compared: usize = res
        .traces
        .iter()
        .filter(|t| t.backend.starts_with("dirt") && exact(&t.setting))
        .map(|t| t.compared)
        .sum();
    // The side-by-side rounds trace the headline's settings, exact all.
    let side_bad: usize = res.side.iter().map(|r| r.dirt_differ).sum();
    let side_compared: usize = res.side.iter().map(|r| r.dirt_compared).sum();
    if dirt_bad.is_empty() && dyn_bad == 0 && side_bad == 0 {
        let _ = writeln!(
            s,
            "**DIRT: 0 rays differ** from brute force in any bit, over {} compared ray traces of every exact setting, traversal, ray type and backend (and every frame of the dynamic scene, and every side-by-side round).\n",
            dirt_compared + side_compared
        );
    } else {
        let _ = writeln!(
            s,
            "**DEFECT: DIRT differs from brute force** on {} (setting, traversal, ray type) rows, {dyn_bad} dynamic-scene rays and {side_bad} ray traces of the side-by-side rounds. The rows:\n",
            dirt_bad.len()
        );
        let _ = writeln!(
            s,
            "| scene | backend | setting | traversal | ray type | differ / compared |\n|---|---|---|---|---|---:|"
        );
        for t in &dirt_bad {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} / {} |",
                t.scene, t.backend, t.setting, t.traversal, t.ray_type, t.differ, t.compared
            );
        }
        let _ = writeln!(s);
    }
    let inexact: Vec<&TraceRow> = res
        .traces
        .iter()
        .filter(|t| t.backend == "dirt-cpu" && !exact(&t.setting) && t.traversal == "linear")
        .collect();
    if !inexact.is_empty() {
        let _ = writeln!(
            s,
            "The single view placed at the camera (the papers' setting for camera-centred effects) is not exact by design: it finds only hits inside its frustum. Its disagreement (linear traversal):\n"
        );
        let _ = writeln!(
            s,
            "| scene | setting | ray type | differ / compared | other prim | missed | false hits |\n|---|---|---|---:|---:|---:|---:|"
        );
        for t in inexact {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} / {} | {} | {} | {} |",
                t.scene,
                t.setting,
                t.ray_type,
                t.differ,
                t.compared,
                t.other_prim,
                t.missed,
                t.false_hits
            );
        }
        let _ = writeln!(s);
    }
    let (grid_differ, grid_compared) = res
        .traces
        .iter()
        .filter(|t| t.backend.starts_with("grid"))
        .map(|t| (t.differ, t.compared))
        .chain(
            res.dynamic
                .iter()
                .filter(|r| r.backend.starts_with("grid"))
                .map(|r| (r.differ, r.compared)),
        )
        .fold((0, 0), |(d, c), (x, y)| (d + x, c + y));
    if grid_compared > 0 {
        let _ = writeln!(
            s,
            "The compact grid (every density measured): {grid_differ} of {grid_compared} compared rays differ from brute force in any bit (every scene, ray type and frame; it shares DIRT's triangle test, so anything but 0 is a defect).\n"
        );
        grid_density_table(&mut s, res);
    }
    let _ = writeln!(
        s,
        "Peers (their own, non-watertight triangle tests; `differ`: another primitive or `t` more than 1e-4 relative away; `prim`: another primitive or a hit/miss change):\n"
    );
    let _ = writeln!(
        s,
        "| scene | peer | ray type | differ | prim | compared |\n|---|---|---|---:|---:|---:|"
    );
    for t in res
        .traces
        .iter()
        .filter(|t| t.backend == "obvhs" || t.backend == "embree")
    {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            t.scene, t.backend, t.ray_type, t.differ, t.differ_prim, t.compared
        );
    }
    let _ = writeln!(s);

    approx::section(&mut s, res);

    if !res.leave_out.is_empty() {
        let _ = writeln!(s, "## Leaving out what a scene does not need\n");
        let _ = writeln!(
            s,
            "Against the everything-on configuration (every view the bounds reach, `Ads::build_all_views`), per scene: `leave out` builds only the views some triangle reaches (`Ads::build`), with the cube at the bounds centre and at the scene camera; `cost model` is the candidate `dirt_cpu::cost::choose` ranks cheapest for a frame of all the run's rays with every candidate built (the default's pruned choice, `cost::auto`, is the headline's setting). Trace: every ray of the run, Hi-Z, median of {} runs. `differ`: compared rays whose hit differs from brute force in any bit (must be 0).\n",
            res.repeat
        );
        let _ = writeln!(
            s,
            "| scene | centre | config | views | res | B | views built | build ms | trace ms | MiB | build saved | trace saved | memory saved | differ / compared |\n|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        );
        for r in &res.leave_out {
            let base = res.leave_out.iter().find(|b| {
                b.scene == r.scene
                    && b.config == "all views"
                    && (b.centre == r.centre
                        || r.config == "cost model" && b.centre == "bounds centre")
            });
            let pct = |x: f64, base: f64| {
                let v = (100.0 * (1.0 - x / base)).round();
                format!("{} %", if v == 0.0 { 0.0 } else { v })
            };
            let (bs, ts, ms_) = base.map_or((String::new(), String::new(), String::new()), |b| {
                (
                    pct(r.build_ms, b.build_ms),
                    pct(r.trace_ms, b.trace_ms),
                    pct(r.bytes as f64, b.bytes as f64),
                )
            });
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {}{} / {} |",
                r.scene,
                r.centre,
                r.config,
                r.views,
                r.resolution,
                r.buckets,
                r.views_built,
                f(r.build_ms),
                f(r.trace_ms),
                mib(r.bytes as f64),
                bs,
                ts,
                ms_,
                if r.differ > 0 { "**" } else { "" },
                r.differ,
                r.compared
            );
        }
        let _ = writeln!(s);
    }

    if let Some(rr) = &res.render_reference {
        let _ = writeln!(s, "## Renders: image error against time\n");
        let first = res.renders.first();
        let _ = writeln!(
            s,
            "Path tracing with `dirt-render` on {} at {}x{} ({} bounces). Reference: {} samples per pixel with another seed (rendered with the renderer's obvhs reference tracer in {:.1} s), so its own noise sets the floor of the curves. Each row is a separate render of the first `spp` samples; wall time includes building the tracer's structure. FLIP is the mean of `nv-flip` over the tone-mapped sRGB images. The approximate tracers (mmrt, 1-layer) trace every ray after the primary hits, which the renderer confirms with the exact test; their error shows in bounces and shadows.\n",
            rr.scene,
            first.map_or(0, |r| r.width),
            first.map_or(0, |r| r.height),
            res.render_settings_bounces,
            rr.spp,
            rr.wall_ms / 1e3
        );
        let _ = writeln!(s, "![converged reference]({prefix}render_reference.png)\n");
        let _ = writeln!(
            s,
            "| tracer | spp | wall ms | trace ms | rays | RMSE | FLIP | same bits as the reference tracer |\n|---|---:|---:|---:|---:|---:|---:|---|"
        );
        for r in &res.renders {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {:.5} | {:.5} | {} |",
                r.tracer,
                r.spp,
                f(r.wall_ms),
                f(r.trace_ms),
                r.rays,
                r.rmse,
                r.flip,
                match (r.same_bits_as_reference_tracer, r.exact) {
                    (true, _) => "yes",
                    (false, true) => "**no**",
                    (false, false) => "no (approximate)",
                }
            );
        }
        let _ = writeln!(s);
    }

    // Per scene.
    for sc in &res.scenes {
        let _ = writeln!(
            s,
            "## {} ({} triangles, `{}`)\n",
            sc.name, sc.triangles, sc.spec
        );
        if let Some(p) = plots
            .iter()
            .find(|p| p.scene.as_deref() == Some(sc.name.as_str()))
        {
            let _ = writeln!(s, "![{}]({prefix}{})\n", p.title, p.file);
        }
        let _ = writeln!(
            s,
            "Build and memory per setting (MiB; model = 001 Table 3):\n"
        );
        let _ = writeln!(
            s,
            "| backend | setting | fill_depth ms | mip_depth ms | fill_primitives ms | build ms | nodes | depth+Hi-Z MiB (model) | id buffer MiB (model) | total MiB |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
        );
        for b in res.builds.iter().filter(|b| b.scene == sc.name) {
            let _ = writeln!(s, "{}", build_line(b));
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "Trace at the default setting ({DEFAULT}), the peers and brute force (tiles, buckets, tests: per ray, over the compared rays):\n"
        );
        let _ = writeln!(
            s,
            "| ray type | backend | traversal | rays | Mrays/s | tiles | buckets | tests | differ / compared |\n|---|---|---|---:|---:|---:|---:|---:|---:|"
        );
        let mut rows: Vec<&TraceRow> = res
            .traces
            .iter()
            .filter(|t| t.scene == sc.name && (t.setting == DEFAULT || t.setting.is_empty()))
            .collect();
        rows.sort_by_key(|t| {
            (
                ray_order(&t.ray_type),
                t.backend.clone(),
                t.traversal.clone(),
            )
        });
        for t in rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} |",
                t.ray_type,
                t.backend,
                t.traversal,
                t.rays,
                f(t.mrays_per_s),
                opt(t.tiles_per_ray),
                opt(t.buckets_per_ray),
                opt(t.tests_per_ray),
                t.differ,
                t.compared
            );
        }
        let _ = writeln!(s);
        // Every setting, all ray types together.
        let _ = writeln!(
            s,
            "Every setting, all ray types together (DIRT on the CPU):\n"
        );
        let _ = writeln!(
            s,
            "| setting | traversal | Mrays/s | tiles | buckets | tests | differ / compared |\n|---|---|---:|---:|---:|---:|---:|"
        );
        // In grid order, then traversal.
        let settings: Vec<&str> = res
            .builds
            .iter()
            .filter(|b| b.scene == sc.name && b.backend == "dirt-cpu")
            .map(|b| b.setting.as_str())
            .collect();
        let mut groups: BTreeMap<(usize, String), (String, Vec<&TraceRow>)> = BTreeMap::new();
        for t in res
            .traces
            .iter()
            .filter(|t| t.scene == sc.name && t.backend == "dirt-cpu")
        {
            let i = settings
                .iter()
                .position(|s| *s == t.setting)
                .unwrap_or(usize::MAX);
            groups
                .entry((i, t.traversal.clone()))
                .or_insert_with(|| (t.setting.clone(), Vec::new()))
                .1
                .push(t);
        }
        for ((_, trav), (setting, rows)) in groups {
            let (ms, n) = totals(rows.iter().copied());
            let c: usize = rows.iter().map(|r| r.compared).sum();
            let avg = |g: fn(&TraceRow) -> Option<f64>| {
                let w: f64 = rows
                    .iter()
                    .map(|r| g(r).unwrap_or(0.0) * r.compared as f64)
                    .sum();
                w / c.max(1) as f64
            };
            let d: usize = rows.iter().map(|r| r.differ).sum();
            let _ = writeln!(
                s,
                "| {setting} | {trav} | {} | {} | {} | {} | {d} / {c} |",
                f(mrays(n, ms)),
                f(avg(|r| r.tiles_per_ray)),
                f(avg(|r| r.buckets_per_ray)),
                f(avg(|r| r.tests_per_ray)),
            );
        }
        let _ = writeln!(s);
    }

    let others: Vec<&Plot> = plots.iter().filter(|p| p.scene.is_none()).collect();
    if !others.is_empty() {
        let _ = writeln!(s, "## Sweeps and the dynamic scene\n");
        for p in others {
            let _ = writeln!(s, "![{}]({prefix}{})\n", p.title, p.file);
        }
    }
    if !res.notes.is_empty() {
        let _ = writeln!(s, "## Notes\n");
        for n in &res.notes {
            let _ = writeln!(s, "- {n}");
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "Raw data: [results.json]({prefix}results.json), [builds.csv]({prefix}builds.csv), [traces.csv]({prefix}traces.csv), [dynamic.csv]({prefix}dynamic.csv), [renders.csv]({prefix}renders.csv), [leave_out.csv]({prefix}leave_out.csv), [side.csv]({prefix}side.csv)."
    );
    s
}

/// DIRT's speed goals ([`goals_table`]), as ratios DIRT / peer: a headline
/// trace and build against Embree's.
const TRACE_GOAL: f64 = 3.0;
const BUILD_GOAL: f64 = 1.0;
/// Of the deforming grid's frame, DIRT / the best peer: with a few thousand
/// rays a frame (the build's share is large) and with 100,000.
const FRAME_GOAL_FEW: f64 = 0.67;
const FRAME_GOAL_MANY: f64 = 1.0;

/// Rays a frame up to which [`FRAME_GOAL_FEW`] applies (the run's 5,000).
const FEW_RAYS: usize = 10_000;

/// Of the render, DIRT / the renderer's BVH; of the whole `dirt trace`
/// process on the large scene, DIRT / Embree.
const RENDER_GOAL: f64 = 2.0;
const PROCESS_GOAL: f64 = 1.5;

/// The scene whose build has no goal, only a figure: 512 stacked triangles
/// that each cover the whole view, which Embree builds in a tenth of a
/// millisecond.
const BUILD_REPORTED_ONLY: &str = "layers";

/// The median of a list of runs, if any.
fn median_of(runs: &[f64]) -> Option<f64> {
    (!runs.is_empty()).then(|| median(runs.to_vec()))
}

/// "## Speed goals": every goal, the ratio this run measured for it, and
/// whether it is met. Ratios are DIRT / peer (above 1: DIRT slower). Rows
/// whose figures the run lacks (a peer unavailable, a part skipped) are
/// left out.
fn goals_table(s: &mut String, res: &EvalResults) {
    // (figure, goal, measured, met, the side-by-side rounds' reading of the
    // same ratio)
    let mut rows: Vec<(String, String, String, &str, String)> = Vec::new();
    let met = |x: f64, goal: f64| if x <= goal { "yes" } else { "no" };
    for sc in &res.scenes {
        let rounds = || side_rounds(res, &sc.name, "embree");
        let setting = chosen_setting(res, &sc.name);
        let (lin, _) = trace_totals(res, &sc.name, "dirt-cpu", setting, "linear");
        let (hiz, _) = trace_totals(res, &sc.name, "dirt-cpu", setting, "hiz");
        let (emb, _) = trace_totals(res, &sc.name, "embree", "", "");
        if emb > 0.0 && lin > 0.0 && hiz > 0.0 {
            let (l, h) = (lin / emb, hiz / emb);
            rows.push((
                format!("trace DIRT/Embree, {} ({setting}; linear / hiz)", sc.name),
                format!("≤ {TRACE_GOAL}"),
                format!("{} / {}", f(l), f(h)),
                met(l.min(h), TRACE_GOAL),
                spread(Spread::of(rounds().filter_map(SideRow::faster_ratio))),
            ));
        }
        let db = build_ms(res, &sc.name, "dirt-cpu", setting);
        if let (Some(d), Some(e)) = (db, build_ms(res, &sc.name, "embree", "")) {
            let reported = sc.name == BUILD_REPORTED_ONLY;
            rows.push((
                format!("build DIRT/Embree, {}", sc.name),
                if reported {
                    "reported".into()
                } else {
                    format!("≤ {BUILD_GOAL}")
                },
                f(d / e),
                if reported {
                    "–"
                } else {
                    met(d / e, BUILD_GOAL)
                },
                spread(Spread::of(rounds().map(SideRow::build_ratio))),
            ));
        }
    }
    let mut counts: Vec<usize> = res
        .dynamic
        .iter()
        .filter(|r| r.scene == crate::dynamic::WAVE)
        .map(|r| r.rays)
        .collect();
    counts.sort_unstable();
    counts.dedup();
    for rays in counts {
        let goal = if rays <= FEW_RAYS {
            FRAME_GOAL_FEW
        } else {
            FRAME_GOAL_MANY
        };
        let of: Vec<crate::dynamic::DynamicRow> = res
            .dynamic
            .iter()
            .filter(|r| r.scene == crate::dynamic::WAVE && r.rays == rays)
            .cloned()
            .collect();
        let tris = of.first().map_or(0, |r| r.triangles);
        let dirt = medians(&of, "dirt-cpu").map(|m| m.2);
        let mut peers: Vec<&str> = of
            .iter()
            .map(|r| r.backend.as_str())
            .filter(|b| !b.starts_with("dirt"))
            .collect();
        peers.sort_unstable();
        peers.dedup();
        let best = peers
            .iter()
            .filter_map(|b| medians(&of, b).map(|m| (m.2, *b)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let (Some(d), Some((p, peer))) = (dirt, best) {
            rows.push((
                format!(
                    "deforming grid frame ({tris} triangles, rebuild + {rays} rays), DIRT/the best peer ({peer})"
                ),
                format!("≤ {goal}"),
                f(d / p),
                met(d / p, goal),
                "–".into(),
            ));
        }
    }
    let at_most_spp = |tracer: &str| {
        res.renders
            .iter()
            .filter(|r| r.tracer == tracer)
            .max_by_key(|r| r.spp)
    };
    if let (Some(d), Some(r)) = (
        at_most_spp(crate::renders::DIRT_TRACER),
        at_most_spp(crate::renders::REFERENCE_TRACER),
    ) && d.spp == r.spp
        && r.wall_ms > 0.0
    {
        let x = d.wall_ms / r.wall_ms;
        rows.push((
            format!(
                "render {} {}x{}, {} spp, DIRT/the renderer's BVH",
                d.scene, d.width, d.height, d.spp
            ),
            format!("≤ {RENDER_GOAL}"),
            f(x),
            met(x, RENDER_GOAL),
            "–".into(),
        ));
    }
    let process = |backend: &str| {
        res.processes
            .iter()
            .find(|r| r.backend == backend)
            .and_then(|r| median_of(&r.runs_s).map(|m| (m, r)))
    };
    if let (Some((d, row)), Some((e, _))) = (process("cpu"), process("embree"))
        && e > 0.0
    {
        rows.push((
            format!(
                "whole `dirt trace` process, {} ({} triangles, {} rays), DIRT/Embree",
                row.scene, row.triangles, row.rays
            ),
            format!("≤ {PROCESS_GOAL}"),
            f(d / e),
            met(d / e, PROCESS_GOAL),
            "–".into(),
        ));
    }
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(s, "## Speed goals\n");
    let _ = writeln!(
        s,
        "What DIRT on the CPU aims for beside its peers, and what this run measured (from the tables below; ratios are DIRT / peer, above 1 means DIRT is slower). A trace goal counts as met when the faster traversal meets it: the command line times both on a sample and keeps the faster.\n"
    );
    if res.side.is_empty() {
        let _ = writeln!(s, "| figure | goal | measured | met |\n|---|---|---:|---|");
        for (what, goal, measured, met, _) in rows {
            let _ = writeln!(s, "| {what} | {goal} | {measured} | {met} |");
        }
    } else {
        let _ = writeln!(
            s,
            "`side by side` reads the same ratio from the alternated rounds of the section of that name (trace: DIRT's faster traversal in each round): the median of the rounds, then their least and greatest. Where it and `measured` fall on either side of a goal, the machine's drift during the run decided `met`.\n"
        );
        let _ = writeln!(
            s,
            "| figure | goal | measured | met | side by side |\n|---|---|---:|---|---:|"
        );
        for (what, goal, measured, met, sd) in rows {
            let _ = writeln!(s, "| {what} | {goal} | {measured} | {met} | {sd} |");
        }
    }
    let _ = writeln!(s);
}

/// A [`Spread`] as `median (min–max)`; `–` for none.
fn spread(sp: Option<Spread>) -> String {
    sp.map_or_else(
        || "–".to_string(),
        |sp| format!("{} ({}–{})", f(sp.median), f(sp.min), f(sp.max)),
    )
}

/// The side-by-side rounds of `scene` against `peer`.
fn side_rounds<'a>(
    res: &'a EvalResults,
    scene: &'a str,
    peer: &'a str,
) -> impl Iterator<Item = &'a SideRow> {
    res.side
        .iter()
        .filter(move |r| r.scene == scene && r.peer == peer)
}

/// "## Side by side": per scene and peer, the ratios of the alternated
/// rounds ([`crate::side`]) as median (least–greatest), and the hits
/// compared in them.
fn side_table(s: &mut String, res: &EvalResults) {
    if res.side.is_empty() {
        return;
    }
    let rounds = res.side.iter().map(|r| r.round + 1).max().unwrap_or(0);
    let _ = writeln!(s, "## Side by side\n");
    let _ = writeln!(
        s,
        "DIRT at the headline's setting and each peer in {rounds} alternated rounds (`dirt_eval::side`): each round builds both, then traces every ray type through one and then through the other (DIRT with each traversal), the order swapped every round; each build and trace is measured as in the headline. The table above measures each backend in turn, up to minutes apart; here a ratio's two times were taken within a second of each other, and the range over the rounds shows how far the machine's speed moved it. Ratios are DIRT / peer: the median of the rounds (least–greatest). `differ` counts, over all rounds, the compared rays whose hit differs from brute force (DIRT: any bit, every traversal; the peer as in the headline).\n"
    );
    let _ = writeln!(
        s,
        "| scene | peer | DIRT setting | rounds | build dirt/peer | trace dirt/peer, linear | trace dirt/peer, hiz | DIRT differ / compared | peer differ / compared |\n|---|---|---|---:|---:|---:|---:|---:|---:|"
    );
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for r in &res.side {
        if !keys.contains(&(r.scene.as_str(), r.peer.as_str())) {
            keys.push((&r.scene, &r.peer));
        }
    }
    for (scene, peer) in keys {
        let rows: Vec<&SideRow> = side_rounds(res, scene, peer).collect();
        let Some(first) = rows.first() else {
            continue;
        };
        let sum = |f: fn(&SideRow) -> usize| rows.iter().map(|r| f(r)).sum::<usize>();
        let _ = writeln!(
            s,
            "| {scene} | {peer} | {} | {} | {} | {} | {} | {} / {} | {} / {} |",
            first.setting,
            rows.len(),
            spread(Spread::of(rows.iter().map(|r| r.build_ratio()))),
            spread(Spread::of(
                rows.iter().filter_map(|r| r.trace_ratio(Traversal::Linear))
            )),
            spread(Spread::of(
                rows.iter().filter_map(|r| r.trace_ratio(Traversal::HiZ))
            )),
            sum(|r| r.dirt_differ),
            sum(|r| r.dirt_compared),
            sum(|r| r.peer_differ),
            sum(|r| r.peer_compared),
        );
    }
    let _ = writeln!(s);
}

/// Whole `dirt trace` processes on the large scene, per backend: the
/// median wall time of its runs and the ratio DIRT / backend.
fn process_table(s: &mut String, res: &EvalResults) {
    let Some(first) = res.processes.first() else {
        return;
    };
    let _ = writeln!(
        s,
        "Whole processes on a large scene (`{}`, {} triangles; {} random rays from `dirt rays --kind random`): `dirt trace SCENE --rays RAYS.npy --out HITS.npy --backend B`, timed from start to exit (loading the scene, building, tracing, writing the hits), runs alternated; `cpu` is DIRT at the cost model's choice. `differ` counts hits with another primitive or a `t` more than 1e-4 (relative) from DIRT's.\n",
        first.scene, first.triangles, first.rays
    );
    let _ = writeln!(
        s,
        "| backend | runs s | median s | dirt/backend | differ / rays |\n|---|---|---:|---:|---:|"
    );
    let dirt = res
        .processes
        .iter()
        .find(|r| r.backend == "cpu")
        .and_then(|r| median_of(&r.runs_s));
    for r in &res.processes {
        let runs: Vec<String> = r.runs_s.iter().map(|&x| f(x)).collect();
        let m = median_of(&r.runs_s);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} / {} |",
            r.backend,
            runs.join(", "),
            opt(m),
            match (dirt, m) {
                (Some(d), Some(m)) if m > 0.0 => f(d / m),
                _ => "–".into(),
            },
            r.differ,
            r.rays
        );
    }
    let _ = writeln!(s);
}

/// The fixed setting ([`DEFAULT`]) against the peers and against the cost
/// model's choice of the headline, so the fixed grid stays reported.
fn fixed_default_table(s: &mut String, res: &EvalResults, peers: &[String]) {
    let _ = writeln!(
        s,
        "The fixed setting {DEFAULT} (the command line's `--fixed`, `DirtCpu::new(AdsParams::default(), …)`): against the peers, and against the cost model's choice above (fixed / chosen: above 1 means the choice is faster).\n"
    );
    let _ = write!(
        s,
        "| scene | build ms | trace Mrays/s (linear / hiz) | build fixed/chosen | trace fixed/chosen (linear / hiz) |"
    );
    for p in peers {
        let _ = write!(s, " build dirt/{p} | trace dirt/{p} (linear / hiz) |");
    }
    let _ = writeln!(s);
    let _ = write!(s, "|---|---:|---:|---:|---:|");
    for _ in peers {
        let _ = write!(s, "---:|---:|");
    }
    let _ = writeln!(s);
    for sc in &res.scenes {
        let build = |backend: &str, setting: &str| build_ms(res, &sc.name, backend, setting);
        let trace = |backend: &str, setting: &str, trav: &str| {
            trace_totals(res, &sc.name, backend, setting, trav)
        };
        let Some(fb) = build("dirt-cpu", DEFAULT) else {
            continue;
        };
        let chosen = chosen_setting(res, &sc.name);
        let (lin_ms, lin_n) = trace("dirt-cpu", DEFAULT, "linear");
        let (hiz_ms, hiz_n) = trace("dirt-cpu", DEFAULT, "hiz");
        let cb = build("dirt-cpu", chosen);
        let (clin, _) = trace("dirt-cpu", chosen, "linear");
        let (chiz, _) = trace("dirt-cpu", chosen, "hiz");
        let _ = write!(
            s,
            "| {} | {} | {} / {} | {} | {} / {} |",
            sc.name,
            f(fb),
            f(mrays(lin_n, lin_ms)),
            f(mrays(hiz_n, hiz_ms)),
            opt(cb.map(|cb| fb / cb)),
            f(lin_ms / clin),
            f(hiz_ms / chiz)
        );
        for p in peers {
            let pb = build(p, "");
            let (pms, _) = trace(p, "", "");
            let _ = write!(
                s,
                " {} | {} |",
                opt(pb.map(|pb| fb / pb)),
                ratio(lin_ms, pms, hiz_ms)
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s);
}

/// `a / p` and `b / p`, as `x / y`.
/// The grid's knob: build and trace against its density (cells per triangle).
fn grid_density_table(s: &mut String, res: &EvalResults) {
    let rows: Vec<&BuildRow> = res
        .builds
        .iter()
        .filter(|b| b.backend.starts_with("grid"))
        .collect();
    if rows
        .iter()
        .map(|b| &b.backend)
        .collect::<std::collections::BTreeSet<_>>()
        .len()
        < 2
    {
        return;
    }
    let _ = writeln!(
        s,
        "The grid's density ρ (cells per triangle), swept: build, trace of all ray types, memory (offsets and ids).\n"
    );
    let _ = writeln!(
        s,
        "| scene | grid | build ms | trace ms | MiB |\n|---|---|---:|---:|---:|"
    );
    let mut rows = rows;
    let density = |b: &BuildRow| {
        b.backend
            .trim_start_matches("grid ρ")
            .parse::<f64>()
            .unwrap_or(f64::INFINITY)
    };
    let scene_order = |name: &str| res.scenes.iter().position(|s| s.name == name);
    rows.sort_by(|a, b| {
        scene_order(&a.scene)
            .cmp(&scene_order(&b.scene))
            .then(density(a).total_cmp(&density(b)))
    });
    for b in rows {
        let (ms, _) = trace_totals(res, &b.scene, &b.backend, "", "");
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            b.scene,
            b.backend,
            f(b.build_ms),
            f(ms),
            b.total_bytes.map_or_else(|| "–".into(), |x| mib(x as f64))
        );
    }
    let _ = writeln!(s);
}

fn ratio(a: f64, p: f64, b: f64) -> String {
    if p > 0.0 {
        format!("{} / {}", f(a / p), f(b / p))
    } else {
        "–".into()
    }
}

fn ray_order(t: &str) -> usize {
    crate::rays::RayType::ALL
        .iter()
        .position(|r| r.name() == t)
        .unwrap_or(usize::MAX)
}

fn build_line(b: &BuildRow) -> String {
    let model = |bytes: Option<u64>, model: Option<f64>| match (bytes, model) {
        (Some(b), Some(m)) => format!("{} ({})", mib(b as f64), mib(m)),
        (Some(b), None) => mib(b as f64),
        _ => "–".into(),
    };
    format!(
        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        b.backend,
        b.setting,
        opt(b.fill_depth_ms),
        opt(b.mip_depth_ms),
        opt(b.fill_primitives_ms),
        f(b.build_ms),
        b.nodes.map_or_else(|| "–".into(), |n| n.to_string()),
        model(b.depth_hiz_bytes, b.depth_hiz_model_bytes),
        model(b.id_buffer_bytes, b.id_buffer_model_bytes),
        b.total_bytes.map_or_else(|| "–".into(), |t| mib(t as f64)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_are_relative_to_the_report() {
        assert_eq!(
            link_prefix(Path::new("docs/RESULTS.md"), Path::new("docs/results")),
            "results/"
        );
        assert_eq!(
            link_prefix(Path::new("RESULTS.md"), Path::new("out")),
            "out/"
        );
        assert_eq!(
            link_prefix(Path::new("a/R.md"), Path::new("/tmp/x")),
            "/tmp/x/"
        );
    }
}
