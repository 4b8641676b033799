//! Arguments shared by several commands: the scene and the structure's
//! parameters (with `--auto`, the cost model's choice), and `X,Y,Z` points.

use anyhow::{Context, Result};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args};
use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_eval::rays::{self, RayKind};
use dirt_math::Vec3;
use dirt_scene::Scene;

/// The positional scene argument shared by every subcommand.
#[derive(Debug, Args)]
pub struct SceneArg {
    /// A built-in scene (cornell, layers, foliage, spheres) or a .gltf/.glb/.obj file.
    #[arg(value_name = "SCENE", default_value = dirt_scene::DEFAULT_SCENE)]
    pub scene: String,
}

impl SceneArg {
    /// Loads the scene, printing its loader's warnings to stderr.
    pub fn open(&self) -> Result<Scene> {
        let spec = &self.scene;
        let scene =
            dirt_scene::open(spec).with_context(|| format!("cannot open scene {spec:?}"))?;
        for w in &scene.warnings {
            eprintln!("warning: {}: {w}", scene.name);
        }
        Ok(scene)
    }
}

/// Which build parameters the user gave (the rest are defaults or the model's).
#[derive(Clone, Copy, Debug, Default)]
pub struct Given {
    pub views: bool,
    pub resolution: bool,
    pub buckets: bool,
    pub tile: bool,
}

/// Build parameters of the acceleration structure; defaults are `AdsParams::default()`.
#[derive(Debug, Args)]
pub struct AdsArgs {
    /// Views covering the scene.
    #[arg(long, value_enum, default_value_t = AdsParams::default().views)]
    pub views: ViewsKind,
    /// Face resolution in pixels (square faces).
    #[arg(long, value_name = "N", default_value_t = AdsParams::default().resolution)]
    pub resolution: u32,
    /// Depth buckets per tile.
    #[arg(long, value_name = "B", default_value_t = AdsParams::default().buckets)]
    pub buckets: u32,
    /// Tile size in pixels.
    #[arg(long, value_name = "S", default_value_t = AdsParams::default().tile)]
    pub tile: u32,
    /// Centre of the views as "X,Y,Z" [default: centre of the scene bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub center: Option<Vec3>,
    /// Choose the views (cube or single, both exact without --center), resolution and B
    /// not given on the command line with the cost model (dirt_cpu::cost), from a
    /// sample of rays; the hits are the same.
    #[arg(long)]
    pub auto: bool,
    /// Which of the options above were given on the command line.
    #[arg(skip)]
    pub given: Given,
}

impl AdsArgs {
    /// Records which options the command line gave (the rest are defaults).
    pub fn note_given(&mut self, m: &ArgMatches) {
        let given = |id: &str| m.value_source(id) == Some(ValueSource::CommandLine);
        self.given = Given {
            views: given("views"),
            resolution: given("resolution"),
            buckets: given("buckets"),
            tile: given("tile"),
        };
    }

    /// The parameters for `scene`: [`AdsArgs::params`], or with `--auto` the
    /// cost model's cheapest candidate among those that keep every given option.
    pub fn params_for(&self, scene: &Scene, rays_per_frame: u64) -> Result<AdsParams> {
        let base = self.params();
        if !self.auto {
            return Ok(base);
        }
        let g = self.given;
        let cands: Vec<AdsParams> = dirt_cpu::cost::candidates(&base, !g.views)
            .into_iter()
            .map(|c| AdsParams {
                resolution: if g.resolution {
                    base.resolution
                } else {
                    c.resolution
                },
                buckets: if g.buckets { base.buckets } else { c.buckets },
                tile: base.tile,
                ..c
            })
            .filter(|c| c.validate().is_ok())
            .collect();
        let mut uniq: Vec<AdsParams> = Vec::new();
        for c in cands {
            if !uniq.contains(&c) {
                uniq.push(c);
            }
        }
        let sample = rays::generate(&scene.triangles, None, RayKind::Mixed, 2000, 1)
            .context("--auto: cannot make the ray sample")?;
        let ranked = dirt_cpu::cost::choose(
            &scene.triangles,
            &sample,
            rays_per_frame,
            Traversal::HiZ,
            &dirt_cpu::cost::CostModel::CALIBRATED,
            &uniq,
        )
        .context("--auto: cannot build the candidates")?;
        let best = ranked.first().map_or(base, |c| c.params);
        eprintln!(
            "--auto: {:?} views, resolution {}, B = {}, S = {} (cheapest predicted frame of {rays_per_frame} rays among {} candidates)",
            best.views,
            best.resolution,
            best.buckets,
            best.tile,
            ranked.len()
        );
        Ok(best)
    }

    /// The parameters as given (defaults for the rest), without `--auto`.
    pub fn params(&self) -> AdsParams {
        AdsParams {
            views: self.views,
            resolution: self.resolution,
            buckets: self.buckets,
            tile: self.tile,
            center: self.center,
        }
    }
}

/// Parses a point `X,Y,Z` (`--center`, `--eye`, `--target`).
pub fn parse_point(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers X,Y,Z (e.g. 0,1,0.5), got {} value(s) in {s:?}",
            parts.len()
        ));
    }
    let mut c = [0.0f32; 3];
    for ((slot, part), axis) in c.iter_mut().zip(&parts).zip(["X", "Y", "Z"]) {
        let v: f32 = part.parse().map_err(|_| {
            format!("{axis} = {part:?} is not a number; expected X,Y,Z (e.g. 0,1,0.5)")
        })?;
        if !v.is_finite() {
            return Err(format!("{axis} = {part:?} is not finite"));
        }
        *slot = v;
    }
    Ok(Vec3::from_array(c))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_parse() {
        assert_eq!(parse_point("1,2,3"), Ok(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(
            parse_point(" -1.5, 0 ,2e-3"),
            Ok(Vec3::new(-1.5, 0.0, 2e-3))
        );
    }

    #[test]
    fn point_errors_are_clear() {
        let err = parse_point("1,2").expect_err("two values");
        assert!(
            err.contains("three comma-separated") && err.contains("2 value(s)"),
            "{err}"
        );
        let err = parse_point("1,2,3,4").expect_err("four values");
        assert!(err.contains("4 value(s)"), "{err}");
        let err = parse_point("1,y,3").expect_err("not a number");
        assert!(err.contains("Y = \"y\" is not a number"), "{err}");
        let err = parse_point("1,2,inf").expect_err("inf");
        assert!(err.contains("Z = \"inf\" is not finite"), "{err}");
        let err = parse_point("").expect_err("empty");
        assert!(err.contains("1 value(s)"), "{err}");
    }
}
