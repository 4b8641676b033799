//! glTF 2.0 loading (`.gltf` and `.glb`).
//!
//! Parsing and validation, buffer loading and image decoding are done by the
//! `gltf` crate (`Gltf::from_slice`, `import_buffers`, `import_images`, the
//! pieces `gltf::import` is made of). Before handing URIs and buffer views to
//! it they are checked here, so that a missing file is reported by name and
//! malformed input cannot reach code in `gltf` that would panic on it.
//! Accessors are decoded here with bounds-checked arithmetic rather than
//! with `gltf`'s reader, which trusts offsets and component types.
//!
//! The loader is split by concern:
//!
//! * this module: the entry point [`load_gltf`], which reads the file and
//!   runs the steps below in order, and the loading context [`Ctx`];
//! * [`validation`]: parsing with lenient validation, and the checks of
//!   external URIs and buffer views made before `gltf` touches them;
//! * [`materials`]: image decoding to RGBA8 and material conversion;
//! * [`nodes`]: the node hierarchy walk (root nodes, transforms, cycle and
//!   size limits), cameras and `KHR_lights_punctual` lights;
//! * [`primitives`]: mesh primitives to world-space triangles (triangle
//!   modes, index resolution, normals and texture coordinates);
//! * [`accessors`]: bounds-checked decoding of accessors, buffer views and
//!   sparse substitution;
//! * [`rig`]: for [`load_gltf_animated`], what the walk records of each mesh
//!   instance, camera and light, and the nodes, skins, morph targets and
//!   animation clips an [`AnimatedScene`] poses with.

mod accessors;
mod materials;
mod nodes;
mod primitives;
mod rig;
mod validation;

use std::path::Path;

use crate::builder::SceneBuilder;
use crate::{AnimatedScene, Scene, SceneError, read_file, stem};

use materials::{convert_image, convert_material};
pub(crate) use nodes::node_frame;
use nodes::{root_nodes, traverse};
use rig::Recorder;
use validation::{check_external, check_views, parse};

pub(crate) fn load_gltf(path: &Path) -> Result<Scene, SceneError> {
    load(path, false).map(|a| a.scene)
}

/// Loads a glTF file with what it takes to pose it (see [`AnimatedScene`]).
pub(crate) fn load_gltf_animated(path: &Path) -> Result<AnimatedScene, SceneError> {
    load(path, true)
}

fn load(path: &Path, animated: bool) -> Result<AnimatedScene, SceneError> {
    let bytes = read_file(path)?;
    let base = path.parent().unwrap_or(Path::new(""));
    from_bytes(path, bytes, Some(base), animated)
}

/// A glTF (GLB, or JSON with `data:` URIs) from bytes in memory; `name` stands
/// for the path in the scene's name and errors. Nothing is read from disk.
pub(crate) fn load_gltf_bytes(
    name: &str,
    bytes: Vec<u8>,
    animated: bool,
) -> Result<AnimatedScene, SceneError> {
    from_bytes(Path::new(name), bytes, None, animated)
}

/// The loader over a file's bytes: `base` is the folder external URIs are
/// resolved against, `None` when there is none (bytes in memory).
fn from_bytes(
    path: &Path,
    bytes: Vec<u8>,
    base: Option<&Path>,
    animated: bool,
) -> Result<AnimatedScene, SceneError> {
    let gltf_err = |source| SceneError::Gltf {
        path: path.to_path_buf(),
        source,
    };
    let mut warnings = Vec::new();
    let (document, blob) = parse(path, &bytes, &mut warnings)?;
    drop(bytes);

    check_external(path, base, &document)?;
    let buffers = gltf::import_buffers(&document, base, blob).map_err(gltf_err)?;
    check_views(path, &document)?;
    let images = gltf::import_images(&document, base, &buffers).map_err(gltf_err)?;

    let mut ctx = Ctx {
        path,
        buffers: &buffers,
        b: SceneBuilder::new(&stem(path)),
        rig: animated.then(Recorder::default),
    };
    ctx.b.scene.warnings = warnings;

    for (i, image) in images.iter().enumerate() {
        let tex = convert_image(image).map_err(|problem| SceneError::Texture {
            path: path.to_path_buf(),
            image: i,
            problem,
        })?;
        ctx.b.scene.textures.push(tex);
    }
    drop(images);

    for m in document.materials() {
        let mat = convert_material(&m, &mut ctx.b);
        ctx.b.add_material(mat);
    }

    let roots = root_nodes(&document, &mut ctx.b);
    traverse(&mut ctx, &document, &roots)?;
    match ctx.rig.take() {
        Some(recorder) => {
            let rig = rig::build(&ctx, &document, recorder)?;
            let scene = ctx.b.finish();
            match rig {
                Some(rig) => AnimatedScene::rigged(scene, rig),
                None => Ok(AnimatedScene::fixed(scene)),
            }
        }
        None => Ok(AnimatedScene::fixed(ctx.b.finish())),
    }
}

struct Ctx<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    b: SceneBuilder,
    /// What the walk records for posing, when loading an animated scene.
    rig: Option<Recorder>,
}

impl Ctx<'_> {
    fn accessor_err(&self, location: &str, attribute: &str, problem: String) -> SceneError {
        SceneError::Accessor {
            path: self.path.to_path_buf(),
            location: location.to_string(),
            attribute: attribute.to_string(),
            problem,
        }
    }
}
