//! Accumulates triangles and their per-triangle attributes in flattened order.

use dirt_math::{Triangle, Vec3};

use crate::{Material, Scene};

/// Builds a [`Scene`] one triangle at a time.
///
/// Normals and UVs are collected for every triangle (face normal / zero UVs
/// where the source has none) and dropped in [`finish`](Self::finish) when no
/// triangle had real ones, which implements the `None` rule of
/// [`Scene::tri_normals`] and [`Scene::tri_uvs`].
#[derive(Debug)]
pub(crate) struct SceneBuilder {
    pub scene: Scene,
    normals: Vec<[[f32; 3]; 3]>,
    uvs: Vec<[[f32; 2]; 3]>,
    any_normals: bool,
    any_uvs: bool,
}

impl SceneBuilder {
    /// An empty scene whose material 0 is [`Material::default`].
    pub fn new(name: &str) -> Self {
        Self {
            scene: Scene {
                name: name.to_string(),
                materials: vec![Material::default()],
                ..Scene::default()
            },
            normals: Vec::new(),
            uvs: Vec::new(),
            any_normals: false,
            any_uvs: false,
        }
    }

    /// Appends a material, returning its index.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.scene.materials.push(m);
        (self.scene.materials.len() - 1) as u32
    }

    /// Number of triangles so far.
    pub fn len(&self) -> usize {
        self.scene.triangles.len()
    }

    /// Appends one triangle.
    pub fn push(
        &mut self,
        tri: Triangle,
        material: u32,
        normals: Option<[[f32; 3]; 3]>,
        uvs: Option<[[f32; 2]; 3]>,
    ) {
        let normals = match normals {
            Some(n) => {
                self.any_normals = true;
                n
            }
            None => [face_normal(&tri).to_array(); 3],
        };
        let uvs = match uvs {
            Some(uv) => {
                self.any_uvs = true;
                uv
            }
            None => [[0.0; 2]; 3],
        };
        self.scene.triangles.push(tri);
        self.scene.tri_material.push(material);
        self.normals.push(normals);
        self.uvs.push(uvs);
    }

    /// Appends a warning to the scene.
    pub fn warn(&mut self, w: String) {
        self.scene.warnings.push(w);
    }

    pub fn finish(mut self) -> Scene {
        self.scene.tri_normals = self.any_normals.then_some(self.normals);
        self.scene.tri_uvs = self.any_uvs.then_some(self.uvs);
        self.scene
    }
}

/// The unit geometric normal `(v1 - v0) x (v2 - v0)`, or zero for a
/// degenerate triangle.
pub fn face_normal(t: &Triangle) -> Vec3 {
    let [a, b, c] = [t.vertex(0), t.vertex(1), t.vertex(2)];
    (b - a).cross(c - a).normalize_or_zero()
}
