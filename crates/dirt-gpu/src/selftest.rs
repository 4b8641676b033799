//! Runs the self-test kernels of `selftest_math.wgsl`, which the tests use to
//! compare single shared functions with their `dirt-math` twins bit for bit.

use crate::{Gpu, GpuError, read_back, storage_init};

/// Runs entry `entry` of `selftest_math.wgsl` over `cases` cases with raw input
/// words, returning `out_words` words.
pub fn run(
    gpu: &Gpu,
    entry: &str,
    input: &[u32],
    cases: u32,
    out_words: usize,
) -> Result<Vec<u32>, GpuError> {
    let st = crate::spirv::compile(
        &gpu.device,
        "selftest_math",
        gpu.exact,
        dirt_shaders::Chunks::ONE,
    )?;
    let p = crate::compute(&gpu.device, &st, entry)?;
    let inb = storage_init(
        gpu,
        "selftest in",
        bytemuck::cast_slice(input),
        wgpu::BufferUsages::empty(),
    );
    let outb = storage_init(
        gpu,
        "selftest out",
        &vec![0u8; out_words * 4],
        wgpu::BufferUsages::COPY_SRC,
    );
    let bind = crate::bind_buffers(
        gpu,
        "selftest",
        &p.get_bind_group_layout(0),
        &[(0, &inb), (1, &outb)],
    );
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&p);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(cases.div_ceil(64), 1, 1);
    }
    gpu.submit(enc);
    gpu.wait()?;
    let out =
        bytemuck::pod_collect_to_vec::<u8, u32>(&read_back(gpu, &outb, 0, (out_words * 4) as u64)?);
    Ok(out[..out_words].to_vec())
}
