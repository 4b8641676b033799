//! Pass `fill_depth` (`fill_depth.wgsl`): rasterizes, per view, the tile-range
//! quad of every triangle; each fragment runs the exact tile test and updates
//! the tile's `[zmin, zmax]` with atomic min/max. Mirrors `dirt_cpu::fill_depth`.

use crate::chunked::{Chunked, Kind, Split};
use crate::{BuildParams, Gpu, GpuError, bind_buffers, with};
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF};

/// The Hi-Z pyramid of `cells` cells, split across bindings, every cell
/// `[enc(+inf), enc(-inf)]` (empty); an error naming the sizes when the
/// device cannot bind them. Checked before the cells are made on the host.
pub(crate) fn new_hiz(gpu: &Gpu, cells: u64) -> Result<Chunked, GpuError> {
    Chunked::new(gpu, Kind::Hiz, cells)?;
    let init: Vec<[u32; 2]> = vec![[ORDERED_POS_INF, ORDERED_NEG_INF]; cells as usize];
    Chunked::with_data(gpu, Kind::Hiz, bytemuck::cast_slice(&init))
}

/// A render target of one pixel per tile; nothing is written to it.
pub(crate) fn tile_target(gpu: &Gpu, tiles: u32) -> wgpu::TextureView {
    gpu.device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("tiles"),
            size: wgpu::Extent3d {
                width: tiles,
                height: tiles,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: crate::TARGET_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

/// Draws the coverage quads of every (view, triangle) with `pipeline` and
/// `bind`, for the views in `content` only (views without content get no draw).
pub(crate) fn draw_coverage(
    gpu: &Gpu,
    pipeline: &wgpu::RenderPipeline,
    bind: &wgpu::BindGroup,
    build: &BuildParams,
    content: &[u32],
) {
    let target = tile_target(gpu, build.tiles);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    for &v in content {
        record_coverage(&mut enc, &target, pipeline, bind, build.n_tris, v..v + 1);
    }
    gpu.submit(enc);
}

/// Records the coverage quads of `n_tris` triangles for the views (instances)
/// in `views`; the vertex shader skips views without a slot.
pub(crate) fn record_coverage(
    enc: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    bind: &wgpu::BindGroup,
    n_tris: u32,
    views: std::ops::Range<u32>,
) {
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("coverage"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Discard,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.draw(0..n_tris * 6, views);
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn fill_depth(
    gpu: &Gpu,
    split: Split,
    tris: &Chunked,
    views: &wgpu::Buffer,
    build_uniform: &wgpu::Buffer,
    hiz: &Chunked,
    build: &BuildParams,
    content: &[u32],
) -> Result<(), GpuError> {
    if build.n_tris == 0 {
        return Ok(());
    }
    let p = &gpu.pipelines_for(split)?.fill_depth;
    let bind = bind_buffers(
        gpu,
        "fill_depth",
        &p.get_bind_group_layout(0),
        &with(
            &[(1, views), (2, build_uniform)],
            [tris.bindings(gpu, split), hiz.bindings(gpu, split)],
        ),
    );
    draw_coverage(gpu, p, &bind, build, content);
    gpu.wait()
}
