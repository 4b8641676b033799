//! Materials, textures, cameras and lights.

use glam::{Mat3, Mat4, Vec3};

/// A metallic-roughness material (the glTF 2.0 core model, reduced to what
/// DIRT renders).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the source file (may be empty).
    pub name: String,
    /// Linear RGBA base colour factor (multiplies the texture when there is one).
    pub base_color: [f32; 4],
    /// Index into [`Scene::textures`](crate::Scene::textures) of the base colour
    /// texture, sampled with [`Scene::tri_uvs`](crate::Scene::tri_uvs).
    pub base_color_texture: Option<u32>,
    /// Metalness in `[0, 1]`.
    pub metallic: f32,
    /// Perceptual roughness in `[0, 1]`.
    pub roughness: f32,
    /// Emitted radiance (linear RGB), already multiplied by
    /// `KHR_materials_emissive_strength`.
    pub emissive: [f32; 3],
    /// `KHR_materials_transmission` factor in `[0, 1]` (0 = opaque).
    pub transmission: f32,
}

impl Default for Material {
    /// Grey Lambertian: base colour 0.8, metallic 0, roughness 1, no emission.
    fn default() -> Self {
        Self {
            name: "default".to_string(),
            base_color: [0.8, 0.8, 0.8, 1.0],
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            transmission: 0.0,
        }
    }
}

impl Material {
    /// A Lambertian material of the given linear RGB colour.
    pub fn diffuse(name: &str, rgb: [f32; 3]) -> Self {
        Self {
            name: name.to_string(),
            base_color: [rgb[0], rgb[1], rgb[2], 1.0],
            ..Self::default()
        }
    }

    /// Whether the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emissive.iter().any(|&e| e > 0.0)
    }
}

/// A decoded texture: `width * height` pixels of RGBA8, rows top to bottom
/// (glTF UV `(0, 0)` is the top-left corner of the first row).
#[derive(Clone, PartialEq, Eq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba8: Vec<u8>,
}

impl std::fmt::Debug for Texture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Texture")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("rgba8", &format_args!("[{} bytes]", self.rgba8.len()))
            .finish()
    }
}

impl Texture {
    /// The RGBA8 texel at `(x, y)`, or `None` outside the image.
    pub fn texel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y as usize * self.width as usize + x as usize) * 4;
        let p = self.rgba8.get(i..i + 4)?;
        Some([p[0], p[1], p[2], p[3]])
    }
}

/// The projection of a [`Camera`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraKind {
    /// Perspective projection with vertical field of view
    /// [`Camera::yfov_radians`].
    Perspective,
    /// Orthographic projection; `xmag`/`ymag` are the half-width and
    /// half-height of the view volume.
    Orthographic { xmag: f32, ymag: f32 },
}

/// A camera in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Name from the source file (may be empty).
    pub name: String,
    /// Eye position.
    pub position: Vec3,
    /// Unit viewing direction (the node's -Z axis).
    pub forward: Vec3,
    /// Unit up vector (the node's +Y axis, made orthogonal to `forward`).
    pub up: Vec3,
    /// Vertical field of view in radians (0 for orthographic cameras).
    pub yfov_radians: f32,
    /// Width / height, when the source specifies it.
    pub aspect: Option<f32>,
    /// Near clipping distance.
    pub znear: f32,
    /// Far clipping distance (`None` = infinite).
    pub zfar: Option<f32>,
    pub kind: CameraKind,
}

impl Camera {
    /// A perspective camera at `position` looking at `target`.
    ///
    /// `up_hint` need not be orthogonal to the viewing direction; it must not
    /// be parallel to it (then +Z or +X is used instead).
    pub fn look_at(
        name: &str,
        position: Vec3,
        target: Vec3,
        up_hint: Vec3,
        yfov_radians: f32,
    ) -> Self {
        let forward = (target - position).normalize_or(Vec3::NEG_Z);
        let (forward, up) = orthonormal_up(forward, up_hint);
        Self {
            name: name.to_string(),
            position,
            forward,
            up,
            yfov_radians,
            aspect: None,
            znear: 0.01,
            zfar: None,
            kind: CameraKind::Perspective,
        }
    }

    /// The unit right vector (`forward x up`).
    pub fn right(&self) -> Vec3 {
        self.forward.cross(self.up).normalize_or_zero()
    }

    /// The camera transformed by `m` (position as a point, axes as directions,
    /// re-normalised). Field of view and orthographic extents are unchanged.
    pub fn transformed(&self, m: Mat4) -> Self {
        let forward = m.transform_vector3(self.forward).normalize_or(self.forward);
        let (forward, up) = orthonormal_up(forward, m.transform_vector3(self.up));
        Self {
            position: m.transform_point3(self.position),
            forward,
            up,
            ..self.clone()
        }
    }
}

/// `up` made orthogonal to unit `forward` and normalised, falling back to +Y,
/// +Z or +X when it is (nearly) parallel.
pub(crate) fn orthonormal_up(forward: Vec3, up: Vec3) -> (Vec3, Vec3) {
    for cand in [up, Vec3::Y, Vec3::Z, Vec3::X] {
        let u = cand - forward * cand.dot(forward);
        if u.length_squared() > 1e-12 && u.is_finite() {
            return (forward, u.normalize());
        }
    }
    (forward, Vec3::Y)
}

/// The kind of a punctual light (`KHR_lights_punctual`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Emits in all directions from [`Light::position`]; intensity in candela.
    Point,
    /// A cone around [`Light::direction`]; angles in radians from the axis.
    Spot { inner_cone: f32, outer_cone: f32 },
    /// Infinitely far away, shining along [`Light::direction`]; intensity in lux.
    Directional,
}

/// A punctual light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Name from the source file (may be empty).
    pub name: String,
    pub kind: LightKind,
    /// World position (the node's origin; meaningless for directional lights).
    pub position: Vec3,
    /// Unit direction the light shines in (the node's -Z axis).
    pub direction: Vec3,
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Candela (point, spot) or lux (directional).
    pub intensity: f32,
    /// Distance beyond which the light has no effect (`None` = infinite).
    pub range: Option<f32>,
}

impl Light {
    /// The light transformed by `m`.
    pub fn transformed(&self, m: Mat4) -> Self {
        Self {
            position: m.transform_point3(self.position),
            direction: m
                .transform_vector3(self.direction)
                .normalize_or(self.direction),
            ..self.clone()
        }
    }
}

/// The matrix that transforms normals for the point transform `m`
/// (inverse-transpose of its upper 3x3).
pub(crate) fn normal_matrix(m: Mat4) -> Mat3 {
    Mat3::from_mat4(m).inverse().transpose()
}
