//! glTF 2.0 loading (`.gltf` and `.glb`).
//!
//! Parsing and validation, buffer loading and image decoding are done by the
//! `gltf` crate (`Gltf::from_slice`, `import_buffers`, `import_images`, the
//! pieces `gltf::import` is made of). Before handing URIs and buffer views to
//! it they are checked here, so that a missing file is reported by name and
//! malformed input cannot reach code in `gltf` that would panic on it.
//! Accessors are decoded here with bounds-checked arithmetic rather than
//! with `gltf`'s reader, which trusts offsets and component types.

use std::path::{Path, PathBuf};

use dirt_math::{Triangle, Vec3};
use glam::{Mat3, Mat4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use crate::builder::{SceneBuilder, face_normal};
use crate::model::{
    Camera, CameraKind, Light, LightKind, Material, Texture, normal_matrix, orthonormal_up,
};
use crate::{Scene, SceneError, read_file, stem};

/// Most node visits one traversal may make (guards against exponential
/// instancing through nodes shared by several parents).
const MAX_NODE_VISITS: usize = 1 << 20;

/// Largest number of components one accessor may decode to (1 GiB of f32);
/// only view-less (all-zero or sparse) accessors can claim more than their
/// buffer holds, and they are refused beyond this.
const MAX_ACCESSOR_COMPONENTS: usize = 1 << 28;

pub(crate) fn load_gltf(path: &Path) -> Result<Scene, SceneError> {
    let bytes = read_file(path)?;
    let gltf_err = |source| SceneError::Gltf {
        path: path.to_path_buf(),
        source,
    };
    let mut warnings = Vec::new();
    let (document, blob) = parse(path, &bytes, &mut warnings)?;
    drop(bytes);
    let base = path.parent().unwrap_or(Path::new(""));

    check_external(path, base, &document)?;
    let buffers = gltf::import_buffers(&document, Some(base), blob).map_err(gltf_err)?;
    check_views(path, &document)?;
    let images = gltf::import_images(&document, Some(base), &buffers).map_err(gltf_err)?;

    let mut ctx = Ctx {
        path,
        buffers: &buffers,
        b: SceneBuilder::new(&stem(path)),
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
    Ok(ctx.b.finish())
}

struct Ctx<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    b: SceneBuilder,
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

/// Parses and validates the document, leniently: a missing `min`/`max` on
/// `POSITION` accessors (required by the specification, omitted by some
/// exporters, unused here) and a default `scene` index that names no scene
/// only add warnings. glTF 1.0 files are recognised and refused by name.
fn parse(
    path: &Path,
    bytes: &[u8],
    warnings: &mut Vec<String>,
) -> Result<(gltf::Document, Option<Vec<u8>>), SceneError> {
    use gltf::json::validation::{Error as VError, Validate};

    if let Some(version) = gltf1_version(bytes) {
        return Err(SceneError::UnsupportedGltfVersion {
            path: path.to_path_buf(),
            version,
        });
    }
    if bytes.starts_with(b"glTF")
        && let Some(len) = bytes
            .get(8..12)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
        && len < 12
    {
        // gltf 1.4 subtracts the header size from this without a check.
        return Err(SceneError::BadResource {
            path: path.to_path_buf(),
            what: "GLB header".to_string(),
            problem: format!("declared file length {len} is shorter than the 12-byte header"),
        });
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|source| SceneError::Gltf {
            path: path.to_path_buf(),
            source,
        })?;
    let mut root = document.into_json();
    if let Some(scene) = root.scene
        && root.scenes.get(scene.value()).is_none()
    {
        warnings.push(format!(
            "default scene {} does not exist; ignored",
            scene.value()
        ));
        root.scene = None;
    }
    // Problems that gltf-json's validation does not catch but that make
    // gltf-json or gltf panic (in validation itself, or later in
    // `Image::source` / `Camera::projection`).
    let mut errors = Vec::new();
    let jpath = gltf::json::Path::new;
    for (i, image) in root.images.iter().enumerate() {
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            errors.push((
                jpath().field("images").index(i).field("mimeType"),
                VError::Missing,
            ));
        }
        if image.buffer_view.is_none() && image.uri.is_none() {
            errors.push((
                jpath().field("images").index(i).field("uri"),
                VError::Missing,
            ));
        }
    }
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::camera::Type;
        use gltf::json::validation::Checked;
        let missing = match camera.type_ {
            Checked::Valid(Type::Perspective) if camera.perspective.is_none() => {
                Some("perspective")
            }
            Checked::Valid(Type::Orthographic) if camera.orthographic.is_none() => {
                Some("orthographic")
            }
            _ => None,
        };
        if let Some(field) = missing {
            errors.push((
                jpath().field("cameras").index(i).field(field),
                VError::Missing,
            ));
        }
    }
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            let pos = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
            if let Some(acc) = prim.attributes.get(&pos)
                && acc.value() >= root.accessors.len()
            {
                let p = gltf::json::Path::new()
                    .field("meshes")
                    .index(mi)
                    .field("primitives")
                    .index(pi);
                errors.push((
                    p.field("attributes").key("POSITION"),
                    VError::IndexOutOfBounds,
                ));
            }
        }
    }
    if !errors.is_empty() {
        return Err(SceneError::Gltf {
            path: path.to_path_buf(),
            source: gltf::Error::Validation(errors),
        });
    }
    root.validate(&root, gltf::json::Path::new, &mut |p, e| {
        errors.push((p(), e))
    });
    let before = errors.len();
    errors.retain(|(p, e)| {
        let p = p.as_str();
        !(*e == VError::Missing
            && (p.ends_with("attributes[\"POSITION\"].min")
                || p.ends_with("attributes[\"POSITION\"].max")))
    });
    if errors.len() < before {
        warnings.push(
            "POSITION accessors without min/max (required by glTF 2.0) were accepted".to_string(),
        );
    }
    if errors.iter().any(|(_, e)| *e == VError::Unsupported) {
        // Say what matters (e.g. a required Draco extension) rather than
        // every consequence of not understanding it.
        errors.retain(|(_, e)| *e == VError::Unsupported);
    }
    if !errors.is_empty() {
        return Err(SceneError::Gltf {
            path: path.to_path_buf(),
            source: gltf::Error::Validation(errors),
        });
    }
    Ok((gltf::Document::from_json_without_validation(root), blob))
}

/// `Some(version)` when `bytes` is recognisably a glTF 1.x asset (binary
/// header version 1, or JSON whose `asset.version` starts with `1`).
fn gltf1_version(bytes: &[u8]) -> Option<String> {
    if bytes.starts_with(b"glTF") {
        let v = u32::from_le_bytes(bytes.get(4..8)?.try_into().ok()?);
        return (v == 1).then(|| "1.0".to_string());
    }
    let value: gltf::json::Value = gltf::json::deserialize::from_slice(bytes).ok()?;
    let version = value.get("asset")?.get("version")?;
    let v = match version {
        gltf::json::Value::String(s) => s.clone(),
        gltf::json::Value::Number(n) => n.to_string(),
        _ => return None,
    };
    v.starts_with('1').then_some(v)
}

// ---------------------------------------------------------------------------
// External resources

/// Checks every buffer and image URI before `gltf` reads it: relative paths
/// must percent-decode to UTF-8 (`gltf` would panic otherwise) and exist.
fn check_external(path: &Path, base: &Path, doc: &gltf::Document) -> Result<(), SceneError> {
    let bad = |what: String, problem: String| SceneError::BadResource {
        path: path.to_path_buf(),
        what,
        problem,
    };
    let mut uris: Vec<(String, &str)> = Vec::new();
    for buffer in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            uris.push((format!("buffer {}", buffer.index()), uri));
        }
    }
    for image in doc.images() {
        if let gltf::image::Source::Uri { uri, .. } = image.source() {
            uris.push((format!("image {}", image.index()), uri));
        }
    }
    for (what, uri) in uris {
        let what = format!("{what} (uri {:?})", shorten(uri));
        if uri.starts_with("data:") {
            continue;
        }
        let resolved: PathBuf = if let Some(rest) = uri
            .strip_prefix("file://")
            .or_else(|| uri.strip_prefix("file:"))
        {
            PathBuf::from(rest)
        } else if uri.contains(':') {
            return Err(bad(
                what,
                "unsupported URI scheme (only data: URIs and files are supported)".into(),
            ));
        } else {
            let decoded = percent_decode(uri)
                .ok_or_else(|| bad(what.clone(), "URI does not percent-decode to UTF-8".into()))?;
            base.join(decoded)
        };
        if !resolved.is_file() {
            return Err(SceneError::MissingResource {
                path: path.to_path_buf(),
                what,
                resolved,
            });
        }
    }
    Ok(())
}

/// Checks that every buffer view lies inside its buffer's data (the `gltf`
/// crate does not validate this and indexes without checks when decoding
/// images stored in buffer views).
fn check_views(path: &Path, doc: &gltf::Document) -> Result<(), SceneError> {
    for view in doc.views() {
        let buffer = view.buffer();
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|end| end > buffer.length()) {
            return Err(SceneError::BadResource {
                path: path.to_path_buf(),
                what: format!("buffer view {}", view.index()),
                problem: format!(
                    "bytes {}..{} lie outside buffer {} ({} bytes)",
                    view.offset(),
                    end.map_or_else(|| "overflow".to_string(), |e| e.to_string()),
                    buffer.index(),
                    buffer.length()
                ),
            });
        }
    }
    Ok(())
}

fn shorten(s: &str) -> String {
    if s.chars().count() > 64 {
        format!("{}...", s.chars().take(61).collect::<String>())
    } else {
        s.to_string()
    }
}

/// Percent-decodes `s` exactly like the `urlencoding` crate that `gltf` uses
/// (`%XX` with two hex digits is decoded, anything else is kept literally)
/// and returns `None` when the result is not UTF-8.
pub(crate) fn percent_decode(s: &str) -> Option<String> {
    fn hex(c: u8) -> Option<u8> {
        (c as char).to_digit(16).map(|d| d as u8)
    }
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while let Some(&c) = bytes.get(i) {
        if c == b'%'
            && let (Some(h), Some(l)) = (
                bytes.get(i + 1).and_then(|&c| hex(c)),
                bytes.get(i + 2).and_then(|&c| hex(c)),
            )
        {
            out.push(h << 4 | l);
            i += 3;
            continue;
        }
        out.push(c);
        i += 1;
    }
    String::from_utf8(out).ok()
}

// ---------------------------------------------------------------------------
// Images and materials

/// Converts any pixel format `gltf` decodes to RGBA8. Luminance formats
/// (`R8`, `R8G8` = luma + alpha) are expanded to grey; 16-bit channels are
/// rounded to 8 bits; float channels are clamped to `[0, 1]`.
pub(crate) fn convert_image(img: &gltf::image::Data) -> Result<Texture, String> {
    use gltf::image::Format;
    let (channels, bytes_per_channel) = match img.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let pixels = (img.width as usize)
        .checked_mul(img.height as usize)
        .ok_or_else(|| format!("{}x{} is too large", img.width, img.height))?;
    let expected = pixels * channels * bytes_per_channel;
    if img.pixels.len() != expected {
        return Err(format!(
            "{}x{} {:?} image has {} bytes of pixel data, expected {expected}",
            img.width,
            img.height,
            img.format,
            img.pixels.len()
        ));
    }
    let channel = |c: &[u8]| -> u8 {
        match *c {
            [v] => v,
            [a, b] => ((u16::from_ne_bytes([a, b]) as u32 * 255 + 32767) / 65535) as u8,
            [a, b, c, d] => {
                let f = f32::from_ne_bytes([a, b, c, d]);
                if f.is_nan() {
                    0
                } else {
                    (f.clamp(0.0, 1.0) * 255.0).round() as u8
                }
            }
            _ => 0,
        }
    };
    let mut rgba8 = Vec::with_capacity(pixels * 4);
    for px in img.pixels.chunks_exact(channels * bytes_per_channel) {
        let mut ch = px.chunks_exact(bytes_per_channel).map(channel);
        let mut next = || ch.next().unwrap_or(0);
        let rgba = match channels {
            1 => {
                let l = next();
                [l, l, l, 255]
            }
            2 => {
                let l = next();
                [l, l, l, next()]
            }
            3 => [next(), next(), next(), 255],
            _ => [next(), next(), next(), next()],
        };
        rgba8.extend_from_slice(&rgba);
    }
    Ok(Texture {
        width: img.width,
        height: img.height,
        rgba8,
    })
}

fn convert_material(m: &gltf::Material, b: &mut SceneBuilder) -> Material {
    let index = m.index().unwrap_or(0);
    let pbr = m.pbr_metallic_roughness();
    let base_color_texture = pbr.base_color_texture().map(|info| {
        if info.tex_coord() != 0 {
            b.warn(format!(
                "material {index}: base colour texture uses TEXCOORD_{}; only TEXCOORD_0 is loaded",
                info.tex_coord()
            ));
        }
        info.texture().source().index() as u32
    });
    let strength = m.emissive_strength().unwrap_or(1.0);
    Material {
        name: m.name().unwrap_or_default().to_string(),
        base_color: pbr.base_color_factor(),
        base_color_texture,
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        emissive: m.emissive_factor().map(|e| e * strength),
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
    }
}

// ---------------------------------------------------------------------------
// Node traversal

/// The root nodes to walk: the default scene's, else scene 0's, else every
/// node that is nobody's child.
fn root_nodes(doc: &gltf::Document, b: &mut SceneBuilder) -> Vec<usize> {
    if let Some(scene) = doc.default_scene() {
        return scene.nodes().map(|n| n.index()).collect();
    }
    let n_scenes = doc.scenes().len();
    if let Some(scene) = doc.scenes().next() {
        if n_scenes > 1 {
            b.warn(format!("no default scene; loading scene 0 of {n_scenes}"));
        }
        return scene.nodes().map(|n| n.index()).collect();
    }
    let mut is_child = vec![false; doc.nodes().len()];
    for node in doc.nodes() {
        for c in node.children() {
            if let Some(f) = is_child.get_mut(c.index()) {
                *f = true;
            }
        }
    }
    let roots: Vec<usize> = (0..is_child.len()).filter(|&i| !is_child[i]).collect();
    if !is_child.is_empty() {
        b.warn(format!("no scenes; loading all {} root nodes", roots.len()));
    }
    roots
}

enum Step {
    Enter(usize, Mat4),
    Exit(usize),
}

/// Depth-first pre-order walk with an explicit stack (no recursion, so deep
/// hierarchies cannot overflow the stack) and cycle detection.
fn traverse(ctx: &mut Ctx, doc: &gltf::Document, roots: &[usize]) -> Result<(), SceneError> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut on_path = vec![false; nodes.len()];
    let mut visits = 0usize;
    let mut stack: Vec<Step> = roots
        .iter()
        .rev()
        .map(|&r| Step::Enter(r, Mat4::IDENTITY))
        .collect();
    let mut warned_skin = false;

    while let Some(step) = stack.pop() {
        let (index, parent) = match step {
            Step::Exit(i) => {
                if let Some(f) = on_path.get_mut(i) {
                    *f = false;
                }
                continue;
            }
            Step::Enter(i, parent) => (i, parent),
        };
        let Some(node) = nodes.get(index) else {
            continue;
        };
        if on_path.get(index).copied().unwrap_or(false) {
            return Err(SceneError::RecursiveNodes {
                path: ctx.path.to_path_buf(),
                node: index,
            });
        }
        visits += 1;
        if visits > MAX_NODE_VISITS {
            return Err(SceneError::TooLarge {
                path: ctx.path.to_path_buf(),
                problem: format!(
                    "more than {MAX_NODE_VISITS} node instances (nodes shared by several parents?)"
                ),
            });
        }
        if let Some(f) = on_path.get_mut(index) {
            *f = true;
        }

        let global = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let label = node_label(node);
        let uses_transform =
            node.mesh().is_some() || node.camera().is_some() || node.light().is_some();
        if uses_transform && !global.is_finite() {
            return Err(SceneError::NonFiniteTransform {
                path: ctx.path.to_path_buf(),
                node: label,
            });
        }

        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() && !warned_skin {
                warned_skin = true;
                ctx.b.warn(
                    "skinning is ignored; skinned meshes are loaded in bind pose".to_string(),
                );
            }
            let nmat = normal_matrix(global);
            let mesh_label = match mesh.name() {
                Some(n) => format!("mesh {} '{n}'", mesh.index()),
                None => format!("mesh {}", mesh.index()),
            };
            for (pi, prim) in mesh.primitives().enumerate() {
                read_primitive(
                    ctx,
                    &format!("{mesh_label} primitive {pi}"),
                    &prim,
                    global,
                    nmat,
                )?;
            }
        }
        if let Some(camera) = node.camera() {
            add_camera(ctx, &camera, global, &label);
        }
        if let Some(light) = node.light() {
            add_light(ctx, &light, global, &label);
        }

        stack.push(Step::Exit(index));
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(children.into_iter().rev().map(|c| Step::Enter(c, global)));
    }
    Ok(())
}

fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("node {} '{n}'", node.index()),
        None => format!("node {}", node.index()),
    }
}

/// Node -Z as forward and +Y as up, or `None` for a degenerate transform.
fn node_frame(global: Mat4) -> Option<(Vec3, Vec3, Vec3)> {
    let position = global.transform_point3(Vec3::ZERO);
    let forward = global.transform_vector3(Vec3::NEG_Z).try_normalize()?;
    let (forward, up) = orthonormal_up(forward, global.transform_vector3(Vec3::Y));
    Some((position, forward, up))
}

fn add_camera(ctx: &mut Ctx, camera: &gltf::Camera, global: Mat4, label: &str) {
    let Some((position, forward, up)) = node_frame(global) else {
        ctx.b.warn(format!(
            "{label}: camera skipped, its transform is degenerate"
        ));
        return;
    };
    let name = camera.name().unwrap_or_default().to_string();
    let cam = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => Camera {
            name,
            position,
            forward,
            up,
            yfov_radians: p.yfov(),
            aspect: p.aspect_ratio(),
            znear: p.znear(),
            zfar: p.zfar(),
            kind: CameraKind::Perspective,
        },
        gltf::camera::Projection::Orthographic(o) => Camera {
            name,
            position,
            forward,
            up,
            yfov_radians: 0.0,
            aspect: None,
            znear: o.znear(),
            zfar: Some(o.zfar()),
            kind: CameraKind::Orthographic {
                xmag: o.xmag(),
                ymag: o.ymag(),
            },
        },
    };
    ctx.b.scene.cameras.push(cam);
}

fn add_light(ctx: &mut Ctx, light: &gltf::khr_lights_punctual::Light, global: Mat4, label: &str) {
    let Some((position, direction, _)) = node_frame(global) else {
        ctx.b.warn(format!(
            "{label}: light skipped, its transform is degenerate"
        ));
        return;
    };
    let kind = match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
        gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner_cone: inner_cone_angle,
            outer_cone: outer_cone_angle,
        },
    };
    ctx.b.scene.lights.push(Light {
        name: light.name().unwrap_or_default().to_string(),
        kind,
        position,
        direction,
        color: light.color(),
        intensity: light.intensity(),
        range: light.range(),
    });
}

// ---------------------------------------------------------------------------
// Primitives

/// Positions in the index list of the corners of triangle `k`, for the
/// triangle modes (see the crate docs for the order).
pub(crate) fn triangle_corners(mode: Mode, len: usize) -> Box<dyn Iterator<Item = [usize; 3]>> {
    match mode {
        Mode::Triangles => Box::new((0..len / 3).map(|k| [3 * k, 3 * k + 1, 3 * k + 2])),
        Mode::TriangleStrip => Box::new((0..len.saturating_sub(2)).map(|k| {
            if k % 2 == 0 {
                [k, k + 1, k + 2]
            } else {
                [k, k + 2, k + 1]
            }
        })),
        Mode::TriangleFan => Box::new((0..len.saturating_sub(2)).map(|k| [k + 1, k + 2, 0])),
        _ => Box::new(std::iter::empty()),
    }
}

fn read_primitive(
    ctx: &mut Ctx,
    location: &str,
    prim: &gltf::Primitive,
    global: Mat4,
    nmat: Mat3,
) -> Result<(), SceneError> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        ctx.b.warn(format!(
            "{location}: mode {mode:?} skipped (only triangle modes are loaded)"
        ));
        return Ok(());
    }
    let Some(pos_acc) = prim.get(&Semantic::Positions) else {
        ctx.b
            .warn(format!("{location}: no POSITION attribute, skipped"));
        return Ok(());
    };
    let positions = read_floats(ctx, &pos_acc, Dimensions::Vec3, location, "POSITION")?;
    let n = positions.len() / 3;
    let attribute = |ctx: &Ctx,
                     sem: Semantic,
                     dims: Dimensions,
                     name: &str|
     -> Result<Option<Vec<f32>>, SceneError> {
        let Some(acc) = prim.get(&sem) else {
            return Ok(None);
        };
        let values = read_floats(ctx, &acc, dims, location, name)?;
        if acc.count() != n {
            return Err(ctx.accessor_err(
                location,
                name,
                format!("has {} elements but POSITION has {n}", acc.count()),
            ));
        }
        Ok(Some(values))
    };
    let normals = attribute(ctx, Semantic::Normals, Dimensions::Vec3, "NORMAL")?;
    let uvs = attribute(ctx, Semantic::TexCoords(0), Dimensions::Vec2, "TEXCOORD_0")?;
    let indices: Option<Vec<u32>> = match prim.indices() {
        Some(acc) => Some(read_indices(ctx, &acc, location)?),
        None => None,
    };
    let len = indices.as_ref().map_or(n, Vec::len);
    if mode == Mode::Triangles && !len.is_multiple_of(3) {
        ctx.b.warn(format!(
            "{location}: {len} indices is not a multiple of 3; the last {} ignored",
            len % 3
        ));
    }
    let material = prim.material().index().map_or(0, |i| i as u32 + 1);

    let mut bad_normals = 0usize;
    let mut bad_uvs = 0usize;
    for corners in triangle_corners(mode, len) {
        let mut vidx = [0usize; 3];
        for (c, &pos) in corners.iter().enumerate() {
            let v = match &indices {
                Some(list) => list.get(pos).copied().unwrap_or(u32::MAX) as usize,
                None => pos,
            };
            if v >= n {
                return Err(SceneError::IndexOutOfRange {
                    path: ctx.path.to_path_buf(),
                    location: location.to_string(),
                    index: v as u64,
                    position: pos,
                    vertex_count: n,
                });
            }
            vidx[c] = v;
        }
        let mut world = [Vec3::ZERO; 3];
        for c in 0..3 {
            let v = vidx[c];
            let p = vec3_at(&positions, v);
            let w = global.transform_point3(p);
            if !p.is_finite() || !w.is_finite() {
                return Err(SceneError::NonFinite {
                    path: ctx.path.to_path_buf(),
                    location: location.to_string(),
                    vertex: v,
                    value: if p.is_finite() {
                        w.to_array()
                    } else {
                        p.to_array()
                    },
                });
            }
            world[c] = w;
        }
        let tri = Triangle::new(world[0], world[1], world[2]);
        let tri_normals = normals.as_ref().map(|ns| {
            let face = face_normal(&tri);
            vidx.map(|v| {
                let wn = (nmat * vec3_at(ns, v)).normalize_or_zero();
                if wn == Vec3::ZERO || !wn.is_finite() {
                    bad_normals += 1;
                    face.to_array()
                } else {
                    wn.to_array()
                }
            })
        });
        let tri_uvs = uvs.as_ref().map(|uv| {
            vidx.map(|v| {
                let t = [
                    uv.get(2 * v).copied().unwrap_or(0.0),
                    uv.get(2 * v + 1).copied().unwrap_or(0.0),
                ];
                if t.iter().all(|x| x.is_finite()) {
                    t
                } else {
                    bad_uvs += 1;
                    [0.0; 2]
                }
            })
        });
        if ctx.b.len() >= dirt_math::INVALID_ID as usize {
            return Err(SceneError::TooLarge {
                path: ctx.path.to_path_buf(),
                problem: format!("more than {} triangles", dirt_math::INVALID_ID),
            });
        }
        ctx.b.push(tri, material, tri_normals, tri_uvs);
    }
    if bad_normals > 0 {
        ctx.b.warn(format!(
            "{location}: {bad_normals} zero or non-finite normals replaced by face normals"
        ));
    }
    if bad_uvs > 0 {
        ctx.b.warn(format!(
            "{location}: {bad_uvs} non-finite texture coordinates replaced by 0"
        ));
    }
    Ok(())
}

fn vec3_at(values: &[f32], i: usize) -> Vec3 {
    match values.get(3 * i..3 * i + 3) {
        Some(&[x, y, z]) => Vec3::new(x, y, z),
        _ => Vec3::ZERO,
    }
}

// ---------------------------------------------------------------------------
// Accessors

/// Reads a float attribute (`dims` components per element) as `f32`,
/// accepting float components and (normalised or not) integer ones
/// (`KHR_mesh_quantization` style).
fn read_floats(
    ctx: &Ctx,
    acc: &gltf::Accessor,
    dims: Dimensions,
    location: &str,
    attribute: &str,
) -> Result<Vec<f32>, SceneError> {
    if acc.dimensions() != dims {
        return Err(ctx.accessor_err(
            location,
            attribute,
            format!(
                "accessor {} has type {:?}, expected {dims:?}",
                acc.index(),
                acc.dimensions()
            ),
        ));
    }
    let raw =
        read_accessor(ctx.buffers, acc).map_err(|p| ctx.accessor_err(location, attribute, p))?;
    let dt = acc.data_type();
    let norm = acc.normalized();
    Ok(raw
        .into_iter()
        .map(|v| match (dt, norm) {
            (DataType::U8, true) => (v / 255.0) as f32,
            (DataType::U16, true) => (v / 65535.0) as f32,
            (DataType::U32, true) => (v / 4294967295.0) as f32,
            (DataType::I8, true) => (v / 127.0).max(-1.0) as f32,
            (DataType::I16, true) => (v / 32767.0).max(-1.0) as f32,
            _ => v as f32,
        })
        .collect())
}

/// Reads an index accessor (scalar `u8`/`u16`/`u32`).
fn read_indices(ctx: &Ctx, acc: &gltf::Accessor, location: &str) -> Result<Vec<u32>, SceneError> {
    let err = |p| ctx.accessor_err(location, "indices", p);
    if acc.dimensions() != Dimensions::Scalar {
        return Err(err(format!(
            "accessor {} has type {:?}, expected Scalar",
            acc.index(),
            acc.dimensions()
        )));
    }
    if !matches!(
        acc.data_type(),
        DataType::U8 | DataType::U16 | DataType::U32
    ) {
        return Err(err(format!(
            "accessor {} has component type {:?}, expected U8, U16 or U32",
            acc.index(),
            acc.data_type()
        )));
    }
    let raw = read_accessor(ctx.buffers, acc).map_err(err)?;
    Ok(raw.into_iter().map(|v| v as u32).collect())
}

fn component_size(dt: DataType) -> usize {
    match dt {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Decodes one little-endian component (exactly representable in `f64`).
fn component(bytes: &[u8], off: usize, dt: DataType) -> Option<f64> {
    let b = |n: usize| bytes.get(off..off.checked_add(n)?);
    Some(match dt {
        DataType::I8 => i8::from_le_bytes(b(1)?.try_into().ok()?) as f64,
        DataType::U8 => u8::from_le_bytes(b(1)?.try_into().ok()?) as f64,
        DataType::I16 => i16::from_le_bytes(b(2)?.try_into().ok()?) as f64,
        DataType::U16 => u16::from_le_bytes(b(2)?.try_into().ok()?) as f64,
        DataType::U32 => u32::from_le_bytes(b(4)?.try_into().ok()?) as f64,
        DataType::F32 => f32::from_le_bytes(b(4)?.try_into().ok()?) as f64,
    })
}

/// The bytes of a buffer view.
fn view_bytes<'b>(
    buffers: &'b [gltf::buffer::Data],
    view: &gltf::buffer::View,
) -> Result<&'b [u8], String> {
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer {} not loaded", view.buffer().index()))?;
    let start = view.offset();
    let end = start.checked_add(view.length());
    end.and_then(|end| data.get(start..end)).ok_or_else(|| {
        format!(
            "buffer view {} (offset {}, length {}) exceeds buffer {} ({} bytes)",
            view.index(),
            start,
            view.length(),
            view.buffer().index(),
            data.len()
        )
    })
}

/// Reads `count` elements of `n` components of type `dt` starting at
/// `offset` with `stride` from `bytes`, appending them to `out` (or, with
/// `targets`, writing element `k` at element position `targets[k]`).
fn read_elements(
    bytes: &[u8],
    offset: usize,
    stride: usize,
    count: usize,
    n: usize,
    dt: DataType,
    mut sink: impl FnMut(usize, usize, f64),
) -> Result<(), String> {
    let elem = n * component_size(dt);
    if count == 0 {
        return Ok(());
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem))
        .ok_or_else(|| "element range overflows".to_string())?;
    if end > bytes.len() {
        return Err(format!(
            "{count} elements of {elem} bytes (stride {stride}, offset {offset}) need {end} bytes, \
             the buffer view has {}",
            bytes.len()
        ));
    }
    for k in 0..count {
        let base = offset + k * stride;
        for c in 0..n {
            let v = component(bytes, base + c * component_size(dt), dt)
                .ok_or("read past the end of the buffer view")?;
            sink(k, c, v);
        }
    }
    Ok(())
}

/// Decodes an accessor (including sparse substitution) to `count * n`
/// components, with every offset, stride and index checked.
fn read_accessor(buffers: &[gltf::buffer::Data], acc: &gltf::Accessor) -> Result<Vec<f64>, String> {
    let dims = acc.dimensions();
    if matches!(dims, Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4) {
        return Err(format!(
            "accessor {}: matrix accessors are not supported here",
            acc.index()
        ));
    }
    let n = dims.multiplicity();
    let dt = acc.data_type();
    let elem = n * component_size(dt);
    let count = acc.count();
    let total = count
        .checked_mul(n)
        .filter(|&t| t <= MAX_ACCESSOR_COMPONENTS)
        .ok_or_else(|| format!("accessor {}: count {count} is too large", acc.index()))?;
    let ctx = |e: String| format!("accessor {}: {e}", acc.index());

    let mut out = vec![0.0f64; 0];
    if let Some(view) = acc.view() {
        let bytes = view_bytes(buffers, &view).map_err(ctx)?;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(ctx(format!(
                "byte stride {stride} is smaller than the element size {elem}"
            )));
        }
        out.reserve_exact(total);
        read_elements(bytes, acc.offset(), stride, count, n, dt, |_, _, v| {
            out.push(v)
        })
        .map_err(ctx)?;
    } else {
        out = vec![0.0; total];
    }

    if let Some(sparse) = acc.sparse() {
        let sc = sparse.count();
        if sc > count {
            return Err(ctx(format!(
                "sparse count {sc} exceeds accessor count {count}"
            )));
        }
        let idx = sparse.indices();
        let idx_dt = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let idx_bytes = view_bytes(buffers, &idx.view()).map_err(ctx)?;
        let mut targets = Vec::with_capacity(sc);
        read_elements(
            idx_bytes,
            idx.offset(),
            component_size(idx_dt),
            sc,
            1,
            idx_dt,
            |_, _, v| targets.push(v as usize),
        )
        .map_err(|e| ctx(format!("sparse indices: {e}")))?;
        if let Some(&bad) = targets.iter().find(|&&t| t >= count) {
            return Err(ctx(format!(
                "sparse index {bad} is out of range (count {count})"
            )));
        }
        let vals = sparse.values();
        let val_bytes = view_bytes(buffers, &vals.view()).map_err(ctx)?;
        let mut bad_slot = false;
        read_elements(
            val_bytes,
            vals.offset(),
            elem,
            sc,
            n,
            dt,
            |k, c, v| match targets.get(k).and_then(|&t| out.get_mut(t * n + c)) {
                Some(slot) => *slot = v,
                None => bad_slot = true,
            },
        )
        .map_err(|e| ctx(format!("sparse values: {e}")))?;
        if bad_slot {
            return Err(ctx("sparse substitution out of range".to_string()));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use gltf::image::{Data, Format};

    #[test]
    fn strip_and_fan_corners() {
        let strip: Vec<_> = triangle_corners(Mode::TriangleStrip, 5).collect();
        assert_eq!(strip, vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        let fan: Vec<_> = triangle_corners(Mode::TriangleFan, 5).collect();
        assert_eq!(fan, vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        let tris: Vec<_> = triangle_corners(Mode::Triangles, 7).collect();
        assert_eq!(tris, vec![[0, 1, 2], [3, 4, 5]]);
        for mode in [Mode::TriangleStrip, Mode::TriangleFan, Mode::Triangles] {
            assert_eq!(triangle_corners(mode, 2).count(), 0);
            assert_eq!(triangle_corners(mode, 0).count(), 0);
        }
        assert_eq!(triangle_corners(Mode::Lines, 6).count(), 0);
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
        assert_eq!(percent_decode("%zz%4").unwrap(), "%zz%4");
        assert_eq!(percent_decode("%C3%A9").unwrap(), "é");
        assert!(percent_decode("%FF").is_none());
        assert!(percent_decode("%C3").is_none());
    }

    fn img(format: Format, pixels: Vec<u8>) -> Data {
        Data {
            pixels,
            format,
            width: 2,
            height: 1,
        }
    }

    #[test]
    fn every_image_format_becomes_rgba8() {
        let cases: Vec<(Data, [u8; 8])> = vec![
            (
                img(Format::R8, vec![10, 20]),
                [10, 10, 10, 255, 20, 20, 20, 255],
            ),
            (
                img(Format::R8G8, vec![10, 1, 20, 2]),
                [10, 10, 10, 1, 20, 20, 20, 2],
            ),
            (
                img(Format::R8G8B8, vec![1, 2, 3, 4, 5, 6]),
                [1, 2, 3, 255, 4, 5, 6, 255],
            ),
            (
                img(Format::R8G8B8A8, vec![1, 2, 3, 4, 5, 6, 7, 8]),
                [1, 2, 3, 4, 5, 6, 7, 8],
            ),
            (
                img(
                    Format::R16,
                    [0u16, 65535].iter().flat_map(|v| v.to_ne_bytes()).collect(),
                ),
                [0, 0, 0, 255, 255, 255, 255, 255],
            ),
            (
                img(
                    Format::R16G16,
                    [257u16, 0, 32896, 65535]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [1, 1, 1, 0, 128, 128, 128, 255],
            ),
            (
                img(
                    Format::R16G16B16,
                    [0u16, 257, 514, 65535, 65535, 0]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 1, 2, 255, 255, 255, 0, 255],
            ),
            (
                img(
                    Format::R16G16B16A16,
                    [0u16, 257, 514, 771, 1, 2, 3, 4]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 1, 2, 3, 0, 0, 0, 0],
            ),
            (
                img(
                    Format::R32G32B32FLOAT,
                    [0.0f32, 0.5, 1.0, -1.0, 2.0, f32::NAN]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 128, 255, 255, 0, 255, 0, 255],
            ),
            (
                img(
                    Format::R32G32B32A32FLOAT,
                    [1.0f32, 0.0, 0.0, 0.25, 0.0, 1.0, 0.0, 1.0]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [255, 0, 0, 64, 0, 255, 0, 255],
            ),
        ];
        for (data, want) in cases {
            let t = convert_image(&data).unwrap();
            assert_eq!((t.width, t.height), (2, 1));
            assert_eq!(t.rgba8, want, "{:?}", data.format);
        }
        // Wrong byte count.
        assert!(convert_image(&img(Format::R8G8B8, vec![1, 2, 3])).is_err());
    }
}
