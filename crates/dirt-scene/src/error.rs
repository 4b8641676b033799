//! The one error type of the crate.

use std::path::PathBuf;

/// Everything that can go wrong while opening or loading a scene.
///
/// Every variant that concerns a file carries its `path`; variants about a
/// piece of geometry carry a `location` such as `mesh 2 'Wheel' primitive 0`
/// (glTF) or `OBJ model 1 'Cube'` (OBJ), so the message says where to look.
/// Loading never panics: a file that cannot be turned into a [`Scene`]
/// yields one of these.
///
/// [`Scene`]: crate::Scene
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene file does not exist.
    #[error("scene file not found: {}", .path.display())]
    NotFound { path: PathBuf },

    /// The scene file exists but could not be read.
    #[error("cannot read {}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// The file name has no extension or one that no loader handles.
    #[error(
        "{}: unsupported scene file extension {extension:?} (supported: .gltf, .glb, .obj)",
        .path.display()
    )]
    UnsupportedExtension { path: PathBuf, extension: String },

    /// The glTF parser rejected the file (JSON/GLB syntax, schema validation,
    /// undecodable embedded data, ...).
    #[error("{}: cannot load glTF: {source}", .path.display())]
    Gltf {
        path: PathBuf,
        #[source]
        source: gltf::Error,
    },

    /// The file is glTF 1.x, which is not supported.
    #[error(
        "{}: glTF {version} is not supported; convert the file to glTF 2.0 (e.g. with Blender or gltf-pipeline)",
        .path.display()
    )]
    UnsupportedGltfVersion { path: PathBuf, version: String },

    /// An external buffer or image referenced by a glTF file does not exist.
    #[error(
        "{}: {what} not found at {} (external glTF resources are resolved relative to the .gltf file)",
        .path.display(),
        .resolved.display()
    )]
    MissingResource {
        path: PathBuf,
        what: String,
        resolved: PathBuf,
    },

    /// A glTF buffer, buffer view or image is unusable (bad URI, a view that
    /// reaches past the end of its buffer, ...).
    #[error("{}: {what}: {problem}", .path.display())]
    BadResource {
        path: PathBuf,
        what: String,
        problem: String,
    },

    /// A vertex index points past the end of the vertex arrays.
    #[error(
        "{}: {location}: index {index} (entry {position} of the index list) is out of range: \
         there are only {vertex_count} vertices",
        .path.display()
    )]
    IndexOutOfRange {
        path: PathBuf,
        location: String,
        index: u64,
        position: usize,
        vertex_count: usize,
    },

    /// A vertex attribute or index accessor has the wrong type, the wrong
    /// element count, or reaches outside its buffer.
    #[error("{}: {location}: {attribute}: {problem}", .path.display())]
    Accessor {
        path: PathBuf,
        location: String,
        attribute: String,
        problem: String,
    },

    /// A vertex position is NaN or infinite (in the file, or after applying
    /// the node transforms).
    #[error(
        "{}: {location}: vertex {vertex} has a non-finite position {value:?}",
        .path.display()
    )]
    NonFinite {
        path: PathBuf,
        location: String,
        vertex: usize,
        value: [f32; 3],
    },

    /// A node's global transform contains NaN or infinity.
    #[error("{}: {node}: transform is not finite", .path.display())]
    NonFiniteTransform { path: PathBuf, node: String },

    /// The glTF node hierarchy contains a cycle.
    #[error(
        "{}: node {node} is its own ancestor (glTF nodes must form a tree)",
        .path.display()
    )]
    RecursiveNodes { path: PathBuf, node: usize },

    /// An image could not be converted to RGBA8.
    #[error("{}: image {image}: {problem}", .path.display())]
    Texture {
        path: PathBuf,
        image: usize,
        problem: String,
    },

    /// The OBJ parser rejected the file.
    #[error("{}: invalid OBJ: {source}", .path.display())]
    Obj {
        path: PathBuf,
        #[source]
        source: tobj::LoadError,
    },

    /// An OBJ file that is not UTF-8 text (tobj would say only "read error").
    #[error(
        "{}: invalid OBJ: not UTF-8 text (first bad byte at offset {offset}{}); OBJ files are text",
        .path.display(),
        if *.utf16 { ", and it looks like UTF-16: convert it to UTF-8" } else { "" }
    )]
    ObjNotText {
        path: PathBuf,
        offset: usize,
        utf16: bool,
    },

    /// An OBJ model's arrays are inconsistent.
    #[error("{}: {location}: {problem}", .path.display())]
    ObjMesh {
        path: PathBuf,
        location: String,
        problem: String,
    },

    /// The scene exceeds a hard limit (e.g. more triangles than primitive
    /// ids can number, or a node hierarchy instanced too often).
    #[error("{}: scene too large: {problem}", .path.display())]
    TooLarge { path: PathBuf, problem: String },

    /// A glTF animation, skin or morph target is unusable (a sampler whose
    /// key and value counts disagree, a NaN or decreasing key, a joint index
    /// past the skin's joints, weights that do not sum to one, ...), or
    /// posing it gave a non-finite vertex.
    #[error("{}: {location}: {problem}", .path.display())]
    Animation {
        path: PathBuf,
        location: String,
        problem: String,
    },

    /// [`open`](crate::open) was given a name that is neither a built-in
    /// scene nor an existing file.
    #[error(
        "{name:?} is neither a built-in scene nor an existing file; \
         built-in scenes: {valid}; files: *.gltf, *.glb, *.obj"
    )]
    UnknownBuiltin { name: String, valid: String },

    /// A dependency (or this crate) panicked while loading. This is a bug;
    /// the panic was caught so that the caller gets an error instead.
    #[error(
        "{}: internal error while loading (a bug in dirt-scene or a dependency, please report it): {message}",
        .path.display()
    )]
    Internal { path: PathBuf, message: String },
}
