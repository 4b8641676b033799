//! Arguments shared by several commands: the scene and the structure's
//! parameters (the cost model's choice for what is not given, or with
//! `--fixed` the fixed defaults), and `X,Y,Z` points.

use anyhow::{Context, Result};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args};
use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_eval::rays::{self, RayKind};
use dirt_math::view::Axis;
use dirt_math::{Ray, Vec3};
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

/// The camera of `render` and `view`: the scene's, with these overrides.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Camera position "X,Y,Z" [default: the scene's first camera, else a framing of the bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Point the camera looks at (and `view` orbits), "X,Y,Z".
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEG")]
    pub fov: Option<f32>,
}

/// Which build parameters the user gave (the rest are defaults or the model's).
#[derive(Clone, Copy, Debug, Default)]
pub struct Given {
    pub views: bool,
    pub resolution: bool,
    pub buckets: bool,
    pub tile: bool,
}

/// Build parameters of the acceleration structure. What is not given is the
/// cost model's choice for the scene and the rays (`dirt_cpu::cost::auto`), or
/// with `--fixed` `AdsParams::default()` (cube, 128, B 8, S 1).
#[derive(Debug, Args)]
pub struct AdsArgs {
    /// Views covering the scene [default: the cost model's choice; with --fixed, cube].
    #[arg(long, value_enum, default_value_t = AdsParams::default().views, hide_default_value = true)]
    pub views: ViewsKind,
    /// Face resolution in pixels (square faces) [default: the cost model's choice; with --fixed, 128].
    #[arg(long, value_name = "N", default_value_t = AdsParams::default().resolution, hide_default_value = true)]
    pub resolution: u32,
    /// Depth buckets per tile [default: the cost model's choice; with --fixed, 8].
    #[arg(long, value_name = "B", default_value_t = AdsParams::default().buckets, hide_default_value = true)]
    pub buckets: u32,
    /// Tile size in pixels [default: 1].
    #[arg(long, value_name = "S", default_value_t = AdsParams::default().tile)]
    pub tile: u32,
    /// Centre of the views as "X,Y,Z" [default: centre of the scene bounds].
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    pub center: Option<Vec3>,
    /// The axis orthographic views (--views ortho, ortho2) look along [default: the bounds' thinnest].
    /// With ortho2, --center is a point of the cutting plane [default: the bounds' centre].
    #[arg(long, value_enum)]
    pub axis: Option<Axis>,
    /// Use the fixed defaults (cube, 128, B 8, S 1) for what is not given, instead of
    /// the cost model's choice. Every setting gives the same hits; only time and memory differ.
    #[arg(long, conflicts_with = "auto")]
    pub fixed: bool,
    /// The cost model chooses the views (cube, single, ortho or ortho2, all exact without
    /// --center), resolution and B not given, from a sample of the rays (dirt_cpu::cost::auto).
    /// This is the default; the flag remains for scripts.
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

    /// The parameters for `scene` and a frame of `rays_per_frame` rays: with
    /// `--fixed`, or when views, resolution and B are all given,
    /// [`AdsArgs::params`]; otherwise the cost model's cheapest candidate among
    /// those that keep every given option, measured on `sample` (a stride of
    /// it), or on generated mixed rays when there is none. Prints the choice.
    pub fn params_for(
        &self,
        scene: &Scene,
        rays_per_frame: u64,
        sample: Option<&[Ray]>,
    ) -> Result<AdsParams> {
        Ok(self.choose(scene, rays_per_frame, sample)?.0)
    }

    /// [`AdsArgs::params_for`], with the CPU structure of the choice when the
    /// cost model built it while choosing (so the CPU backend need not build it again).
    pub fn choose(
        &self,
        scene: &Scene,
        rays_per_frame: u64,
        sample: Option<&[Ray]>,
    ) -> Result<(AdsParams, Option<dirt_cpu::Ads>)> {
        self.choose_within(scene, rays_per_frame, sample, None)
    }

    /// [`AdsArgs::choose`] for a GPU of binding limits `limits`: the cost
    /// model chooses among the candidates that fit
    /// (`dirt_cpu::cost::auto_within`).
    pub fn choose_within(
        &self,
        scene: &Scene,
        rays_per_frame: u64,
        sample: Option<&[Ray]>,
        limits: Option<dirt_core::BindingLimits>,
    ) -> Result<(AdsParams, Option<dirt_cpu::Ads>)> {
        let base = self.params();
        let g = self.given;
        if self.fixed || (g.views && g.resolution && g.buckets) {
            return Ok((base, None));
        }
        let start = std::time::Instant::now();
        // Rays that all start at one point (a camera's): the views placed
        // there, each exact for every ray, of the views given if any.
        let origin = match (base.center, sample) {
            (None, Some(rays)) => dirt_cpu::cost::common_origin(rays),
            _ => None,
        };
        let placed: Vec<AdsParams> = origin
            .map(|o| {
                let bounds = dirt_math::Aabb::of_triangles(&scene.triangles);
                dirt_cpu::cost::candidates_at(o, &bounds)
            })
            .unwrap_or_default()
            .into_iter()
            .filter(|c| !g.views || c.views == base.views)
            .collect();
        let at = match origin {
            Some(o) if !placed.is_empty() => {
                format!(
                    ", placed at the rays' common origin {},{},{}",
                    o.x, o.y, o.z
                )
            }
            _ => String::new(),
        };
        let raw = if !placed.is_empty() {
            placed
        } else if g.views {
            dirt_cpu::cost::candidates(&base, false)
        } else {
            dirt_cpu::cost::candidates_all(&base, &scene.triangles)
        };
        let cands: Vec<AdsParams> = raw
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
        let sample = sample_of(scene, sample, AUTO_SAMPLE)?;
        let mut choice = dirt_cpu::cost::auto_within(
            &scene.triangles,
            &sample,
            rays_per_frame,
            Traversal::HiZ,
            &dirt_cpu::cost::CostModel::CALIBRATED,
            &uniq,
            limits,
        )
        .context("cost model: cannot build the candidates")?;
        if let Some(l) = limits.filter(|_| choice.too_large > 0) {
            eprintln!(
                "ads: {} candidates need more than the GPU binds ({l}) and were not chosen",
                choice.too_large
            );
        }
        let best = choice.best.params;
        eprintln!(
            "ads: {} views, resolution {}, B {}, S {}{at}: the cost model's cheapest predicted frame of {rays_per_frame} rays ({} of {} candidates built, {} pruned; choosing took {:.1} ms; --fixed for cube 128 B8 S1)",
            best.views,
            best.resolution,
            best.buckets,
            best.tile,
            choice.ranked.len(),
            uniq.len(),
            choice.skipped,
            start.elapsed().as_secs_f64() * 1e3
        );
        Ok((best, choice.best_ads.take()))
    }

    /// The traversal of DIRT on the CPU: `given`, else, for a structure the
    /// cost model chose (`ads`), the faster of the two on a sample of the
    /// rays (`dirt_cpu::cost::faster_traversal`, said on stderr), else the
    /// default.
    pub fn traversal(
        &self,
        given: Option<Traversal>,
        ads: Option<&dirt_cpu::Ads>,
        scene: &Scene,
        sample: Option<&[Ray]>,
    ) -> Result<Traversal> {
        let (Some(ads), None) = (ads, given) else {
            return Ok(given.unwrap_or_default());
        };
        let sample = sample_of(scene, sample, TRAVERSAL_SAMPLE)?;
        let c = dirt_cpu::cost::faster_traversal(ads, &scene.triangles, &sample);
        eprintln!(
            "traversal: {}, the faster on a sample of {} rays (linear {:.2} ms, hiz {:.2} ms; --traversal sets it)",
            c.traversal,
            c.rays,
            c.linear.as_secs_f64() * 1e3,
            c.hiz.as_secs_f64() * 1e3
        );
        Ok(c.traversal)
    }

    /// The parameters as given, `AdsParams::default()` for the rest (what `--fixed` builds).
    pub fn params(&self) -> AdsParams {
        AdsParams {
            views: self.views,
            resolution: self.resolution,
            buckets: self.buckets,
            tile: self.tile,
            center: self.center,
            axis: self.axis,
        }
    }
}

/// Rays in the sample the cost model measures its candidates with.
const AUTO_SAMPLE: usize = 1000;

/// Rays in the sample the traversals are timed on: enough for milliseconds.
const TRAVERSAL_SAMPLE: usize = 4000;

/// `n` of `rays` (evenly strided) or, without rays, `n` mixed rays of `scene`.
fn sample_of(scene: &Scene, rays: Option<&[Ray]>, n: usize) -> Result<Vec<Ray>> {
    Ok(match rays {
        Some(rays) if !rays.is_empty() => dirt_cpu::cost::stride_sample(rays, n),
        _ => rays::generate(&scene.triangles, None, RayKind::Mixed, n, 1)
            .context("cannot make a sample of rays")?,
    })
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
