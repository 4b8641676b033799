//! Pass `mip_depth` (`mip_depth.wgsl`): one compute dispatch per Hi-Z level.
//! Mirrors `dirt_cpu::mip_depth`.

use crate::{Gpu, GpuError, MipParams, bind_buffers, uniform_init};
use dirt_math::dda::{hiz_levels, hiz_width};

/// The dispatches of one Hi-Z pyramid, made once for its buffer and kept.
#[derive(Debug)]
pub(crate) struct MipDepth {
    levels: Vec<(wgpu::BindGroup, [u32; 3])>,
}

impl MipDepth {
    pub(crate) fn new(gpu: &Gpu, hiz: &wgpu::Buffer, tiles: u32, n_slots: u32) -> MipDepth {
        let p = &gpu.pipelines.mip_depth;
        let mut base = 0u32;
        let mut levels = Vec::new();
        for l in 1..hiz_levels(tiles) {
            let src_w = hiz_width(tiles, l - 1);
            let dst_w = hiz_width(tiles, l);
            let params = MipParams {
                src_base: base,
                dst_base: base + src_w * src_w * n_slots,
                src_w,
                dst_w,
            };
            base = params.dst_base;
            let u = uniform_init(gpu, "mip params", bytemuck::bytes_of(&params));
            let bind = bind_buffers(
                gpu,
                "mip_depth",
                &p.get_bind_group_layout(0),
                &[(0, hiz), (1, &u)],
            );
            levels.push((bind, [dst_w.div_ceil(8), dst_w.div_ceil(8), n_slots]));
        }
        if n_slots == 0 {
            levels.clear();
        }
        MipDepth { levels }
    }

    /// Records every level, finest first.
    pub(crate) fn record(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder) {
        for (bind, groups) in &self.levels {
            crate::record_dispatch(enc, "mip_depth", &gpu.pipelines.mip_depth, bind, *groups);
        }
    }
}

pub(crate) fn mip_depth(
    gpu: &Gpu,
    hiz: &wgpu::Buffer,
    tiles: u32,
    n_slots: u32,
) -> Result<(), GpuError> {
    if n_slots == 0 {
        return Ok(());
    }
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    MipDepth::new(gpu, hiz, tiles, n_slots).record(gpu, &mut enc);
    gpu.submit(enc);
    gpu.wait()
}
