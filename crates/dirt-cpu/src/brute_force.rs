//! Ground truth: every ray against every triangle with the same triangle test
//! and the same tie-break as `trace`.

use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::{Hit, Ray, Triangle};
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
