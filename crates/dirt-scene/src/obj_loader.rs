//! Wavefront OBJ loading (via `tobj`).

use std::cell::RefCell;
use std::io::Read;
use std::path::Path;

use dirt_math::{Triangle, Vec3};

use crate::builder::SceneBuilder;
use crate::{Material, Scene, SceneError, read_file, stem};

/// Largest `.mtl` file read. Material libraries are small; the bound keeps a
/// hostile `mtllib` line from exhausting memory.
const MAX_MTL_BYTES: u64 = 64 << 20;

/// Reads a material library named by an OBJ file: only regular files (a FIFO
/// would block on open, `/dev/zero` never ends) and at most [`MAX_MTL_BYTES`].
fn read_mtl(path: &Path) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".to_string());
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    file.take(MAX_MTL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_MTL_BYTES {
        return Err(format!("larger than {MAX_MTL_BYTES} bytes"));
    }
    Ok(bytes)
}

pub(crate) fn load_obj(path: &Path) -> Result<Scene, SceneError> {
    // Read here rather than by tobj: it reports only "open file failed", and
    // this refuses devices and pipes by name.
    let bytes = read_file(path)?;
    if let Err(e) = std::str::from_utf8(&bytes) {
        // A byte-order mark or NULs between ASCII letters: UTF-16.
        let utf16 = bytes.starts_with(&[0xfe, 0xff])
            || bytes.starts_with(&[0xff, 0xfe])
            || bytes.iter().take(64).filter(|&&b| b == 0).count() >= 16;
        return Err(SceneError::ObjNotText {
            path: path.to_path_buf(),
            offset: e.valid_up_to(),
            utf16,
        });
    }
    let base = path.parent().unwrap_or(Path::new(""));
    let mtl_problems = RefCell::new(Vec::new());
    let material_loader = |mtl: &Path| -> tobj::MTLLoadResult {
        // Resolved as tobj's own `load_obj` does: relative to the OBJ file.
        let full = base.join(mtl);
        match read_mtl(&full) {
            Ok(b) => tobj::load_mtl_buf(&mut &b[..]),
            Err(problem) => {
                mtl_problems
                    .borrow_mut()
                    .push(format!("{}: {problem}", full.display()));
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    // `..Default::default()` covers the fields tobj's optional features add
    // when another crate in the build enables them.
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut &bytes[..], &opts, material_loader).map_err(|source| {
            SceneError::Obj {
                path: path.to_path_buf(),
                source,
            }
        })?;
    drop(bytes);

    let mut b = SceneBuilder::new(&stem(path));
    for problem in mtl_problems.into_inner() {
        b.warn(format!("material library {problem}; skipped"));
    }
    let n_mats = match materials {
        Ok(mats) => {
            let n = mats.len();
            let mut textured = false;
            for m in mats {
                textured |= m.diffuse_texture.is_some();
                b.add_material(convert_material(m));
            }
            if textured {
                b.warn("OBJ texture maps (map_Kd) are not loaded; base colours only".to_string());
            }
            n
        }
        Err(e) => {
            b.warn(format!(
                "materials (.mtl) could not be loaded ({e}); using the default material"
            ));
            0
        }
    };

    for (mi, model) in models.iter().enumerate() {
        let location = format!("OBJ model {mi} '{}'", model.name);
        let mesh = &model.mesh;
        let err = |problem: String| SceneError::ObjMesh {
            path: path.to_path_buf(),
            location: location.clone(),
            problem,
        };
        if !mesh.positions.len().is_multiple_of(3) {
            return Err(err(format!(
                "{} position components is not a multiple of 3",
                mesh.positions.len()
            )));
        }
        let n = mesh.positions.len() / 3;
        let has_normals = !mesh.normals.is_empty() && mesh.normals.len() == mesh.positions.len();
        let has_uvs = !mesh.texcoords.is_empty() && mesh.texcoords.len() == 2 * n;
        if !mesh.normals.is_empty() && !has_normals {
            b.warn(format!(
                "{location}: normal count does not match the vertex count; normals ignored"
            ));
        }
        if !mesh.texcoords.is_empty() && !has_uvs {
            b.warn(format!(
                "{location}: texcoord count does not match the vertex count; texcoords ignored"
            ));
        }
        let material = match mesh.material_id {
            Some(id) if id < n_mats => id as u32 + 1,
            Some(id) => {
                b.warn(format!(
                    "{location}: material {id} does not exist; using the default material"
                ));
                0
            }
            None => 0,
        };
        if !mesh.indices.len().is_multiple_of(3) {
            b.warn(format!(
                "{location}: {} indices is not a multiple of 3; the rest ignored",
                mesh.indices.len()
            ));
        }
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let mut p = [Vec3::ZERO; 3];
            let mut vidx = [0usize; 3];
            for c in 0..3 {
                let pos = 3 * t + c;
                let v = tri.get(c).copied().unwrap_or(u32::MAX) as usize;
                let Some(&[x, y, z]) = mesh.positions.get(3 * v..3 * v + 3) else {
                    return Err(SceneError::IndexOutOfRange {
                        path: path.to_path_buf(),
                        location: location.clone(),
                        index: v as u64,
                        position: pos,
                        vertex_count: n,
                    });
                };
                let q = Vec3::new(x, y, z);
                if !q.is_finite() {
                    return Err(SceneError::NonFinite {
                        path: path.to_path_buf(),
                        location: location.clone(),
                        vertex: v,
                        value: q.to_array(),
                    });
                }
                p[c] = q;
                vidx[c] = v;
            }
            let tri = Triangle::new(p[0], p[1], p[2]);
            let normals = has_normals.then(|| {
                let face = crate::builder::face_normal(&tri);
                vidx.map(|v| match mesh.normals.get(3 * v..3 * v + 3) {
                    Some(&[x, y, z]) => Vec3::new(x, y, z)
                        .try_normalize()
                        .unwrap_or(face)
                        .to_array(),
                    _ => face.to_array(),
                })
            });
            let uvs = has_uvs.then(|| {
                vidx.map(|v| match mesh.texcoords.get(2 * v..2 * v + 2) {
                    Some(&[s, t]) if s.is_finite() && t.is_finite() => [s, 1.0 - t],
                    _ => [0.0; 2],
                })
            });
            if b.len() >= dirt_math::INVALID_ID as usize {
                return Err(SceneError::TooLarge {
                    path: path.to_path_buf(),
                    problem: format!("more than {} triangles", dirt_math::INVALID_ID),
                });
            }
            b.push(tri, material, normals, uvs);
        }
    }
    Ok(b.finish())
}

/// `Kd` → base colour (`d` → alpha), `Ke` → emissive; metallic 0 and
/// roughness 1 (Phong specular terms are ignored).
fn convert_material(m: tobj::Material) -> Material {
    let finite = |v: f32, default: f32| if v.is_finite() { v } else { default };
    let kd = m.diffuse.unwrap_or([0.8; 3]).map(|c| finite(c, 0.8));
    let alpha = finite(m.dissolve.unwrap_or(1.0), 1.0).clamp(0.0, 1.0);
    let emissive = m
        .emissive
        .or_else(|| {
            let ke = m.unknown_param.get("Ke")?;
            let v: Vec<f32> = ke
                .split_whitespace()
                .filter_map(|s| s.parse().ok())
                .collect();
            match v.as_slice() {
                [r, g, b] => Some([*r, *g, *b]),
                [x] => Some([*x; 3]),
                _ => None,
            }
        })
        .unwrap_or([0.0; 3])
        .map(|c| finite(c, 0.0).max(0.0));
    Material {
        name: m.name,
        base_color: [kd[0], kd[1], kd[2], alpha],
        base_color_texture: None,
        metallic: 0.0,
        roughness: 1.0,
        emissive,
        transmission: 0.0,
    }
}
