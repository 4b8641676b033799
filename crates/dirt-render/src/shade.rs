//! Stage `shade`: the three-point form of light transport. At G(k) the BSDF
//! is evaluated between G(k-1) and G(k+1); radiance reaches the pixel from
//! emission found at G(k+1) (BSDF sampling) and from lights sampled at G(k)
//! (next-event estimation, shadow rays traced like every other ray), the two
//! combined by multiple importance sampling (power heuristic).

use crate::bsdf::Bsdf;
use crate::fetch::SurfacePoint;
use crate::lights::{LightSample, Lights};
use crate::rng::{Sampler, dim};
use crate::shading_buffer::{Scatter, ShadingBuffer};
use dirt_math::{Hit, Ray, Vec3};
use dirt_scene::Scene;
use rayon::prelude::*;

/// What `shade` reads besides the buffer.
#[derive(Debug)]
pub struct ShadeContext<'a> {
    pub scene: &'a Scene,
    pub lights: &'a Lights,
    /// Radiance of rays that leave the scene.
    pub environment: Vec3,
    /// How far a secondary ray's origin is moved off its surface, along the
    /// geometric normal on the side it leaves from.
    pub offset: f32,
    pub seed: u64,
    /// The sample being rendered.
    pub sample: u32,
    /// Russian roulette from this bounce on.
    pub roulette_from: Option<u32>,
}

/// A shadow ray's payload: what it adds to its path if the light is visible.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shadow {
    pub path: usize,
    pub contribution: Vec3,
    /// Emissive primitive aimed at (`None` for punctual lights).
    pub target: Option<u32>,
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// The origin of a ray leaving `sp` on the side of its geometric normal.
pub fn offset_origin(sp: &SurfacePoint, offset: f32) -> Vec3 {
    sp.p + sp.ng * offset
}

impl ShadeContext<'_> {
    fn sampler(&self, path: usize) -> Sampler {
        Sampler::new(self.seed, path as u32, self.sample)
    }

    /// Emission of G(1) towards the eye, and the environment for primary misses.
    pub fn primary(&self, buf: &mut ShadingBuffer) {
        let env = self.environment;
        buf.paths
            .par_iter_mut()
            .zip(&buf.cur)
            .for_each(|(path, cur)| match cur {
                Some(sp) => path.radiance += sp.emission,
                None => {
                    path.radiance += env;
                    path.alive = false;
                }
            });
    }

    /// Next-event estimation at G(k): one light sample per live path, as a
    /// shadow ray and the contribution it adds when unoccluded.
    pub fn next_event(&self, buf: &ShadingBuffer, bounce: u32) -> (Vec<Ray>, Vec<Shadow>) {
        if self.lights.is_empty() {
            return (Vec::new(), Vec::new());
        }
        let per_path: Vec<Option<(Ray, Shadow)>> = (0..buf.len())
            .into_par_iter()
            .map(|i| {
                let path = &buf.paths[i];
                let sp = buf.cur[i].as_ref()?;
                if !path.alive {
                    return None;
                }
                let bsdf = Bsdf::of(sp);
                if bsdf.is_delta() {
                    return None;
                }
                let wo = (buf.prev[i] - sp.p).normalize_or_zero();
                let s = self.sampler(i);
                let ls = self.lights.sample(
                    self.scene,
                    s.get(bounce, dim::LIGHT_PICK),
                    s.get(bounce, dim::LIGHT_U),
                    s.get(bounce, dim::LIGHT_V),
                )?;
                let origin = offset_origin(sp, self.offset);
                let (ray, contribution, target) = match ls {
                    LightSample::Area {
                        prim,
                        point,
                        normal,
                        pdf_area,
                    } => {
                        let to = point - sp.p;
                        let d2 = to.length_squared();
                        let wi = to.normalize_or_zero();
                        let cos_l = -normal.dot(wi);
                        let cos_s = sp.ns.dot(wi);
                        if !(d2 > 0.0 && cos_l > 0.0 && cos_s > 0.0 && sp.ng.dot(wi) > 0.0) {
                            return None;
                        }
                        let le = self.scene.material_of(prim as usize)?.emissive;
                        let f = bsdf.eval(sp.ns, wo, wi);
                        let pdf_light = pdf_area * d2 / cos_l;
                        let w = power_heuristic(pdf_light, bsdf.pdf(sp.ns, wo, wi));
                        let c = Vec3::from_array(le) * f * (cos_s * w / pdf_light);
                        (Ray::new(origin, point - origin, 0.0, 1.0), c, Some(prim))
                    }
                    LightSample::Point {
                        index,
                        point,
                        intensity,
                        pick,
                    } => {
                        let to = point - sp.p;
                        let d2 = to.length_squared();
                        let wi = to.normalize_or_zero();
                        let cos_s = sp.ns.dot(wi);
                        if !(d2 > 0.0 && cos_s > 0.0 && sp.ng.dot(wi) > 0.0) {
                            return None;
                        }
                        let light = &self.lights.punctual[index];
                        let k = Lights::punctual_factor(light, -wi, d2.sqrt());
                        let f = bsdf.eval(sp.ns, wo, wi);
                        let c = intensity * f * (k * cos_s / (d2 * pick));
                        (Ray::new(origin, point - origin, 0.0, 1.0), c, None)
                    }
                    LightSample::Directional {
                        dir,
                        irradiance,
                        pick,
                    } => {
                        let wi = -dir;
                        let cos_s = sp.ns.dot(wi);
                        if !(cos_s > 0.0 && sp.ng.dot(wi) > 0.0) {
                            return None;
                        }
                        let f = bsdf.eval(sp.ns, wo, wi);
                        let c = irradiance * f * (cos_s / pick);
                        (Ray::new(origin, wi, 0.0, f32::INFINITY), c, None)
                    }
                };
                let c = path.throughput * contribution;
                if !c.is_finite() || c == Vec3::ZERO || ray.validate().is_err() {
                    return None;
                }
                Some((
                    ray,
                    Shadow {
                        path: i,
                        contribution: c,
                        target,
                    },
                ))
            })
            .collect();
        per_path.into_iter().flatten().unzip()
    }

    /// Adds the contributions of the shadow rays that reached their light:
    /// nothing hit before the light point (a hit on the aimed triangle, or one
    /// at the light point itself, counts as reaching it).
    pub fn apply_shadows(&self, buf: &mut ShadingBuffer, shadows: &[Shadow], hits: &[Hit]) {
        for (s, h) in shadows.iter().zip(hits) {
            let visible = !h.is_hit()
                || (s.target.is_some() && (Some(h.prim) == s.target || h.t >= 1.0 - 1.0 / 1024.0));
            if visible {
                buf.paths[s.path].radiance += s.contribution;
            }
        }
    }

    /// Samples the BSDF at G(k) of every live path; returns the rays and the
    /// path each belongs to.
    pub fn sample_scatter(&self, buf: &mut ShadingBuffer, bounce: u32) -> (Vec<Ray>, Vec<usize>) {
        let ShadingBuffer {
            prev,
            cur,
            scatter,
            paths,
            ..
        } = buf;
        scatter.par_iter_mut().enumerate().for_each(|(i, sc)| {
            *sc = None;
            let Some(sp) = cur[i].as_ref() else { return };
            if !paths[i].alive {
                return;
            }
            let wo = (prev[i] - sp.p).normalize_or_zero();
            let s = self.sampler(i);
            let bsdf = Bsdf::of(sp);
            *sc = bsdf
                .sample(
                    sp.ns,
                    sp.ng,
                    wo,
                    s.get(bounce, dim::LOBE),
                    s.get(bounce, dim::DIR_U),
                    s.get(bounce, dim::DIR_V),
                )
                .map(|b| Scatter {
                    dir: b.wi,
                    weight: b.weight,
                    pdf: b.pdf,
                    delta: b.delta,
                });
        });
        let mut rays = Vec::new();
        let mut owner = Vec::new();
        for (i, sc) in scatter.iter().enumerate() {
            match (sc, cur[i].as_ref()) {
                (Some(sc), Some(sp)) => {
                    rays.push(Ray::new(
                        offset_origin(sp, self.offset),
                        sc.dir,
                        0.0,
                        f32::INFINITY,
                    ));
                    owner.push(i);
                }
                _ => paths[i].alive = false,
            }
        }
        (rays, owner)
    }

    /// After G(k+1) is fetched: the throughput takes the BSDF weight at G(k),
    /// emission at G(k+1) towards G(k) is added (MIS-weighted against
    /// next-event estimation), a miss adds the environment, and Russian
    /// roulette may end the path.
    pub fn scatter(&self, buf: &mut ShadingBuffer, bounce: u32) {
        let env = self.environment;
        let ShadingBuffer {
            cur,
            next,
            scatter,
            paths,
            ..
        } = buf;
        paths.par_iter_mut().enumerate().for_each(|(i, path)| {
            if !path.alive {
                return;
            }
            let (Some(sc), Some(sp)) = (scatter[i].as_ref(), cur[i].as_ref()) else {
                path.alive = false;
                return;
            };
            path.throughput *= sc.weight;
            match next[i].as_ref() {
                None => {
                    path.radiance += path.throughput * env;
                    path.alive = false;
                    return;
                }
                Some(nx) => {
                    if nx.emission != Vec3::ZERO {
                        let w = if sc.delta {
                            1.0
                        } else {
                            let to = nx.p - sp.p;
                            let d2 = to.length_squared();
                            let cos_l = nx.ng.dot(-sc.dir).abs();
                            let pdf_light = if cos_l > 0.0 {
                                self.lights.pdf_area(self.scene, nx.prim) * d2 / cos_l
                            } else {
                                0.0
                            };
                            power_heuristic(sc.pdf, pdf_light)
                        };
                        path.radiance += path.throughput * nx.emission * w;
                    }
                }
            }
            if let Some(from) = self.roulette_from
                && bounce >= from
            {
                let q = path.throughput.max_element().min(0.95);
                let u = self.sampler(i).get(bounce, dim::ROULETTE);
                if !(u < q) {
                    path.alive = false;
                    return;
                }
                path.throughput /= q;
            }
        });
    }
}
