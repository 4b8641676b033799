//! Pass `mip_depth` (`mip_depth.wgsl`): one compute dispatch per Hi-Z level.
//! Mirrors `dirt_cpu::mip_depth`.

use crate::{Gpu, GpuError, MipParams, bind_buffers, uniform_init};
use dirt_math::dda::{hiz_levels, hiz_width};

pub(crate) fn mip_depth(
    gpu: &Gpu,
    hiz: &wgpu::Buffer,
    tiles: u32,
    n_slots: u32,
) -> Result<(), GpuError> {
    if n_slots == 0 {
        return Ok(());
    }
    let p = &gpu.pipelines.mip_depth;
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    let mut base = 0u32;
    let mut uniforms = Vec::new();
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
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(p);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(dst_w.div_ceil(8), dst_w.div_ceil(8), n_slots);
        }
        uniforms.push(u);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.wait()
}
