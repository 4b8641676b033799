//! The lights of a scene: emissive triangles (area lights, chosen by power)
//! and `KHR_lights_punctual` point, spot and directional lights.

use dirt_math::{Triangle, Vec3};
use dirt_scene::{LightKind, Scene};

/// An emissive triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    pub prim: u32,
    pub area: f32,
}

/// A point on a light chosen for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSample {
    /// A point on emissive triangle `prim`; `pdf_area` includes the choice of the triangle.
    Area {
        prim: u32,
        point: Vec3,
        normal: Vec3,
        pdf_area: f32,
    },
    /// A punctual light: the radiance it brings is `intensity / d²` from
    /// `point` (point, spot) or `intensity` from direction `-dir` (directional);
    /// `pick` is the probability of choosing it.
    Point {
        /// Index into [`Lights::punctual`] (for the spot cone and range).
        index: usize,
        point: Vec3,
        intensity: Vec3,
        pick: f32,
    },
    Directional {
        dir: Vec3,
        irradiance: Vec3,
        pick: f32,
    },
}

/// The scene's lights with the sampling distribution over them.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub area: Vec<AreaLight>,
    /// Cumulative power of `area`, normalised to end at 1.
    cdf: Vec<f32>,
    /// Probability of an area light (given by power) within it.
    pub prob: Vec<f32>,
    /// `prob` of each primitive (0 for non-emitters), for MIS.
    prim_prob: Vec<f32>,
    pub punctual: Vec<dirt_scene::Light>,
    /// Probability of choosing the area lights rather than a punctual light.
    pub p_area: f32,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

fn area_of(t: &Triangle) -> f32 {
    0.5 * (t.vertex(1) - t.vertex(0))
        .cross(t.vertex(2) - t.vertex(0))
        .length()
}

impl Lights {
    pub fn new(scene: &Scene) -> Self {
        let mut area = Vec::new();
        let mut power = Vec::new();
        for (i, t) in scene.triangles.iter().enumerate() {
            let Some(m) = scene.material_of(i) else {
                continue;
            };
            let e = Vec3::from_array(m.emissive);
            let a = area_of(t);
            let p = luminance(e).max(e.max_element() * 1e-3) * a;
            if m.is_emissive() && a > 0.0 && p.is_finite() && p > 0.0 {
                area.push(AreaLight {
                    prim: i as u32,
                    area: a,
                });
                power.push(f64::from(p));
            }
        }
        let total: f64 = power.iter().sum();
        let mut acc = 0.0f64;
        let mut cdf = Vec::with_capacity(power.len());
        let mut prob = Vec::with_capacity(power.len());
        let mut prim_prob = vec![0.0f32; scene.triangles.len()];
        for (l, p) in area.iter().zip(&power) {
            acc += p;
            cdf.push((acc / total) as f32);
            let q = (p / total) as f32;
            prob.push(q);
            prim_prob[l.prim as usize] = q;
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let punctual: Vec<_> = scene
            .lights
            .iter()
            .filter(|l| {
                l.intensity.is_finite()
                    && l.intensity > 0.0
                    && l.position.is_finite()
                    && l.direction.is_finite()
            })
            .cloned()
            .collect();
        let p_area = match (area.is_empty(), punctual.is_empty()) {
            (false, false) => 0.5,
            (false, true) => 1.0,
            _ => 0.0,
        };
        Self {
            area,
            cdf,
            prob,
            prim_prob,
            punctual,
            p_area,
        }
    }

    /// Cumulative power of [`Lights::area`], ending at 1.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// The probability of area light `prim` among the area lights (0 for a non-emitter).
    pub fn prim_prob(&self, prim: u32) -> f32 {
        self.prim_prob.get(prim as usize).copied().unwrap_or(0.0)
    }

    pub fn is_empty(&self) -> bool {
        self.area.is_empty() && self.punctual.is_empty()
    }

    /// Area-measure pdf with which next-event estimation picks a point on
    /// emissive primitive `prim` (for MIS with BSDF sampling).
    pub fn pdf_area(&self, scene: &Scene, prim: u32) -> f32 {
        let q = self.prim_prob.get(prim as usize).copied().unwrap_or(0.0);
        if q == 0.0 {
            return 0.0;
        }
        let a = scene.triangles.get(prim as usize).map_or(0.0, area_of);
        if a > 0.0 { self.p_area * q / a } else { 0.0 }
    }

    /// Chooses a light and a point on it from three uniform numbers.
    pub fn sample(&self, scene: &Scene, u0: f32, u1: f32, u2: f32) -> Option<LightSample> {
        if self.is_empty() {
            return None;
        }
        if u0 < self.p_area {
            let x = u0 / self.p_area;
            let k = self
                .cdf
                .partition_point(|&c| c <= x)
                .min(self.area.len() - 1);
            let l = self.area[k];
            let t = scene.triangles.get(l.prim as usize)?;
            let (a, b, c) = (t.vertex(0), t.vertex(1), t.vertex(2));
            let su = u1.sqrt();
            let point = a * (1.0 - su) + b * (su * (1.0 - u2)) + c * (su * u2);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            return Some(LightSample::Area {
                prim: l.prim,
                point,
                normal,
                pdf_area: self.p_area * self.prob[k] / l.area,
            });
        }
        let n = self.punctual.len();
        let x = (u0 - self.p_area) / (1.0 - self.p_area);
        let i = ((x * n as f32) as usize).min(n - 1);
        let l = &self.punctual[i];
        let pick = (1.0 - self.p_area) / n as f32;
        let color = Vec3::from_array(l.color) * l.intensity;
        Some(match l.kind {
            LightKind::Directional => LightSample::Directional {
                dir: l.direction.normalize_or(Vec3::NEG_Y),
                irradiance: color,
                pick,
            },
            LightKind::Point | LightKind::Spot { .. } => LightSample::Point {
                index: i,
                point: l.position,
                intensity: color,
                pick,
            },
        })
    }

    /// The spot cone factor of a punctual light towards unit `to_point`
    /// (1 for point lights), with the smooth falloff of `KHR_lights_punctual`,
    /// and the range window.
    pub fn punctual_factor(light: &dirt_scene::Light, to_point: Vec3, dist: f32) -> f32 {
        let mut f = 1.0;
        if let LightKind::Spot {
            inner_cone,
            outer_cone,
        } = light.kind
        {
            let cos_outer = outer_cone.cos();
            let cos_inner = inner_cone.cos();
            let cd = light.direction.normalize_or(Vec3::NEG_Z).dot(to_point);
            let scale = 1.0 / (cos_inner - cos_outer).max(1e-4);
            let t = ((cd - cos_outer) * scale).clamp(0.0, 1.0);
            f *= t * t;
        }
        if let Some(r) = light.range
            && r > 0.0
        {
            let x = dist / r;
            let w = (1.0 - x * x * x * x).clamp(0.0, 1.0);
            f *= w * w;
        }
        f
    }
}
