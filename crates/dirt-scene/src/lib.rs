//! dirt-scene: the scenes DIRT renders.
//!
//! A [`Scene`] is a flat list of world-space triangles plus per-triangle
//! material indices, optional per-vertex normals and texture coordinates,
//! and the materials, textures, cameras and punctual lights of the source.
//! Scenes come from glTF 2.0 (`.gltf`, `.glb`), Wavefront OBJ (`.obj`) or a
//! small set of deterministic procedural built-ins.
//!
//! ```
//! let scene = dirt_scene::open(dirt_scene::DEFAULT_SCENE).unwrap();
//! assert!(!scene.is_empty());
//! assert_eq!(scene.tri_material.len(), scene.len());
//! ```
//!
//! # Entry points
//!
//! * [`open`]`(spec)`: a built-in scene if `spec` is one of [`BUILTIN_NAMES`],
//!   else a file path given to [`load`].
//! * [`load`]`(path)`: by extension (case-insensitive): `.gltf`/`.glb` →
//!   glTF, `.obj` → OBJ, anything else → [`SceneError::UnsupportedExtension`].
//! * [`builtin`]`(name)`, [`builtin_scaled`]`(name, scale, offset)`,
//!   [`Scene::transformed`].
//! * [`open_animated`]`(spec)`, [`load_animated`]`(path)`: a scene that
//!   moves, [`AnimatedScene::pose`]`(t)` writing its triangles, normals,
//!   cameras and lights at time `t` (glTF node animation, skins, morph
//!   targets); anything else opens as a fixed [`AnimatedScene`].
//!
//! Loading never panics on any input: malformed files give a [`SceneError`]
//! naming the file and, for geometry problems, the mesh, primitive and
//! vertex or index. (As a last line of defence a panic inside a dependency
//! is caught and returned as [`SceneError::Internal`].) Problems that do not
//! prevent loading (skipped point/line primitives, missing `.mtl`, replaced
//! degenerate normals, ...) are collected in [`Scene::warnings`].
//!
//! # Data model
//!
//! * `triangles[i]`: triangle `i` in world space; `i` is the **primitive id**
//!   used everywhere else in DIRT (hits, buffers). Vertex order within a
//!   triangle is the source's (not flipped for mirroring transforms).
//! * `tri_material[i]`: index into `materials`.
//! * `tri_normals`: `Some` when at least one source primitive has normals;
//!   then every triangle has three unit world-space normals (transformed by
//!   the inverse-transpose of the node transform and re-normalised). Triangles
//!   whose source lacks normals, and normals that are zero or non-finite, get
//!   the geometric face normal `(v1 - v0) x (v2 - v0)` normalised (zero for a
//!   degenerate triangle). `None` when no primitive has normals.
//! * `tri_uvs`: the same rule for `TEXCOORD_0` (missing = `[0, 0]`). UVs
//!   follow the glTF convention: `(0, 0)` is the top-left of the image (OBJ
//!   `v` is flipped to `1 - v` on load).
//! * `materials`, `textures`, `cameras`, `lights`: see [`Material`],
//!   [`Texture`], [`Camera`], [`Light`].
//!
//! ## Material indices
//!
//! `materials[0]` is always [`Material::default`] (grey Lambertian, base
//! colour 0.8), used by every primitive without a material. Source material
//! `k` (glTF `materials[k]`, or the `k`-th material of the OBJ's `.mtl`
//! files in tobj's order) is `materials[k + 1]`. Texture `j` is glTF image
//! `j` (so `base_color_texture` is the glTF *image* index of the texture the
//! material references). OBJ texture maps are not loaded.
//!
//! # The flattened order (stable public contract)
//!
//! The primitive id of a triangle is its index in [`Scene::triangles`]:
//!
//! * **glTF**: the node hierarchy is walked depth-first, pre-order, starting
//!   from the root nodes of the scene in the order the scene lists them,
//!   visiting children in the order the node lists them. For each node the
//!   primitives of its mesh are taken in order; within a primitive the
//!   triangles are taken in index order:
//!   * `TRIANGLES`: `(i[3k], i[3k+1], i[3k+2])` (a trailing partial triangle
//!     is ignored with a warning);
//!   * `TRIANGLE_STRIP`: triangle `k` is `(i[k], i[k+1], i[k+2])` for even `k`
//!     and `(i[k], i[k+2], i[k+1])` for odd `k` (alternating winding, as the
//!     glTF specification defines it);
//!   * `TRIANGLE_FAN`: triangle `k` is `(i[k+1], i[k+2], i[0])` (glTF
//!     specification);
//!   * where a primitive has no indices, `i[n] = n`;
//!   * `POINTS`, `LINES`, `LINE_LOOP`, `LINE_STRIP` primitives contribute no
//!     triangles and add a warning. Degenerate triangles are kept.
//!
//!   The scene walked is the document's default scene (`"scene"`), else
//!   `scenes[0]`, else (no scenes at all) every node that is no other
//!   node's child, in node index order. A node reached twice (not a glTF
//!   tree, but not a cycle either) is instanced twice; a cycle is
//!   [`SceneError::RecursiveNodes`]. Node transforms compose as
//!   `global = parent_global * local`. [`load`] ignores animations, skins and
//!   morph targets (bind pose, base geometry); [`load_animated`] keeps them
//!   and poses the same triangles at any time (see [`AnimatedScene`]). Cameras and lights are listed in the same
//!   traversal order.
//!
//!   Validation is the `gltf` crate's, with two relaxations (each recorded
//!   as a warning): `POSITION` accessors without `min`/`max`, and a default
//!   `scene` index that names no scene. glTF 1.0 files are refused with
//!   [`SceneError::UnsupportedGltfVersion`].
//! * **OBJ**: models (objects/groups, split by material as tobj does) in
//!   file order, faces in file order; polygons are fan-triangulated by tobj
//!   into `(v0, v[k+1], v[k+2])`. Point (`p`) and line (`l`) elements are
//!   ignored. A missing or unreadable `.mtl` is a warning (all faces then
//!   use material 0).
//! * **Built-ins**: as documented per scene in [`builtin`].
//!
//! # Built-in scenes
//!
//! See [`BUILTIN_NAMES`] and [`builtin`]: `cornell` (the default, a closed
//! room with a ceiling light and a camera inside), `layers` (256 parallel
//! quads in depth), `foliage` (thin random triangles in a volume) and
//! `spheres` (an 8x8 field of UV spheres on a ground quad). They are
//! generated with a fixed-seed PRNG (no OS randomness), so they are
//! identical on every run; only `sin`/`cos` of the platform's maths library
//! could make the last bits differ between platforms.

mod animation;
mod builder;
mod builtin;
mod error;
mod gltf_loader;
mod model;
mod obj_loader;

use std::path::Path;

pub use animation::{AnimatedScene, ClipInfo, load_animated, load_animated_bytes, open_animated};
pub use builtin::{BUILTIN_NAMES, DEFAULT_SCENE, builtin, builtin_scaled};
pub use dirt_math::{Aabb, Triangle, Vec3};
pub use error::SceneError;
pub use glam::Mat4;
pub use model::{Camera, CameraKind, Light, LightKind, Material, Texture};

/// A renderable scene: world-space triangles in the flattened order (see the
/// [crate docs](crate#the-flattened-order-stable-public-contract)) and
/// everything needed to shade them.
///
/// All per-triangle vectors (`tri_material`, and `tri_normals` / `tri_uvs`
/// when `Some`) have exactly `triangles.len()` entries; see
/// [`validate`](Self::validate).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// World-space triangles; the index is the primitive id.
    pub triangles: Vec<Triangle>,
    /// Material index (into `materials`) per triangle.
    pub tri_material: Vec<u32>,
    /// Unit world-space per-vertex normals per triangle, `None` when the
    /// source has no normals at all (see the crate docs for the fill rule).
    pub tri_normals: Option<Vec<[[f32; 3]; 3]>>,
    /// `TEXCOORD_0` per vertex per triangle, `None` when the source has no
    /// texture coordinates at all (missing ones are `[0, 0]`).
    pub tri_uvs: Option<Vec<[[f32; 2]; 3]>>,
    /// Materials; index 0 is always the default material.
    pub materials: Vec<Material>,
    /// Decoded textures (glTF image `j` = `textures[j]`).
    pub textures: Vec<Texture>,
    /// Cameras in world space, in traversal order.
    pub cameras: Vec<Camera>,
    /// Punctual lights in world space, in traversal order.
    pub lights: Vec<Light>,
    /// Built-in name or the file stem.
    pub name: String,
    /// Non-fatal problems met while loading (skipped primitives, missing
    /// `.mtl`, replaced normals, ...).
    pub warnings: Vec<String>,
}

impl Scene {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the scene has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bounds of all triangles ([`Aabb::EMPTY`] for an empty scene).
    pub fn bounds(&self) -> Aabb {
        Aabb::of_triangles(&self.triangles)
    }

    /// The material of triangle `prim`, if both exist.
    pub fn material_of(&self, prim: usize) -> Option<&Material> {
        let m = *self.tri_material.get(prim)?;
        self.materials.get(m as usize)
    }

    /// A copy with every triangle, normal, camera and light transformed by
    /// `m` (normals by the inverse-transpose, re-normalised). The flattened
    /// order and vertex order are unchanged.
    pub fn transformed(&self, m: Mat4) -> Scene {
        let nm = model::normal_matrix(m);
        let triangles = self
            .triangles
            .iter()
            .map(|t| {
                Triangle::new(
                    m.transform_point3(t.vertex(0)),
                    m.transform_point3(t.vertex(1)),
                    m.transform_point3(t.vertex(2)),
                )
            })
            .collect();
        let tri_normals = self.tri_normals.as_ref().map(|ns| {
            ns.iter()
                .map(|n| n.map(|v| (nm * Vec3::from_array(v)).normalize_or_zero().to_array()))
                .collect()
        });
        Scene {
            triangles,
            tri_normals,
            cameras: self.cameras.iter().map(|c| c.transformed(m)).collect(),
            lights: self.lights.iter().map(|l| l.transformed(m)).collect(),
            ..self.clone()
        }
    }

    /// Checks the invariants every loader guarantees: per-triangle vectors
    /// as long as `triangles`, finite vertices, material and texture indices
    /// in range, a material 0, texture sizes consistent. Returns a
    /// description of the first violation.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.triangles.len();
        if self.tri_material.len() != n {
            return Err(format!(
                "tri_material has {} entries, triangles {n}",
                self.tri_material.len()
            ));
        }
        if let Some(ns) = &self.tri_normals
            && ns.len() != n
        {
            return Err(format!(
                "tri_normals has {} entries, triangles {n}",
                ns.len()
            ));
        }
        if let Some(uvs) = &self.tri_uvs
            && uvs.len() != n
        {
            return Err(format!("tri_uvs has {} entries, triangles {n}", uvs.len()));
        }
        if self.materials.is_empty() {
            return Err("no material 0".to_string());
        }
        if n >= dirt_math::INVALID_ID as usize {
            return Err(format!("{n} triangles do not fit in u32 primitive ids"));
        }
        if let Some(i) = self.triangles.iter().position(|t| !t.is_finite()) {
            return Err(format!("triangle {i} is not finite"));
        }
        if let Some(i) = self
            .tri_material
            .iter()
            .position(|&m| m as usize >= self.materials.len())
        {
            return Err(format!(
                "triangle {i} has material {} of {}",
                self.tri_material[i],
                self.materials.len()
            ));
        }
        for (i, m) in self.materials.iter().enumerate() {
            if let Some(t) = m.base_color_texture
                && t as usize >= self.textures.len()
            {
                return Err(format!(
                    "material {i} uses texture {t} of {}",
                    self.textures.len()
                ));
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            if t.rgba8.len() != t.width as usize * t.height as usize * 4 {
                return Err(format!(
                    "texture {i} has {} bytes for {}x{}",
                    t.rgba8.len(),
                    t.width,
                    t.height
                ));
            }
        }
        Ok(())
    }
}

/// Opens a scene by specification: a built-in scene if `spec` is exactly one
/// of [`BUILTIN_NAMES`], otherwise the file at path `spec` (see [`load`]).
///
/// A `spec` that is neither a built-in name nor an existing file and has no
/// extension gives [`SceneError::UnknownBuiltin`], listing the valid names.
pub fn open(spec: &str) -> Result<Scene, SceneError> {
    if let Some(scene) = builtin(spec) {
        return Ok(scene);
    }
    let path = Path::new(spec);
    if path.extension().is_none() && !path.exists() {
        return Err(SceneError::UnknownBuiltin {
            name: spec.to_string(),
            valid: BUILTIN_NAMES.join(", "),
        });
    }
    load(path)
}

/// Loads a scene file, choosing the loader by extension (case-insensitive):
/// `.gltf` and `.glb` (glTF 2.0; either container is accepted under either
/// extension), `.obj` (Wavefront OBJ with its `.mtl` materials).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let loader: fn(&Path) -> Result<Scene, SceneError> = match ext.as_str() {
        "gltf" | "glb" => gltf_loader::load_gltf,
        "obj" => obj_loader::load_obj,
        _ => {
            return Err(SceneError::UnsupportedExtension {
                path: path.to_path_buf(),
                extension: ext,
            });
        }
    };
    catch_panics(path, || loader(path))
}

/// A glTF 2.0 scene from its bytes in memory (a `.glb`, or a `.gltf` whose
/// buffers and images are `data:` URIs), as a web page gets a dropped file:
/// nothing is read from disk, and an external URI is
/// [`SceneError::BadResource`]. `name` names the scene and stands for the
/// path in errors. Never panics (as [`load`]).
pub fn load_gltf_bytes(name: &str, bytes: Vec<u8>) -> Result<Scene, SceneError> {
    catch_panics(Path::new(name), || {
        gltf_loader::load_gltf_bytes(name, bytes, false).map(|a| a.scene)
    })
}

/// Runs a loader, turning a panic inside it (a bug, here or in a
/// dependency) into [`SceneError::Internal`].
pub(crate) fn catch_panics<T>(
    path: &Path,
    loader: impl FnOnce() -> Result<T, SceneError>,
) -> Result<T, SceneError> {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(loader));
    match result {
        Ok(r) => r,
        Err(payload) => {
            let message = if let Some(s) = payload.downcast_ref::<&str>() {
                (*s).to_string()
            } else if let Some(s) = payload.downcast_ref::<String>() {
                s.clone()
            } else {
                "panic".to_string()
            };
            Err(SceneError::Internal {
                path: path.to_path_buf(),
                message,
            })
        }
    }
}

/// Reads a whole file, mapping errors to [`SceneError::NotFound`] /
/// [`SceneError::Io`].
/// Only regular files are read: a FIFO would block and a device such as
/// `/dev/zero` would never end.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    if !meta.is_file() {
        let e = std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a directory, device or pipe)",
        );
        return Err(io_error(path, e));
    }
    std::fs::read(path).map_err(|e| io_error(path, e))
}

pub(crate) fn io_error(path: &Path, e: std::io::Error) -> SceneError {
    if e.kind() == std::io::ErrorKind::NotFound {
        SceneError::NotFound {
            path: path.to_path_buf(),
        }
    } else {
        SceneError::Io {
            path: path.to_path_buf(),
            source: e,
        }
    }
}

/// The file stem as a scene name.
pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_and_scenes_are_send_sync() {
        fn check<T: Send + Sync + 'static>() {}
        check::<SceneError>();
        check::<Scene>();
    }

    #[test]
    fn validate_catches_broken_invariants() {
        let mut s = builtin("cornell").unwrap_or_default();
        assert_eq!(s.validate(), Ok(()));
        s.tri_material[3] = 99;
        assert!(s.validate().is_err());
        let mut s = builtin("layers").unwrap_or_default();
        s.tri_material.pop();
        assert!(s.validate().is_err());
        let mut s = builtin("layers").unwrap_or_default();
        s.triangles[0].v[1][2] = f32::NAN;
        assert!(s.validate().is_err());
    }
}
