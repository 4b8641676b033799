//! `dirt`: the command line of DIRT (Deferred Image-based Ray Tracing).
//!
//! ```text
//! dirt rays      SCENE --out RAYS.npy [--count N] [--seed S] [--kind mixed|camera|random|inside]
//! dirt trace     SCENE --rays RAYS.npy --out HITS.npy [--backend cpu|gpu|brute] [ADS options] [--traversal linear|hiz]
//! dirt bench     SCENE [ADS options] [--rays N] [--seed S] [--kind K] [--backends cpu,gpu,brute] [--repeat K] [--json FILE]
//! dirt triangles SCENE --out TRIS.npy
//! dirt info      SCENE [ADS options]
//! dirt view      [SCENE] [--width W --height H --scale F] [--backend auto|gpu|cpu] [--frames N] [--max-samples N]
//! ADS options:   [--views cube|single] [--resolution N] [--buckets B] [--tile S] [--center X,Y,Z]
//! ```
//!
//! File formats are described in [`dirt_cli::npy`]. Timings and counts go to stderr,
//! `dirt info` and `dirt bench` print to stdout.

mod args;
mod commands;
mod gpu;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use crate::commands::{bench, eval, info, rays, render, trace, triangles, view};

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
    Trace(trace::TraceArgs),
    /// Write the scene's world-space triangles (float32, shape (T, 9)) in the flattened order.
    Triangles(triangles::TrianglesArgs),
    /// Print the triangle count, the bounds and the acceleration structure's statistics and memory.
    Info(info::InfoArgs),
    /// Write a file of test rays for a scene (deterministic for a seed).
    Rays(rays::RaysArgs),
    /// Benchmark build and trace of every backend side by side on generated rays,
    /// with their errors against brute force (a Markdown table on stdout).
    Bench(bench::BenchArgs),
    /// Evaluate DIRT against brute force, obvhs and Embree over scenes and a parameter
    /// grid; write CSV, JSON, plots and a Markdown report.
    Eval(eval::EvalArgs),
    /// Render an image: a path tracer whose every ray is traced through DIRT
    /// (or the reference BVH, or brute force); tone-mapped PNG, linear EXR.
    Render(render::RenderArgs),
    /// Open a window that path-traces the scene progressively through DIRT
    /// (GPU, or CPU with the image uploaded): orbit, pan, zoom, play/pause;
    /// samples and rays/s in the title bar.
    View(view::ViewArgs),
}

/// The program's allocator: a frame's rebuild allocates and frees buffers of
/// megabytes, which the system allocator hands back to the kernel and then
/// page-faults in again, zeroed, every frame; mimalloc keeps them for reuse
/// (the deforming grid's build: 3.92 -> 3.43 ms). It serves every Rust
/// allocation of a run, DIRT's and its peers' alike; Embree allocates its
/// own structures through the C library, as in any program that links it.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

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
            Command::View(a) => a.ads.note_given(sub),
            Command::Bench(a) => a.ads.note_given(sub),
            Command::Render(a) => a.ads.note_given(sub),
            _ => {}
        }
    }
    let result = match cli.command {
        Command::Trace(args) => trace::trace(&args),
        Command::Triangles(args) => triangles::triangles(&args),
        Command::Info(args) => info::info(&args),
        Command::Rays(args) => rays::rays(&args),
        Command::Bench(args) => bench::bench(&args),
        Command::Eval(args) => eval::eval(&args),
        Command::Render(args) => render::render(&args),
        Command::View(args) => view::view(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_core::{AdsParams, Traversal, ViewsKind};
    use dirt_math::Vec3;
    use trace::TraceBackend as Backend;

    #[test]
    fn command_line_is_well_formed() {
        Cli::command().debug_assert();
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
        assert_eq!(args.traversal, None);
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
        assert_eq!(args.traversal, Some(Traversal::HiZ));
        let p = args.ads.params();
        assert_eq!(p.views, ViewsKind::Single);
        assert_eq!((p.resolution, p.buckets, p.tile), (64, 4, 2));
        assert_eq!(p.center, Some(Vec3::new(-1.0, 0.5, 2.0)));
    }

    #[test]
    fn view_options_parse() {
        let parse = |args: &[&str]| {
            let m = Cli::command().get_matches_from(args);
            let mut cli = Cli::from_arg_matches(&m).expect("parse");
            let Command::View(a) = &mut cli.command else {
                panic!("not view")
            };
            if let Some((_, sub)) = m.subcommand() {
                a.ads.note_given(sub);
            }
            a.options()
        };
        let o = parse(&["dirt", "view"]);
        assert_eq!(o.scene, dirt_scene::DEFAULT_SCENE);
        assert_eq!((o.width, o.height, o.scale), (640, 480, 2.0));
        assert!(o.play && o.frames.is_none());
        assert_eq!(o.ads, dirt_view::Ads::Auto(AdsParams::default()));
        let o = parse(&[
            "dirt",
            "view",
            "layers",
            "--frames",
            "5",
            "--scale",
            "1",
            "--backend",
            "cpu",
            "--resolution",
            "64",
            "--paused",
            "--eye",
            "0,1,2",
            "--max-samples",
            "8",
        ]);
        assert_eq!(o.scene, "layers");
        assert_eq!((o.frames, o.max_samples, o.scale), (Some(5), Some(8), 1.0));
        assert_eq!(o.backend, dirt_view::Backend::Cpu);
        assert!(!o.play);
        assert_eq!(o.eye, Some(Vec3::new(0.0, 1.0, 2.0)));
        let dirt_view::Ads::Fixed(p) = o.ads else {
            panic!("a given resolution fixes the parameters")
        };
        assert_eq!(p.resolution, 64);
    }

    #[test]
    fn bad_center_is_a_usage_error() {
        let err =
            Cli::try_parse_from(["dirt", "info", "--center", "1;2;3"]).expect_err("bad centre");
        assert!(err.to_string().contains("X,Y,Z"), "{err}");
    }
}
