//! Pass `gather` (`gather.wgsl`): an application's mesh — vertex buffer,
//! optional u16/u32 index buffer, stride, position offset, optional affine
//! transform ([`dirt_core::gather::MeshLayout`]) — into the structure's
//! triangle buffer, one thread per triangle. Mirrors `dirt_core::gather`.

use crate::chunked::{Chunked, Split};
use crate::fill_primitives::grid;
use crate::{GatherParams, Gpu, GpuError};
use dirt_core::gather::{IndexFormat, MeshLayout};

/// One mesh of a build recorded with [`crate::GpuAds::encode_build`]: the
/// application's buffers and how its triangles lie in them. Both buffers are
/// read as storage buffers (they need [`wgpu::BufferUsages::STORAGE`]) and
/// only read.
#[derive(Clone, Copy, Debug)]
pub struct GpuMesh<'a> {
    /// Positions: three little-endian f32 at `layout.position_offset` of each
    /// `layout.vertex_stride` bytes (or dirt's own triangles, nine f32 each,
    /// with [`MeshLayout::triangles`]).
    pub vertices: &'a wgpu::Buffer,
    /// Indices of `layout.index_format`, when the layout has them.
    pub indices: Option<&'a wgpu::Buffer>,
    pub layout: MeshLayout,
}

impl GpuMesh<'_> {
    /// Checks the layout against the buffers: usages, alignment, and an
    /// index buffer long enough for the triangles.
    pub(crate) fn check(&self) -> Result<(), GpuError> {
        let usage = |what: &'static str, b: &wgpu::Buffer| {
            if b.usage().contains(wgpu::BufferUsages::STORAGE) {
                Ok(())
            } else {
                Err(GpuError::Buffer {
                    what,
                    problem: format!(
                        "has usage {:?}; the build reads it as a storage buffer and needs STORAGE",
                        b.usage()
                    ),
                })
            }
        };
        usage("the mesh's vertex buffer", self.vertices)?;
        if let Some(i) = self.indices {
            usage("the mesh's index buffer", i)?;
        }
        if self.indices.is_some() && self.layout.index_format.is_none() {
            return Err(GpuError::Buffer {
                what: "the mesh's index buffer",
                problem: "was given, but the layout has no index format".into(),
            });
        }
        self.layout
            .validate(self.indices.map(|b| b.size()))
            .map_err(GpuError::Params)
    }

    pub(crate) fn params(&self, first_tri: u32, tri_shift: u32) -> GatherParams {
        let l = &self.layout;
        GatherParams {
            first_tri,
            n_tris: l.triangles,
            stride: l.vertex_stride / 4,
            offset: l.position_offset / 4,
            index_format: match l.index_format {
                None => 0,
                Some(IndexFormat::U16) => 1,
                Some(IndexFormat::U32) => 2,
            },
            first_index: l.first_index,
            has_transform: l.transform.is_some() as u32,
            tri_shift,
            rows: l.transform.unwrap_or_default(),
        }
    }
}

/// A whole-buffer binding rounded down to whole words (storage bindings are
/// sized in words; a u16 index buffer may end half-way).
fn words(buf: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer: buf,
        offset: 0,
        size: wgpu::BufferSize::new((buf.size() & !3).max(4)),
    })
}

/// Records the gather of `mesh` into `tris` from triangle `first_tri`, with
/// its parameters already written to `uniform`; `pipelines` are
/// [`Gpu::pipelines_for`]`(split)`.
pub(crate) fn record(
    gpu: &Gpu,
    pipelines: &crate::Pipelines,
    split: Split,
    enc: &mut wgpu::CommandEncoder,
    mesh: &GpuMesh<'_>,
    uniform: &wgpu::Buffer,
    tris: &Chunked,
) {
    if mesh.layout.triangles == 0 {
        return;
    }
    let p = &pipelines.gather;
    let mut entries: Vec<wgpu::BindGroupEntry<'_>> = [
        (0, words(mesh.vertices)),
        (1, words(mesh.indices.unwrap_or(mesh.vertices))),
        (3, uniform.as_entire_binding()),
    ]
    .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource })
    .into();
    entries.extend(crate::whole(tris.bindings(gpu, split)));
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gather"),
        layout: &p.get_bind_group_layout(0),
        entries: &entries,
    });
    let (x, y) = grid(gpu, (mesh.layout.triangles as u64).div_ceil(64));
    crate::record_dispatch(enc, "gather", p, &bind, [x, y, 1]);
}
