//! Stage `direct_visibility`: the primary hits.
//!
//! A z-buffer rasteriser on the CPU proposes, per pixel, the primitive
//! closest at the pixel centre. It is only a proposal: the pixel's (jittered)
//! primary ray is tested exactly against it, and when it is hit at `t`, the ray
//! is traced with `tmax = t` (inclusive, so a primitive at the same `t` with a
//! smaller id still wins) and the closer of the two under [`Hit::closer_than`]
//! is kept; when it is missed, the ray is traced in full. Either way the
//! result is the closest hit of the traced primary ray, bit for bit: the
//! rasteriser can make the trace shorter, never change the image.

use crate::RenderError;
use crate::camera::Camera;
use crate::trace::Tracer;
use dirt_math::triangle::{RayShear, intersect};
use dirt_math::{Hit, INVALID_ID, Ray, Triangle, Vec3};

/// One candidate primitive per pixel (`INVALID_ID`: none).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Raster {
    pub width: u32,
    pub height: u32,
    pub prim: Vec<u32>,
}

/// How the primary hits of a batch were found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VisibilityStats {
    /// Rays whose candidate the exact test confirmed (traced with `tmax = t`).
    pub confirmed: u64,
    /// Rays traced in full (no candidate, or the candidate missed).
    pub fallback: u64,
}

/// Rasterises `tris` as `camera` sees them; the depth test keeps the smaller
/// depth, and the smaller primitive id at equal depth. Triangles are clipped
/// at a near distance in front of the eye.
pub fn rasterize(tris: &[Triangle], camera: &Camera, width: u32, height: u32) -> Raster {
    let n = width as usize * height as usize;
    let mut prim = vec![INVALID_ID; n];
    let mut depth = vec![f32::INFINITY; n];
    if camera.ortho_half_height.is_some() {
        return Raster {
            width,
            height,
            prim,
        };
    }
    let scale = tris
        .iter()
        .flat_map(|t| t.v.iter().flatten())
        .fold(0.0f32, |m, c| m.max(c.abs()));
    let near = (scale + camera.eye.abs().max_element()) * 1e-5;
    let mut depth_test = |id: u32, s: [(f32, f32, f32); 3]| {
        let area = (s[1].0 - s[0].0) * (s[2].1 - s[0].1) - (s[2].0 - s[0].0) * (s[1].1 - s[0].1);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let xs = [s[0].0, s[1].0, s[2].0];
        let ys = [s[0].1, s[1].1, s[2].1];
        let xmin = xs
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
            .floor()
            .max(0.0);
        let xmax = xs
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil()
            .min(width as f32);
        let ymin = ys
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
            .floor()
            .max(0.0);
        let ymax = ys
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil()
            .min(height as f32);
        if !(xmin < xmax && ymin < ymax) {
            return;
        }
        let inv_area = 1.0 / area;
        for y in ymin as u32..ymax as u32 {
            let py = y as f32 + 0.5;
            for x in xmin as u32..xmax as u32 {
                let px = x as f32 + 0.5;
                let edge = |a: (f32, f32, f32), b: (f32, f32, f32)| {
                    (b.0 - a.0) * (py - a.1) - (px - a.0) * (b.1 - a.1)
                };
                let w0 = edge(s[1], s[2]) * inv_area;
                let w1 = edge(s[2], s[0]) * inv_area;
                let w2 = edge(s[0], s[1]) * inv_area;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                // Perspective-correct depth: 1/z is linear in screen space.
                let inv_z = w0 / s[0].2 + w1 / s[1].2 + w2 / s[2].2;
                if !(inv_z > 0.0) {
                    continue;
                }
                let z = 1.0 / inv_z;
                let i = y as usize * width as usize + x as usize;
                if z < depth[i] {
                    depth[i] = z;
                    prim[i] = id;
                }
            }
        }
    };
    for (id, t) in tris.iter().enumerate() {
        // Clip against the near plane (depth along `forward` >= near) in
        // world space, then project the (up to four) vertices and fan them.
        let depth_of = |p: Vec3| (p - camera.eye).dot(camera.forward);
        let mut poly: Vec<Vec3> = Vec::with_capacity(4);
        for k in 0..3 {
            let (a, b) = (t.vertex(k), t.vertex((k + 1) % 3));
            let (da, db) = (depth_of(a) - near, depth_of(b) - near);
            if da >= 0.0 {
                poly.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                poly.push(a + (b - a) * (da / (da - db)));
            }
        }
        if poly.len() < 3 {
            continue;
        }
        let projected: Option<Vec<(f32, f32, f32)>> = poly
            .iter()
            .map(|&p| camera.project(p, width, height, near * 0.5))
            .collect();
        let Some(sp) = projected else { continue };
        if sp.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
            continue;
        }
        for k in 1..sp.len() - 1 {
            depth_test(id as u32, [sp[0], sp[k], sp[k + 1]]);
        }
    }
    Raster {
        width,
        height,
        prim,
    }
}

/// The closest hits of `rays`, where ray `i` belongs to pixel `pixels[i]`
/// of `raster`: candidates confirmed exactly, traces limited by them.
pub fn primary_hits(
    tracer: &mut dyn Tracer,
    tris: &[Triangle],
    raster: &Raster,
    rays: &[Ray],
    pixels: &[usize],
) -> Result<(Vec<Hit>, VisibilityStats), RenderError> {
    let proposed = Proposed::new(tris, raster, rays, pixels);
    let traced = tracer.trace(&proposed.limited)?;
    proposed.settle(traced)
}

/// The rasteriser's proposals for a batch of primary rays, confirmed by the
/// exact test: the rays limited to the confirmed distances (what is traced)
/// and the confirmed hits. [`primary_hits`] in two halves, so that the trace
/// between them can be awaited.
#[derive(Debug)]
pub struct Proposed {
    /// The rays, each limited to its confirmed candidate's `t` (unchanged where none was).
    pub limited: Vec<Ray>,
    candidates: Vec<Hit>,
    stats: VisibilityStats,
}

impl Proposed {
    /// Confirms the rasterised primitive of each ray's pixel (`pixels[i]`) with the exact test.
    pub fn new(tris: &[Triangle], raster: &Raster, rays: &[Ray], pixels: &[usize]) -> Proposed {
        let mut stats = VisibilityStats::default();
        let mut limited = rays.to_vec();
        let mut candidates = vec![Hit::MISS; rays.len()];
        for (i, ray) in limited.iter_mut().enumerate() {
            let c = raster.prim.get(pixels[i]).copied().unwrap_or(INVALID_ID);
            let hit = tris
                .get(c as usize)
                .and_then(|t| intersect(ray, &RayShear::new(ray), t));
            match hit {
                Some((t, u, v)) => {
                    ray.tmax = t;
                    candidates[i] = Hit { prim: c, t, u, v };
                    stats.confirmed += 1;
                }
                None => stats.fallback += 1,
            }
        }
        Proposed {
            limited,
            candidates,
            stats,
        }
    }

    /// The primary hits: the closer of each confirmed candidate and the
    /// trace of its limited ray.
    pub fn settle(self, traced: Vec<Hit>) -> Result<(Vec<Hit>, VisibilityStats), RenderError> {
        if traced.len() != self.candidates.len() {
            return Err(RenderError::HitCount {
                expected: self.candidates.len(),
                got: traced.len(),
            });
        }
        let hits = traced
            .into_iter()
            .zip(self.candidates)
            .map(|(h, c)| if c.closer_than(&h) { c } else { h })
            .collect();
        Ok((hits, self.stats))
    }
}
