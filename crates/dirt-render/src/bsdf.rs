//! The metallic-roughness BSDF of glTF, in three forms chosen from the
//! material: Lambertian (metallic 0, roughness 1), a perfect mirror (metallic
//! 1, roughness at most [`MIRROR_ROUGHNESS`]), otherwise a diffuse lobe
//! weighted by `(1 - metallic)(1 - F)` plus a GGX specular lobe (height-
//! correlated Smith visibility, Schlick Fresnel with `F0 = mix(0.04, base, metallic)`).

use crate::fetch::SurfacePoint;
use dirt_math::Vec3;
use std::f32::consts::PI;

/// Roughness at or below which a metal is a perfect mirror.
pub const MIRROR_ROUGHNESS: f32 = 0.02;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    Lambert {
        albedo: Vec3,
    },
    Mirror {
        f0: Vec3,
    },
    Microfacet {
        diffuse: Vec3,
        f0: Vec3,
        alpha: f32,
        p_spec: f32,
    },
}

/// A sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// `f · cos / pdf`.
    pub weight: Vec3,
    /// Solid-angle pdf (0 for a delta lobe).
    pub pdf: f32,
    pub delta: bool,
}

/// An orthonormal basis around unit `n` (Duff et al. 2017).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-distributed direction around `n`.
pub fn cosine_sample(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = basis(n);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3::ONE - f0) * m5
}

fn ggx_d(alpha: f32, noh: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = noh * noh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

fn smith_vis(alpha: f32, nov: f32, nol: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = nol * (nov * nov * (1.0 - a2) + a2).sqrt();
    let gl = nov * (nol * nol * (1.0 - a2) + a2).sqrt();
    let s = gv + gl;
    if s > 0.0 { 0.5 / s } else { 0.0 }
}

impl Bsdf {
    pub fn of(sp: &SurfacePoint) -> Self {
        if sp.metallic == 0.0 && sp.roughness >= 1.0 {
            return Bsdf::Lambert { albedo: sp.base };
        }
        let f0 = Vec3::splat(0.04).lerp(sp.base, sp.metallic);
        if sp.metallic >= 1.0 && sp.roughness <= MIRROR_ROUGHNESS {
            return Bsdf::Mirror { f0 };
        }
        let alpha = (sp.roughness * sp.roughness).max(1e-3);
        Bsdf::Microfacet {
            diffuse: sp.base * (1.0 - sp.metallic),
            f0,
            alpha,
            p_spec: 0.25 + 0.75 * sp.metallic,
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror { .. })
    }

    /// `f(wo, wi)` for unit `wo`, `wi` on the side of `n` (zero otherwise; zero for a mirror).
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let nol = n.dot(wi);
        let nov = n.dot(wo);
        if nol <= 0.0 || nov <= 0.0 {
            return Vec3::ZERO;
        }
        match *self {
            Bsdf::Lambert { albedo } => albedo / PI,
            Bsdf::Mirror { .. } => Vec3::ZERO,
            Bsdf::Microfacet {
                diffuse, f0, alpha, ..
            } => {
                let h = (wo + wi).normalize_or_zero();
                if h == Vec3::ZERO {
                    return Vec3::ZERO;
                }
                let voh = wo.dot(h).max(0.0);
                let f = schlick(f0, voh);
                let spec = f * (ggx_d(alpha, n.dot(h).max(0.0)) * smith_vis(alpha, nov, nol));
                let fd = schlick(Vec3::splat(0.04), voh);
                diffuse * (Vec3::ONE - fd) / PI + spec
            }
        }
    }

    /// Solid-angle pdf of [`sample`](Self::sample) choosing `wi` (0 for a mirror).
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let nol = n.dot(wi);
        if nol <= 0.0 || n.dot(wo) <= 0.0 {
            return 0.0;
        }
        match *self {
            Bsdf::Lambert { .. } => nol / PI,
            Bsdf::Mirror { .. } => 0.0,
            Bsdf::Microfacet { alpha, p_spec, .. } => {
                let h = (wo + wi).normalize_or_zero();
                let voh = wo.dot(h);
                let spec = if voh > 0.0 {
                    let noh = n.dot(h).max(0.0);
                    ggx_d(alpha, noh) * noh / (4.0 * voh)
                } else {
                    0.0
                };
                p_spec * spec + (1.0 - p_spec) * nol / PI
            }
        }
    }

    /// Samples `wi` given `wo` (unit, towards the previous point) and three
    /// uniform numbers. `None` when the sample leaves the hemisphere of `ng`
    /// or has no weight (the path ends; the estimator stays unbiased).
    pub fn sample(
        &self,
        n: Vec3,
        ng: Vec3,
        wo: Vec3,
        u_lobe: f32,
        u1: f32,
        u2: f32,
    ) -> Option<BsdfSample> {
        if n.dot(wo) <= 0.0 {
            return None;
        }
        let (wi, delta_weight) = match *self {
            Bsdf::Lambert { albedo } => {
                let wi = cosine_sample(n, u1, u2);
                (wi, Some(albedo))
            }
            Bsdf::Mirror { f0 } => {
                let wi = (n * (2.0 * n.dot(wo)) - wo).normalize();
                (wi, Some(schlick(f0, n.dot(wo))))
            }
            Bsdf::Microfacet { alpha, p_spec, .. } => {
                let wi = if u_lobe < p_spec {
                    let (t, b) = basis(n);
                    let phi = 2.0 * PI * u2;
                    let cos2 = (1.0 - u1) / (1.0 + (alpha * alpha - 1.0) * u1);
                    let cos = cos2.max(0.0).sqrt();
                    let sin = (1.0 - cos2).max(0.0).sqrt();
                    let h = (t * (sin * phi.cos()) + b * (sin * phi.sin()) + n * cos).normalize();
                    (h * (2.0 * h.dot(wo)) - wo).normalize()
                } else {
                    cosine_sample(n, u1, u2)
                };
                (wi, None)
            }
        };
        if !(wi.dot(ng) > 0.0 && wi.dot(n) > 0.0 && wi.is_finite()) {
            return None;
        }
        let (weight, pdf, delta) = match (delta_weight, self) {
            // Mirror: f·cos/pdf is the Fresnel term.
            (Some(w), Bsdf::Mirror { .. }) => (w, 0.0, true),
            // Lambert: f·cos/pdf = albedo exactly.
            (Some(w), _) => (w, n.dot(wi) / PI, false),
            (None, _) => {
                let pdf = self.pdf(n, wo, wi);
                if !(pdf > 0.0) {
                    return None;
                }
                (self.eval(n, wo, wi) * (n.dot(wi) / pdf), pdf, false)
            }
        };
        if !weight.is_finite() || weight == Vec3::ZERO {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Sampler;

    /// The sampled weights average to the directional albedo, estimated
    /// independently by uniform hemisphere integration of `eval`.
    #[test]
    fn sampling_matches_evaluation() {
        let n = Vec3::new(0.2, 0.9, 0.1).normalize();
        let wo = Vec3::new(0.5, 0.6, -0.3).normalize();
        for bsdf in [
            Bsdf::Lambert {
                albedo: Vec3::splat(0.7),
            },
            Bsdf::Microfacet {
                diffuse: Vec3::splat(0.5),
                f0: Vec3::splat(0.04),
                alpha: 0.3,
                p_spec: 0.25,
            },
            Bsdf::Microfacet {
                diffuse: Vec3::ZERO,
                f0: Vec3::new(0.9, 0.6, 0.3),
                alpha: 0.5,
                p_spec: 1.0,
            },
        ] {
            let count = 200_000;
            let mut sampled = 0.0f64;
            let mut uniform = 0.0f64;
            for i in 0..count {
                let s = Sampler::new(3, i, 0);
                if let Some(x) = bsdf.sample(n, n, wo, s.get(0, 0), s.get(0, 1), s.get(0, 2)) {
                    sampled += f64::from(x.weight.x);
                }
                // Uniform hemisphere direction.
                let (t, b) = basis(n);
                let z = s.get(1, 0);
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * s.get(1, 1);
                let wi = t * (r * phi.cos()) + b * (r * phi.sin()) + n * z;
                uniform += f64::from(bsdf.eval(n, wo, wi).x * z * 2.0 * PI);
            }
            let (a, b) = (sampled / f64::from(count), uniform / f64::from(count));
            assert!((a - b).abs() < 0.02 * b.max(0.05), "{bsdf:?}: {a} vs {b}");
        }
    }
}
