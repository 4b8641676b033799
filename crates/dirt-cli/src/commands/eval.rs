//! `dirt eval`: the evaluation harness (`dirt_eval`) from the command line.
//!
//! Measures DIRT (CPU, and GPU on small scenes), obvhs and Embree (with the
//! `embree` feature), the compact grid and the approximate methods (MMRT's
//! A-buffer, one depth layer) over scenes and a parameter grid against brute force,
//! then writes CSV, JSON, SVG plots and a Markdown summary to `--out`, and
//! the same summary to `--report` (e.g. `docs/RESULTS.md`).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use dirt_eval::EvalConfig;
use dirt_eval::dynamic::DynamicConfig;

#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A tiny grid on two small scenes, no GPU: finishes in well under a minute.
    #[arg(long)]
    quick: bool,
    /// Folder for results.json, builds.csv, traces.csv, dynamic.csv, the plots and summary.md.
    #[arg(long, value_name = "DIR", default_value = "out/eval")]
    out: PathBuf,
    /// Also write the Markdown report here (links point into --out).
    #[arg(long, value_name = "FILE")]
    report: Option<PathBuf>,
    /// Scenes, replacing the default list: a built-in name or a .gltf/.glb/.obj path,
    /// optionally labelled as LABEL=SPEC. Repeat for several.
    #[arg(long = "scene", value_name = "[LABEL=]SPEC")]
    scenes: Vec<String>,
    /// Rays per ray type (default: 4000 with --quick, else 5000).
    #[arg(long, value_name = "N")]
    rays: Option<usize>,
    /// Runs per measurement; medians are reported (default: 1 with --quick, else 2).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    repeat: Option<u32>,
    /// Skip the GPU backend.
    #[arg(long)]
    no_gpu: bool,
    /// Skip the deforming scene.
    #[arg(long)]
    no_dynamic: bool,
    /// Skip the path-traced renders (image error against time).
    #[arg(long)]
    no_render: bool,
    /// Skip the approximate methods (MMRT's A-buffer, one depth layer).
    #[arg(long)]
    no_approx: bool,
    /// Skip the whole `dirt trace` processes on the large scene (not run with --quick).
    #[arg(long)]
    no_processes: bool,
    /// Alternated rounds of DIRT beside each peer (default 5; --quick: 2; 0 leaves them out).
    #[arg(long, value_name = "N")]
    side_rounds: Option<u32>,
    /// Frames of the deforming scene.
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Seed of the rays.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The Stanford bunny as OBJ (made by scripts/eval); used in the full run when it exists.
    #[arg(long, value_name = "FILE", default_value = "target/assets/bunny.obj")]
    bunny: PathBuf,
}

pub fn eval(args: &EvalArgs) -> Result<()> {
    let mut cfg = if args.quick {
        EvalConfig::quick()
    } else {
        EvalConfig::full()
    };
    let mut notes = Vec::new();
    if args.scenes.is_empty() {
        if !args.quick {
            let engine = dirt_eval::harness::engine_path();
            if engine.exists() {
                cfg.scenes
                    .push(("2CylinderEngine".into(), engine.display().to_string()));
            } else {
                notes.push(format!(
                    "2CylinderEngine skipped: {} not found (Debian package assimp-testmodels)",
                    engine.display()
                ));
            }
            if args.bunny.exists() {
                cfg.scenes
                    .push(("bunny".into(), args.bunny.display().to_string()));
            } else {
                notes.push(format!(
                    "bunny skipped: {} not found (scripts/eval makes it from the npm package `bunny`)",
                    args.bunny.display()
                ));
            }
        }
    } else {
        cfg.scenes = args
            .scenes
            .iter()
            .map(|s| match s.split_once('=') {
                Some((label, spec)) if !label.is_empty() && !spec.is_empty() => {
                    (label.to_string(), spec.to_string())
                }
                _ => {
                    let label = std::path::Path::new(s)
                        .file_stem()
                        .map_or_else(|| s.clone(), |f| f.to_string_lossy().into_owned());
                    (label, s.clone())
                }
            })
            .collect();
    }
    if let Some(n) = args.rays {
        if n == 0 {
            bail!("--rays must be at least 1");
        }
        cfg.rays = n;
        if let Some(d) = cfg.dynamic.as_mut() {
            d.rays = n;
        }
    }
    if let Some(k) = args.repeat {
        cfg.repeat = k;
    }
    if let Some(n) = args.side_rounds {
        cfg.side_rounds = n;
    }
    if args.no_gpu {
        cfg.gpu = None;
    }
    if args.no_render {
        cfg.render = None;
    }
    if args.no_approx {
        cfg.approx.clear();
        if let Some(r) = cfg.render.as_mut() {
            r.approx.clear();
        }
    }
    if args.no_dynamic {
        cfg.dynamic = None;
    } else if let Some(f) = args.frames {
        if f == 0 {
            bail!("--frames must be at least 1");
        }
        let d = cfg.dynamic.get_or_insert(DynamicConfig {
            grid: 64,
            animated: true,
            frames: f,
            rays: cfg.rays,
            rays_large: None,
        });
        d.frames = f;
    }
    cfg.seed = args.seed;
    eprintln!(
        "dirt eval: {} scene(s), {} grid point(s), {} rays per type, {} peer(s), {} approximate setting(s), rayon threads {}",
        cfg.scenes.len(),
        cfg.grid.len(),
        cfg.rays,
        cfg.peers.len(),
        cfg.approx.len(),
        rayon::current_num_threads()
    );
    let mut res = dirt_eval::run(&cfg).context("evaluation failed")?;
    if !args.quick && !args.no_processes {
        match processes(&args.out) {
            Ok(rows) => res.processes = rows,
            Err(e) => notes.push(format!("whole processes skipped: {e:#}")),
        }
    }
    notes.append(&mut res.notes);
    res.notes = notes;
    let files = dirt_eval::report::write_all(&res, &args.out, args.report.as_deref())
        .context("cannot write the results")?;
    // DIRT and the grid share the triangle test: any difference is a defect.
    let exact = |backend: &str| backend.starts_with("dirt") || backend.starts_with("grid");
    let dirt_errors: usize = res
        .traces
        .iter()
        .filter(|t| exact(&t.backend) && !t.setting.starts_with("single@camera"))
        .map(|t| t.differ)
        .sum::<usize>()
        + res
            .dynamic
            .iter()
            .filter(|r| exact(&r.backend))
            .map(|r| r.differ)
            .sum::<usize>();
    for f in &files {
        eprintln!("wrote {}", f.display());
    }
    for n in &res.notes {
        eprintln!("note: {n}");
    }
    eprintln!(
        "dirt eval: {:.0} s; DIRT and grid rays differing from brute force (exact settings): {dirt_errors}",
        res.wall_s
    );
    if dirt_errors > 0 {
        bail!(
            "DIRT or the grid differs from brute force on {dirt_errors} ray(s): a defect (see the report)"
        );
    }
    Ok(())
}

/// Rings and segments of the large scene's tube: 2 · 320 · 320 = 204,800 triangles.
const LARGE_TUBE: usize = 320;
/// Random rays traced through it.
const LARGE_RAYS: usize = 1_000_000;
/// Runs per backend, alternated.
const PROCESS_RUNS: usize = 2;

/// Whole `dirt trace` processes of this binary on a generated tube of
/// 204,800 triangles and a million random rays, per backend (DIRT at the
/// cost model's choice, obvhs, Embree when built with it).
fn processes(out: &std::path::Path) -> Result<Vec<dirt_eval::harness::ProcessRow>> {
    use std::process::{Command, Stdio};
    let exe = std::env::current_exe().context("cannot find this program")?;
    let dir = out.join("process");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot make {}", dir.display()))?;
    let scene = dir.join("tube.glb");
    std::fs::write(
        &scene,
        dirt_eval::dynamic::twister_glb(LARGE_TUBE, LARGE_TUBE),
    )
    .with_context(|| format!("cannot write {}", scene.display()))?;
    let rays = dir.join("rays.npy");
    let run = |args: &[&std::ffi::OsStr]| -> Result<f64> {
        let start = std::time::Instant::now();
        let status = Command::new(&exe)
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .context("cannot run dirt")?;
        if !status.success() {
            bail!("dirt {args:?} failed ({status})");
        }
        Ok(start.elapsed().as_secs_f64())
    };
    let count = LARGE_RAYS.to_string();
    run(&[
        "rays".as_ref(),
        scene.as_os_str(),
        "--count".as_ref(),
        count.as_ref(),
        "--kind".as_ref(),
        "random".as_ref(),
        "--out".as_ref(),
        rays.as_os_str(),
    ])?;
    let mut backends = vec!["cpu", "obvhs"];
    if cfg!(feature = "embree") {
        backends.push("embree");
    }
    let hits_of = |b: &str| dir.join(format!("hits-{b}.npy"));
    let mut runs = vec![Vec::new(); backends.len()];
    for _ in 0..PROCESS_RUNS {
        for (k, b) in backends.iter().enumerate() {
            let hits = hits_of(b);
            eprintln!("dirt eval: whole process, dirt trace --backend {b}");
            runs[k].push(run(&[
                "trace".as_ref(),
                scene.as_os_str(),
                "--rays".as_ref(),
                rays.as_os_str(),
                "--out".as_ref(),
                hits.as_os_str(),
                "--backend".as_ref(),
                b.as_ref(),
            ])?);
        }
    }
    let dirt = dirt_cli::npy::read_hits(&hits_of("cpu"))?;
    let mut rows = Vec::new();
    for (b, runs_s) in backends.iter().zip(runs) {
        let hits = dirt_cli::npy::read_hits(&hits_of(b))?;
        if hits.len() != dirt.len() {
            bail!("{} hits from {b}, {} from DIRT", hits.len(), dirt.len());
        }
        let differ = dirt
            .iter()
            .zip(&hits)
            .filter(|(d, h)| d.prim != h.prim || (d.t - h.t).abs() > 1e-4 * d.t.abs().max(1e-30))
            .count();
        rows.push(dirt_eval::harness::ProcessRow {
            scene: "tube".into(),
            triangles: 2 * LARGE_TUBE * LARGE_TUBE,
            rays: dirt.len(),
            backend: b.to_string(),
            runs_s,
            differ,
        });
    }
    Ok(rows)
}
