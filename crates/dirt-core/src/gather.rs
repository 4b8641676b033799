//! Stage `gather`: an application's mesh — a vertex buffer with a stride and a
//! position offset, an optional u16 or u32 index buffer, an optional affine
//! transform — as dirt's triangles. The CPU reference of `gather.wgsl`
//! (`dirt_gpu::gather`), to the bit: the transform is written out with no
//! fused operation, in the order the shader uses.
//!
//! A vertex index past the end of the vertex bytes gives NaN positions, as on
//! the GPU (which cannot stop a build it only records): [`crate::views_for`]
//! then refuses the triangle as non-finite, naming it.

use crate::CoreError;
use dirt_math::{Triangle, Vec3};

/// Width of a mesh's indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IndexFormat {
    U16,
    U32,
}

impl IndexFormat {
    pub fn bytes(self) -> u32 {
        match self {
            IndexFormat::U16 => 2,
            IndexFormat::U32 => 4,
        }
    }
}

/// A 3×4 affine transform, row-major: `p' = rows · (p, 1)`.
pub type Affine = [[f32; 4]; 3];

/// How a mesh's triangles lie in its buffers. Byte offsets and strides are
/// multiples of 4 (positions are three little-endian f32).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshLayout {
    /// Bytes from one vertex to the next.
    pub vertex_stride: u32,
    /// Bytes from the start of a vertex to its position.
    pub position_offset: u32,
    /// `None`: no index buffer, triangle `t` is vertices `3t, 3t+1, 3t+2`.
    pub index_format: Option<IndexFormat>,
    /// The first index read (in indices, not bytes).
    pub first_index: u32,
    /// Triangles: `3 · triangles` indices (or vertices) are read.
    pub triangles: u32,
    /// Applied to every position; `None` keeps them as they are.
    pub transform: Option<Affine>,
}

impl MeshLayout {
    /// `triangles` triangles of tightly packed positions (dirt's own layout:
    /// nine f32 a triangle), no index buffer, no transform.
    pub fn triangles(triangles: u32) -> Self {
        MeshLayout {
            vertex_stride: 12,
            position_offset: 0,
            index_format: None,
            first_index: 0,
            triangles,
            transform: None,
        }
    }

    /// `triangles` triangles of `format` indices into vertices of `vertex_stride`
    /// bytes with the position at `position_offset`.
    pub fn indexed(
        vertex_stride: u32,
        position_offset: u32,
        format: IndexFormat,
        triangles: u32,
    ) -> Self {
        MeshLayout {
            vertex_stride,
            position_offset,
            index_format: Some(format),
            first_index: 0,
            triangles,
            transform: None,
        }
    }

    /// Checks the layout: strides and offsets in whole words, the position
    /// inside the stride, and an index buffer of `index_bytes` long enough.
    pub fn validate(&self, index_bytes: Option<u64>) -> Result<(), CoreError> {
        let bad = |m: String| Err(CoreError::InvalidParams(m));
        if !self.vertex_stride.is_multiple_of(4) || !self.position_offset.is_multiple_of(4) {
            return bad(format!(
                "vertex stride {} and position offset {} must be multiples of 4",
                self.vertex_stride, self.position_offset
            ));
        }
        if self.position_offset as u64 + 12 > self.vertex_stride as u64 {
            return bad(format!(
                "a position (12 bytes) at offset {} does not fit a vertex stride of {}",
                self.position_offset, self.vertex_stride
            ));
        }
        if let Some(f) = self.index_format {
            let need = (self.first_index as u64 + 3 * self.triangles as u64) * f.bytes() as u64;
            match index_bytes {
                None => return bad("the layout has indices but no index buffer was given".into()),
                Some(have) if have < need => {
                    return bad(format!(
                        "{} triangles from index {} need {need} bytes of {f:?} indices; the index buffer holds {have}",
                        self.triangles, self.first_index
                    ));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }
}

/// `rows · (p, 1)`, each row `((m0·x + m1·y) + m2·z) + m3`, no fused operation.
pub fn transform_point(m: &Affine, p: Vec3) -> Vec3 {
    let row = |r: &[f32; 4]| {
        let (a, b, c) = (r[0] * p.x, r[1] * p.y, r[2] * p.z);
        ((a + b) + c) + r[3]
    };
    Vec3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// The triangles of a mesh in `vertices` (and `indices`, when the layout has
/// them), as the GPU's `gather` writes them.
pub fn gather(
    vertices: &[u8],
    indices: Option<&[u8]>,
    layout: &MeshLayout,
) -> Result<Vec<Triangle>, CoreError> {
    layout.validate(indices.map(|i| i.len() as u64))?;
    let word = |bytes: &[u8], at: usize| -> Option<u32> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let vertex_index = |i: u64| -> u32 {
        let at = layout.first_index as u64 + i;
        match (layout.index_format, indices) {
            (Some(IndexFormat::U16), Some(ix)) => {
                let k = at as usize * 2;
                u16::from_le_bytes([ix[k], ix[k + 1]]) as u32
            }
            (Some(IndexFormat::U32), Some(ix)) => word(ix, at as usize * 4).unwrap_or(u32::MAX),
            _ => i as u32,
        }
    };
    let position = |v: u32| -> Vec3 {
        let base = v as u64 * layout.vertex_stride as u64 + layout.position_offset as u64;
        let p = (0..3)
            .map(|k| {
                usize::try_from(base + 4 * k)
                    .ok()
                    .and_then(|at| word(vertices, at))
            })
            .collect::<Option<Vec<u32>>>();
        let p = match p {
            Some(w) => Vec3::new(
                f32::from_bits(w[0]),
                f32::from_bits(w[1]),
                f32::from_bits(w[2]),
            ),
            None => Vec3::splat(f32::NAN),
        };
        match &layout.transform {
            Some(m) => transform_point(m, p),
            None => p,
        }
    };
    Ok((0..layout.triangles as u64)
        .map(|t| {
            Triangle::new(
                position(vertex_index(3 * t)),
                position(vertex_index(3 * t + 1)),
                position(vertex_index(3 * t + 2)),
            )
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(words: &[f32]) -> Vec<u8> {
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    #[test]
    fn an_interleaved_indexed_mesh_gathers_its_positions() {
        // Vertices of 6 floats: a normal (3) then the position (3).
        let mut v = Vec::new();
        for k in 0..4 {
            v.extend_from_slice(&[9.0, 9.0, 9.0, k as f32, 2.0 * k as f32, 0.5]);
        }
        let ix: Vec<u8> = [0u16, 1, 2, 2, 1, 3]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let layout = MeshLayout::indexed(24, 12, IndexFormat::U16, 2);
        let t = gather(&bytes(&v), Some(&ix), &layout).expect("gathers");
        assert_eq!(t.len(), 2);
        assert_eq!(t[1].vertex(2), Vec3::new(3.0, 6.0, 0.5));
        assert_eq!(t[1].vertex(0), Vec3::new(2.0, 4.0, 0.5));
    }

    #[test]
    fn a_transform_moves_every_vertex() {
        let v = bytes(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        let mut layout = MeshLayout::triangles(1);
        layout.transform = Some([
            [2.0, 0.0, 0.0, 10.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, -1.0],
        ]);
        let t = gather(&v, None, &layout).expect("gathers");
        assert_eq!(t[0].vertex(0), Vec3::new(12.0, 2.0, 2.0));
        assert_eq!(t[0].vertex(1), Vec3::new(10.0, 0.0, -1.0));
    }

    #[test]
    fn an_index_past_the_vertices_is_non_finite_and_refused_by_name() {
        let v = bytes(&[0.0; 9]);
        let ix: Vec<u8> = [0u32, 1, 7].iter().flat_map(|i| i.to_le_bytes()).collect();
        let layout = MeshLayout::indexed(12, 0, IndexFormat::U32, 1);
        let t = gather(&v, Some(&ix), &layout).expect("gathers");
        assert!(t[0].vertex(2).x.is_nan());
        let e = crate::views_for(&t, &crate::AdsParams::default()).expect_err("an error");
        assert!(
            matches!(e, CoreError::NonFiniteTriangle { index: 0 }),
            "{e}"
        );
    }

    #[test]
    fn bad_layouts_are_errors() {
        let v = bytes(&[0.0; 9]);
        let odd = MeshLayout {
            vertex_stride: 14,
            ..MeshLayout::triangles(1)
        };
        assert!(gather(&v, None, &odd).is_err());
        let short = MeshLayout::indexed(12, 4, IndexFormat::U32, 1);
        assert!(gather(&v, Some(&[0; 12]), &short).is_err());
        let few = MeshLayout::indexed(12, 0, IndexFormat::U32, 2);
        assert!(gather(&v, Some(&[0; 12]), &few).is_err());
        let missing = MeshLayout::indexed(12, 0, IndexFormat::U16, 1);
        assert!(gather(&v, None, &missing).is_err());
    }
}
