//! Parsing with lenient validation, and the checks that make malformed input
//! an error before it can reach code in `gltf` that would panic on it: glTF
//! 1.x detection, the GLB header length, images, cameras and `POSITION`
//! references that `gltf-json` does not validate, external URIs (scheme,
//! percent-decoding, existence) and buffer view bounds.

use std::path::{Path, PathBuf};

use crate::SceneError;

/// Parses and validates the document, leniently: a missing `min`/`max` on
/// `POSITION` accessors (required by the specification, omitted by some
/// exporters, unused here) and a default `scene` index that names no scene
/// only add warnings. glTF 1.0 files are recognised and refused by name.
pub(super) fn parse(
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
pub(super) fn check_external(
    path: &Path,
    base: Option<&Path>,
    doc: &gltf::Document,
) -> Result<(), SceneError> {
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
        let Some(base) = base else {
            return Err(bad(
                what,
                "an external resource, which a scene read from bytes cannot reach (pack it into a .glb or a data: URI)".into(),
            ));
        };
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
pub(super) fn check_views(path: &Path, doc: &gltf::Document) -> Result<(), SceneError> {
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
        assert_eq!(percent_decode("%zz%4").unwrap(), "%zz%4");
        assert_eq!(percent_decode("%C3%A9").unwrap(), "é");
        assert!(percent_decode("%FF").is_none());
        assert!(percent_decode("%C3").is_none());
    }
}
