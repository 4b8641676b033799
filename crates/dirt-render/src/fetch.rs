//! Stage `fetch`: material attributes gathered only for primitives that were
//! hit. Barycentric interpolation of the vertex normals and texture
//! coordinates, the base-colour texture lookup (bilinear, repeat) and the
//! material parameters, into a [`SurfacePoint`].

use dirt_math::{Hit, Ray, Vec3};
use dirt_scene::{Scene, Texture};
use glam::{Vec2, Vec4};

/// What shading needs of a hit point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub prim: u32,
    /// The hit point, from the barycentrics.
    pub p: Vec3,
    /// Unit geometric normal on the side the ray came from.
    pub ng: Vec3,
    /// Unit shading normal (interpolated), on the same side as `ng`.
    pub ns: Vec3,
    /// Whether the ray hit the front face (counter-clockwise winding).
    pub front: bool,
    pub uv: Vec2,
    /// Linear base colour (factor times texture).
    pub base: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    /// Emitted radiance leaving the front face (zero seen from the back).
    pub emission: Vec3,
}

/// A texture decoded to linear RGBA floats once per render (base colours are sRGB).
#[derive(Clone, Debug)]
pub struct LinearTexture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec4>,
}

fn srgb_to_linear(c: u8) -> f32 {
    let x = f32::from(c) / 255.0;
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

impl LinearTexture {
    pub fn from_srgb(t: &Texture) -> Self {
        let texels = t
            .rgba8
            .chunks_exact(4)
            .map(|p| {
                Vec4::new(
                    srgb_to_linear(p[0]),
                    srgb_to_linear(p[1]),
                    srgb_to_linear(p[2]),
                    f32::from(p[3]) / 255.0,
                )
            })
            .collect();
        Self {
            width: t.width,
            height: t.height,
            texels,
        }
    }

    fn texel(&self, x: i64, y: i64) -> Vec4 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let i = y.rem_euclid(h) * w + x.rem_euclid(w);
        self.texels.get(i as usize).copied().unwrap_or(Vec4::ONE)
    }

    /// Bilinear lookup with repeat wrapping; `(0, 0)` is the top-left corner.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        if self.width == 0 || self.height == 0 || !uv.is_finite() {
            return Vec4::ONE;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let b = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        a.lerp(b, fy)
    }
}

/// The scene data `fetch` reads.
///
/// Only what the render uses is prepared: textures are decoded only when a
/// material some triangle uses refers to them, and a geometry-only fetcher
/// (ambient occlusion needs positions and normals, 004 §4.1) decodes none
/// and reads no material.
#[derive(Debug)]
pub struct Fetcher<'s> {
    pub scene: &'s Scene,
    /// Indexed like `scene.textures`; `None` where the texture is not decoded.
    pub textures: Vec<Option<LinearTexture>>,
    /// Positions and normals only: no texture coordinates, materials or textures.
    pub geometry_only: bool,
}

/// Which textures the materials of the scene's triangles refer to.
pub fn used_textures(scene: &Scene) -> Vec<bool> {
    let mut used_material = vec![false; scene.materials.len()];
    for &m in &scene.tri_material {
        if let Some(u) = used_material.get_mut(m as usize) {
            *u = true;
        }
    }
    let mut used = vec![false; scene.textures.len()];
    for (m, _) in scene
        .materials
        .iter()
        .zip(&used_material)
        .filter(|(_, u)| **u)
    {
        if let Some(u) = m.base_color_texture.and_then(|t| used.get_mut(t as usize)) {
            *u = true;
        }
    }
    used
}

impl<'s> Fetcher<'s> {
    /// Everything shading reads, with the textures the scene's triangles use.
    pub fn new(scene: &'s Scene) -> Self {
        let used = used_textures(scene);
        Self {
            scene,
            textures: scene
                .textures
                .iter()
                .zip(used)
                .map(|(t, u)| u.then(|| LinearTexture::from_srgb(t)))
                .collect(),
            geometry_only: false,
        }
    }

    /// Positions and normals only (no textures decoded, no material read).
    pub fn geometry(scene: &'s Scene) -> Self {
        Self {
            scene,
            textures: Vec::new(),
            geometry_only: true,
        }
    }

    /// Textures decoded.
    pub fn decoded_textures(&self) -> usize {
        self.textures.iter().filter(|t| t.is_some()).count()
    }

    /// The surface point of `hit` on `ray`, or `None` for a miss. A
    /// geometry-only fetcher leaves the material fields at the default
    /// material's values and `uv` at zero.
    pub fn fetch(&self, ray: &Ray, hit: &Hit) -> Option<SurfacePoint> {
        if !hit.is_hit() {
            return None;
        }
        let s = self.scene;
        let prim = hit.prim as usize;
        let tri = s.triangles.get(prim)?;
        let (u, v) = (hit.u, hit.v);
        let w = 1.0 - u - v;
        let (a, b, c) = (tri.vertex(0), tri.vertex(1), tri.vertex(2));
        let p = a * w + b * u + c * v;
        let face = (b - a).cross(c - a).normalize_or_zero();
        let front = face.dot(ray.dir()) < 0.0;
        let ng = if front { face } else { -face };
        let mut ns = match &s.tri_normals {
            Some(ns) => {
                let n = ns[prim];
                (Vec3::from_array(n[0]) * w
                    + Vec3::from_array(n[1]) * u
                    + Vec3::from_array(n[2]) * v)
                    .normalize_or_zero()
            }
            None => ng,
        };
        if ns == Vec3::ZERO {
            ns = ng;
        }
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        if self.geometry_only {
            let m = dirt_scene::Material::default();
            return Some(SurfacePoint {
                prim: hit.prim,
                p,
                ng,
                ns,
                front,
                uv: Vec2::ZERO,
                base: Vec3::new(m.base_color[0], m.base_color[1], m.base_color[2]),
                metallic: m.metallic,
                roughness: m.roughness,
                emission: Vec3::ZERO,
            });
        }
        let uv = match &s.tri_uvs {
            Some(uvs) => {
                let t = uvs[prim];
                Vec2::from_array(t[0]) * w + Vec2::from_array(t[1]) * u + Vec2::from_array(t[2]) * v
            }
            None => Vec2::ZERO,
        };
        let m = s.material_of(prim)?;
        let mut base = Vec3::new(m.base_color[0], m.base_color[1], m.base_color[2]);
        if let Some(t) = m.base_color_texture
            && let Some(Some(tex)) = self.textures.get(t as usize)
        {
            base *= tex.sample(uv).truncate();
        }
        let emission = if front {
            Vec3::from_array(m.emissive)
        } else {
            Vec3::ZERO
        };
        Some(SurfacePoint {
            prim: hit.prim,
            p,
            ng,
            ns,
            front,
            uv,
            base: base.clamp(Vec3::ZERO, Vec3::ONE),
            metallic: m.metallic.clamp(0.0, 1.0),
            roughness: m.roughness.clamp(0.0, 1.0),
            emission,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_repeats_and_hits_texel_centres() {
        let t = Texture {
            width: 2,
            height: 1,
            rgba8: vec![255, 0, 0, 255, 0, 0, 255, 255],
        };
        let lt = LinearTexture::from_srgb(&t);
        let left = lt.sample(Vec2::new(0.25, 0.5));
        assert_eq!(left, Vec4::new(1.0, 0.0, 0.0, 1.0));
        let right = lt.sample(Vec2::new(1.75, 0.5));
        assert_eq!(right, Vec4::new(0.0, 0.0, 1.0, 1.0));
        let mid = lt.sample(Vec2::new(0.5, 0.5));
        assert!((mid.x - 0.5).abs() < 1e-6 && (mid.z - 0.5).abs() < 1e-6);
    }
}
