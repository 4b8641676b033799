//! Time and memory saved by leaving out what a scene does not need, against
//! the everything-on configuration, with the hits of every configuration
//! compared with brute force (they must not change).
//!
//! Configurations per scene, all with the default B, S and resolution unless
//! said otherwise:
//! * `all views` / `leave out`: `Ads::build_all_views` against `Ads::build`
//!   (views no triangle reaches get no passes and no memory), with the cube
//!   centred on the bounds (the default) and on the scene camera (the
//!   papers' placement, where whole faces can be empty);
//! * `cost model`: the candidate `dirt_cpu::cost::choose` ranks cheapest for
//!   a frame of every ray of the run, every candidate built (the default,
//!   `cost::auto`, prunes that ranking; its pick is the headline's setting), leaving out too.

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::cost::{CostModel, candidates, choose};
use dirt_cpu::{Ads, DirtCpu};
use dirt_math::{Hit, Ray, Triangle, Vec3};
use serde::Serialize;

use crate::measure::{self, StatsPass};
use crate::{EvalError, Match, compare};

/// One configuration of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct LeaveOutRow {
    pub scene: String,
    /// `bounds centre` or `camera`.
    pub centre: String,
    /// `all views`, `leave out`, `cost model`.
    pub config: String,
    pub views: String,
    pub resolution: u32,
    pub buckets: u32,
    pub views_built: usize,
    pub build_ms: f64,
    /// Median wall time of tracing every ray of the run (Hi-Z).
    pub trace_ms: f64,
    pub rays: usize,
    pub bytes: u64,
    /// Rays of the compared prefixes whose hit differs from brute force in any bit.
    pub differ: usize,
    pub compared: usize,
}

/// Rays and ground truth of one scene, as the harness prepared them.
#[derive(Debug)]
pub struct Input<'a> {
    pub scene: &'a str,
    pub tris: &'a [Triangle],
    /// Every ray of the run, all types.
    pub rays: &'a [Ray],
    /// Prefixes compared with brute force: (rays, truth).
    pub compared: Vec<(&'a [Ray], &'a [Hit])>,
    pub camera: Option<Vec3>,
    pub repeat: u32,
}

fn measure(
    input: &Input<'_>,
    centre: &str,
    config: &str,
    params: &AdsParams,
    all_views: bool,
) -> Result<LeaveOutRow, EvalError> {
    let scene = || input.scene.to_string();
    let (build_err, trace_err) = (
        EvalError::build_of(input.scene),
        EvalError::trace_of(input.scene),
    );
    // `DirtCpu` builds with `Ads::build` only: time the build of either kind here.
    let (build_ms, ads) = measure::timed(input.repeat, || {
        if all_views {
            Ads::build_all_views(input.tris, params)
        } else {
            Ads::build(input.tris, params)
        }
    })
    .map_err(|e| build_err(e.into()))?;
    let (views_built, bytes) = (ads.views.slots(), ads.memory().total());
    let mut tracer = DirtCpu::from_ads(ads, input.tris, Traversal::HiZ);
    let traced = measure::trace(&mut tracer, input.rays, input.repeat, StatsPass::Prefix(0))
        .map_err(trace_err)?;
    let mut differ = 0;
    let mut compared = 0;
    for (rays, truth) in &input.compared {
        let hits = tracer.trace(rays).map_err(trace_err)?;
        let d = compare(&hits, truth, Match::Bits);
        differ += d.differ;
        compared += d.compared;
    }
    Ok(LeaveOutRow {
        scene: scene(),
        centre: centre.to_string(),
        config: config.to_string(),
        views: format!("{:?}", params.views).to_lowercase(),
        resolution: params.resolution,
        buckets: params.buckets,
        views_built,
        build_ms,
        trace_ms: traced.trace_ms,
        rays: input.rays.len(),
        bytes,
        differ,
        compared,
    })
}

/// Every configuration of the module docs for one scene.
pub fn run(input: &Input<'_>) -> Result<Vec<LeaveOutRow>, EvalError> {
    let mut rows = Vec::new();
    let mut centres = vec![("bounds centre", AdsParams::default())];
    if let Some(eye) = input.camera {
        centres.push((
            "camera",
            AdsParams {
                center: Some(eye),
                ..AdsParams::default()
            },
        ));
    }
    for (centre, params) in &centres {
        rows.push(measure(input, centre, "all views", params, true)?);
        rows.push(measure(input, centre, "leave out", params, false)?);
    }
    // The cost model ranks on a sample, for a frame of every ray of the run.
    let sample: Vec<Ray> = input
        .rays
        .iter()
        .step_by((input.rays.len() / 2000).max(1))
        .copied()
        .collect();
    let base = AdsParams::default();
    let ranked = choose(
        input.tris,
        &sample,
        input.rays.len() as u64,
        Traversal::HiZ,
        &CostModel::CALIBRATED,
        &candidates(&base, true),
    )
    .map_err(|source| EvalError::Build {
        scene: input.scene.to_string(),
        source: source.into(),
    })?;
    if let Some(best) = ranked.first() {
        rows.push(measure(
            input,
            "bounds centre",
            "cost model",
            &best.params,
            false,
        )?);
    }
    Ok(rows)
}
