//! Pass `mip_depth` (`mip_depth.wgsl`): one compute dispatch per Hi-Z level.
//! Mirrors `dirt_cpu::mip_depth`.

use crate::chunked::{Chunked, Split};
use crate::{Gpu, GpuError, MipParams, bind_buffers, uniform_init, with};
use dirt_math::dda::{hiz_levels, hiz_width};

/// The dispatches of one Hi-Z pyramid, made once for its buffers and the
/// pipelines of `split`, and kept.
#[derive(Debug)]
pub(crate) struct MipDepth {
    split: Split,
    levels: Vec<(wgpu::BindGroup, [u32; 3])>,
}

impl MipDepth {
    pub(crate) fn new(
        gpu: &Gpu,
        split: Split,
        hiz: &Chunked,
        tiles: u32,
        n_slots: u32,
    ) -> Result<MipDepth, GpuError> {
        let p = &gpu.pipelines_for(split)?.mip_depth;
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
                shift: hiz.shift(),
                ..Default::default()
            };
            base = params.dst_base;
            let u = uniform_init(gpu, "mip params", bytemuck::bytes_of(&params));
            let bind = bind_buffers(
                gpu,
                "mip_depth",
                &p.get_bind_group_layout(0),
                &with(&[(1, &u)], [hiz.bindings(gpu, split)]),
            );
            levels.push((bind, [dst_w.div_ceil(8), dst_w.div_ceil(8), n_slots]));
        }
        if n_slots == 0 {
            levels.clear();
        }
        Ok(MipDepth { split, levels })
    }

    /// The pipelines these dispatches were made for.
    pub(crate) fn split(&self) -> Split {
        self.split
    }

    /// Records every level, finest first.
    pub(crate) fn record(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder) -> Result<(), GpuError> {
        let p = &gpu.pipelines_for(self.split)?.mip_depth;
        for (bind, groups) in &self.levels {
            crate::record_dispatch(enc, "mip_depth", p, bind, *groups);
        }
        Ok(())
    }
}

pub(crate) fn mip_depth(
    gpu: &Gpu,
    split: Split,
    hiz: &Chunked,
    tiles: u32,
    n_slots: u32,
) -> Result<(), GpuError> {
    if n_slots == 0 {
        return Ok(());
    }
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    MipDepth::new(gpu, split, hiz, tiles, n_slots)?.record(gpu, &mut enc)?;
    gpu.submit(enc);
    gpu.wait()
}
