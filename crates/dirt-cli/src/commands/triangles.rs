//! `dirt triangles`: the scene's world-space triangles in the flattened order
//! (a triangle's row is its primitive id).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use dirt_cli::npy;

use crate::args::SceneArg;

#[derive(Debug, Args)]
pub struct TrianglesArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    /// Where to write the triangles: float32 .npy of shape (T, 9), rows `v0 v1 v2`.
    #[arg(long, value_name = "TRIS.npy")]
    pub out: PathBuf,
}

pub fn triangles(args: &TrianglesArgs) -> Result<()> {
    let scene = args.scene.open()?;
    npy::write_triangles(&args.out, &scene.triangles)?;
    eprintln!(
        "scene {}: wrote {} triangles to {}",
        scene.name,
        scene.triangles.len(),
        args.out.display()
    );
    Ok(())
}
