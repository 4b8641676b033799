//! Mesh primitives to world-space triangles: the triangle modes and their
//! corner order, index resolution and range checks, and per-vertex normals
//! and texture coordinates (with non-finite values replaced).

use dirt_math::{Triangle, Vec3};
use glam::{Mat3, Mat4};
use gltf::accessor::Dimensions;
use gltf::mesh::{Mode, Semantic};

use super::Ctx;
use super::accessors::{read_floats, read_indices};
use crate::SceneError;
use crate::builder::face_normal;

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

pub(super) fn read_primitive(
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

    let first = ctx.b.len();
    let mut corner_list = ctx.rig.is_some().then(Vec::new);
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
        if let Some(list) = corner_list.as_mut() {
            list.push(vidx.map(|v| v as u32));
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
    if let Some(corners) = corner_list {
        super::rig::record_primitive(ctx, location, prim, first, corners, &positions, normals)?;
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

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
}
