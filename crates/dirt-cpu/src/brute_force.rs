//! Ground truth: every ray against every triangle with the same triangle test
//! and the same tie-break as `trace`.

use dirt_core::{
    BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Triangle, trace_each,
};
use dirt_math::triangle::{RayShear, intersect_closest};
use rayon::prelude::*;

/// Closest hits by testing every triangle. Rays that fail [`Ray::validate`] miss.
pub fn trace(tris: &[Triangle], rays: &[Ray]) -> Vec<Hit> {
    rays.par_iter().map(|r| trace_ray(tris, r)).collect()
}

pub fn trace_ray(tris: &[Triangle], ray: &Ray) -> Hit {
    let mut best = Hit::MISS;
    if ray.validate().is_err() {
        return best;
    }
    let sh = RayShear::new(ray);
    for (id, t) in tris.iter().enumerate() {
        intersect_closest(ray, &sh, t, id as u32, &mut best);
    }
    best
}

/// Brute force as a [`Tracer`]: the ground truth every other tracer is held to.
#[derive(Debug, Default)]
pub struct Brute {
    tris: Vec<Triangle>,
}

impl Brute {
    /// Brute force over `tris` (a copy is kept).
    pub fn new(tris: &[Triangle]) -> Self {
        Self {
            tris: tris.to_vec(),
        }
    }
}

impl Tracer for Brute {
    fn name(&self) -> String {
        "brute".to_string()
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        self.tris.clear();
        self.tris.extend_from_slice(tris);
        Ok(BuildReport {
            stages: Vec::new(),
            // It builds nothing: the triangles it keeps are the input, not a structure.
            memory: Some(0),
        })
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        let tris = &self.tris;
        trace_each(rays, hits, stats.as_deref(), |r| trace_ray(tris, r))
    }
}
