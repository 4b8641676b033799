//! `dirt info`: the triangle count, the bounds, the structure's statistics and
//! memory; with `--explain`, what it leaves out and chooses, and why.

use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use dirt_cpu::Ads;

use crate::args::{AdsArgs, SceneArg};
use crate::commands::{explain, millis};

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub ads: AdsArgs,
    /// Also say what the structure leaves out for this scene and why, what it
    /// chose and why (with the cost model's ranking), measured against building every view.
    #[arg(long)]
    pub explain: bool,
    /// Rays per frame the cost model of --explain and --auto predicts for.
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    pub rays_per_frame: u64,
}

pub fn info(args: &InfoArgs) -> Result<()> {
    let scene = args.scene.open()?;
    let bounds = scene.bounds();
    println!("scene: {}", scene.name);
    println!("triangles: {}", scene.triangles.len());
    if bounds.is_empty() {
        println!("bounds: empty");
    } else {
        println!(
            "bounds: min {} max {} (extent {})",
            bounds.min,
            bounds.max,
            bounds.extent()
        );
    }
    let ext = std::path::Path::new(&args.scene.scene)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("gltf" | "glb")) {
        // The animations `dirt render --frames --animation K` can play.
        let animated = dirt_scene::open_animated(&args.scene.scene)
            .with_context(|| format!("cannot read the animations of {}", args.scene.scene))?;
        let clips = animated.clips();
        println!("animations: {}", clips.len());
        for (k, c) in clips.iter().enumerate() {
            println!(
                "  {k}: {:?}, {:.3} s, {} channels",
                c.name, c.duration, c.channels
            );
        }
    }
    let params = args.ads.params_for(&scene, args.rays_per_frame, None)?;
    let center = params.center.map_or_else(
        || format!("{} (bounds centre)", bounds.center()),
        |c| c.to_string(),
    );
    println!(
        "ads: {} views, resolution {}, {} buckets, tile {}, centre {center}",
        args.ads.views, params.resolution, params.buckets, params.tile
    );
    let start = Instant::now();
    let ads = Ads::build(&scene.triangles, &params)
        .with_context(|| format!("cannot build the acceleration structure ({params:?})"))?;
    println!("build: {:.3} ms", millis(start.elapsed()));
    println!("stats:\n{}", ads.stats());
    println!("memory:\n{}", ads.memory());
    if args.explain {
        print!(
            "{}",
            explain::explain(&scene, &params, args.ads.given, args.rays_per_frame)?
        );
    }
    Ok(())
}
