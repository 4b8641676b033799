//! `dirt rays`: deterministic test rays for a scene (`dirt_eval::rays`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use dirt_cli::npy;
use dirt_eval::rays::{self, Camera, RayKind};

use crate::args::SceneArg;

#[derive(Debug, Args)]
pub struct RaysArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    /// Where to write the rays: float32 .npy of shape (N, 8).
    #[arg(long, value_name = "RAYS.npy")]
    pub out: PathBuf,
    /// Number of rays.
    #[arg(long, default_value_t = 100_000)]
    pub count: usize,
    /// Seed of the generator: the same seed gives the same file.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Which rays: `mixed` interleaves every family (random, axis-aligned, aimed at vertices
    /// and edge midpoints, grazing along triangle planes, tmax-limited segments, bounces, camera).
    #[arg(long, value_enum, default_value_t = RayKind::Mixed)]
    pub kind: RayKind,
}

pub fn rays(args: &RaysArgs) -> Result<()> {
    let scene = args.scene.open()?;
    let rays = rays::generate(
        &scene.triangles,
        Camera::of_scene(&scene),
        args.kind,
        args.count,
        args.seed,
    )
    .with_context(|| format!("cannot make rays for scene {}", scene.name))?;
    npy::write_rays(&args.out, &rays)?;
    eprintln!(
        "scene {}: wrote {} {} rays (seed {}) to {}",
        scene.name,
        rays.len(),
        args.kind
            .to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_owned()),
        args.seed,
        args.out.display()
    );
    Ok(())
}
