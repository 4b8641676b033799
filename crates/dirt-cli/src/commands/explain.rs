//! `dirt info --explain`: what the structure leaves out for a scene and why,
//! what it chose and why, measured against the everything-on configuration.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use dirt_core::{AdsParams, LeftOutReason, Traversal, ViewsKind, left_out_views};
use dirt_cpu::Ads;
use dirt_cpu::cost::{CostModel, candidates, choose};
use dirt_scene::Scene;

use crate::args::Given;
use dirt_eval::rays::{self, RayKind};

/// Rays of the sample the cost model counts per candidate.
const SAMPLE: usize = 2000;

fn kib(bytes: u64) -> f64 {
    bytes as f64 / 1024.0
}

/// The explanation as text.
pub fn explain(
    scene: &Scene,
    params: &AdsParams,
    given: Given,
    rays_per_frame: u64,
) -> Result<String> {
    let tris = &scene.triangles;
    let mut out = String::new();
    let o = &mut out;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;

    // The views.
    let _ = writeln!(o, "chosen:");
    let _ = writeln!(
        o,
        "  views: {} — {}",
        ViewsKind::name(params.views),
        match (params.views, params.center) {
            (ViewsKind::Cube, _) =>
                "six 90° views around one centre see all of space: exact for every ray",
            (ViewsKind::Single, None) =>
                "one view placed outside the bounds sees all of them: exact for every ray, one sixth of the cube's tiles",
            (ViewsKind::Single, Some(_)) =>
                "one view from the given eye: exact only for hits inside its frustum (use the cube for all rays)",
            (ViewsKind::Ortho, _) =>
                "one orthographic view over the bounds sees all of them: exact for every ray",
            (ViewsKind::OrthoSplit, _) =>
                "two orthographic views, split by a plane across the axis they look along, see all of the bounds: exact for every ray",
        }
    );

    // Parameters: given, or ranked by the cost model on a ray sample.
    let sample = rays::generate(tris, None, RayKind::Mixed, SAMPLE, 1)
        .context("cannot make the ray sample for the cost model")?;
    let model = CostModel::CALIBRATED;
    let mut cands = if given.views {
        candidates(params, false)
    } else {
        dirt_cpu::cost::candidates_all(params, tris)
    };
    if !cands.contains(params) {
        cands.push(*params);
    }
    let ranked = choose(
        tris,
        &sample,
        rays_per_frame,
        Traversal::HiZ,
        &model,
        &cands,
    )
    .context("cannot build the candidates of the cost model")?;
    let source = |g: bool| if g { "given" } else { "default" };
    let _ = writeln!(
        o,
        "  resolution {} ({}), buckets B = {} ({}), tile S = {} ({})",
        params.resolution,
        source(given.resolution),
        params.buckets,
        source(given.buckets),
        params.tile,
        source(given.tile)
    );
    let _ = writeln!(
        o,
        "  cost model (calibrated weights, Hi-Z, counts from {SAMPLE} mixed rays), frame of {rays_per_frame} rays:"
    );
    let _ = writeln!(
        o,
        "    {:>6} {:>10} {:>4} {:>4} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "views", "resolution", "B", "S", "nodes", "tests/ray", "build ms", "frame ms", "KiB"
    );
    for (k, c) in ranked.iter().enumerate() {
        let here = c.params == *params;
        let _ = writeln!(
            o,
            "    {:>6} {:>10} {:>4} {:>4} {:>10} {:>10.1} {:>10.1} {:>10.1} {:>9.0}{}{}",
            ViewsKind::name(c.params.views),
            c.params.resolution,
            c.params.buckets,
            c.params.tile,
            c.counts.nodes,
            c.counts.tests_per_ray,
            c.build_ms,
            c.frame_ms,
            kib(c.bytes),
            if k == 0 {
                "  <- cheapest predicted"
            } else {
                ""
            },
            if here { "  <- in use" } else { "" }
        );
    }
    if let Some(best) = ranked.first() {
        let _ = writeln!(
            o,
            "    every candidate gives the same hits; without --fixed the commands build the cheapest \
             (here {} views, resolution {}, B = {}; they prune the ranking, so a close second may win), or set --views/--resolution/--buckets/--tile yourself",
            ViewsKind::name(best.params.views),
            best.params.resolution,
            best.params.buckets
        );
    }

    // What is left out, measured against building every view.
    let _ = writeln!(o, "left out:");
    let left = left_out_views(tris, params).context("cannot place the views")?;
    if left.is_empty() {
        let _ = writeln!(o, "  views: none; geometry reaches every view");
    }
    for l in &left {
        let why = match l.reason {
            LeftOutReason::BoundsBehind => "no part of the scene bounds is in front of it",
            LeftOutReason::NoTriangleReaches => "no triangle reaches any of its tiles",
        };
        let _ = writeln!(
            o,
            "  view {}: {why}; no fill_depth, mip_depth or fill_primitives work, no memory, rays skip it",
            l.name
        );
    }
    let lean = Ads::build(tris, params).context("cannot build the structure")?;
    let full = Ads::build_all_views(tris, params).context("cannot build the structure")?;
    let (lm, fm) = (lean.memory().total(), full.memory().total());
    let _ = writeln!(
        o,
        "  measured: {} of {} views built; memory {:.1} KiB against {:.1} KiB with every view the bounds reach ({:.1} KiB saved); \
         build {:.2} ms against {:.2} ms",
        lean.views.slots(),
        lean.views.views.len(),
        kib(lm),
        kib(fm),
        kib(fm.saturating_sub(lm)),
        ms(lean.timings.total()),
        ms(full.timings.total()),
    );
    let stats = lean.stats();
    let _ = writeln!(
        o,
        "  lists: sized by a counting pass ({} nodes in {} non-empty lists); no fixed pool, nothing dropped",
        stats.nodes, stats.nonempty_lists
    );
    let _ = writeln!(
        o,
        "  rebuilds: the structure depends only on the triangles and these parameters; \
         dirt_cpu::BuildCache reuses it while they are unchanged (camera-only changes rebuild nothing)"
    );

    // What the scene has, for the shading stages.
    let _ = writeln!(o, "scene content:");
    let emissive = scene
        .tri_material
        .iter()
        .filter(|&&m| {
            scene
                .materials
                .get(m as usize)
                .is_some_and(|m| m.is_emissive())
        })
        .count();
    let textured = scene
        .materials
        .iter()
        .filter(|m| m.base_color_texture.is_some())
        .count();
    let _ = writeln!(
        o,
        "  {} triangles, {} materials ({} textured), {} textures, {} emissive triangles, {} punctual lights, {} cameras",
        tris.len(),
        scene.materials.len(),
        textured,
        scene.textures.len(),
        emissive,
        scene.lights.len(),
        scene.cameras.len()
    );
    // The renderer's shading features for this scene.
    for mode in [dirt_render::Mode::Pt, dirt_render::Mode::Ao] {
        let settings = dirt_render::Settings {
            mode,
            ..Default::default()
        };
        let _ = writeln!(
            o,
            "dirt render --mode {}:",
            format!("{mode:?}").to_lowercase()
        );
        for f in dirt_render::features(scene, &settings) {
            let _ = writeln!(
                o,
                "  {:<8} {}: {}",
                if f.used { "runs" } else { "left out" },
                f.name,
                f.why
            );
        }
    }
    Ok(out)
}
