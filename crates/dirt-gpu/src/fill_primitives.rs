//! Pass `fill_primitives` (`fill_primitives.wgsl`): counts per list (raster
//! `count`), an exclusive prefix sum in place (compute `scan_blocks`,
//! `scan_add`), the total read back to size the ids exactly, then the
//! lists filled through atomic cursors (raster `fill`). Nothing is ever
//! dropped: the ids (split across bindings, see `ids.wgsl`) hold as many as
//! the count says, or the build fails before filling with
//! [`GpuError::SplitTooLarge`]. Mirrors `dirt_cpu::fill_primitives`.

use crate::chunked::{Chunked, Kind};
use crate::fill_depth::draw_coverage;
use crate::{
    BuildParams, Gpu, GpuError, ScanParams, bind_buffers, read_back, storage_init, uniform_init,
    with,
};

const SCAN_BLOCK: u64 = 256;

/// Workgroups for `n` elements, as a 2D grid when one dimension is not enough.
pub(crate) fn grid(gpu: &Gpu, groups: u64) -> (u32, u32) {
    let max = gpu.limits.max_compute_workgroups_per_dimension as u64;
    if groups <= max {
        (groups.max(1) as u32, 1)
    } else {
        (max as u32, groups.div_ceil(max) as u32)
    }
}

/// The dispatches of an exclusive prefix sum of the first `n` u32 of one
/// buffer, in place: made once for the buffer (block sums, uniforms, bind
/// groups) and kept.
#[derive(Debug)]
pub(crate) struct Scan {
    /// (pipeline is scan_add, bind group, workgroups) in recording order.
    steps: Vec<(bool, wgpu::BindGroup, (u32, u32))>,
}

impl Scan {
    pub(crate) fn new(gpu: &Gpu, data: &wgpu::Buffer, n: u64) -> Scan {
        // Levels: data (n), then per-block sums until one block holds everything.
        let mut levels: Vec<(wgpu::Buffer, u64)> = Vec::new();
        let mut sums_of: Vec<wgpu::Buffer> = Vec::new();
        let mut count = n;
        loop {
            let blocks = count.div_ceil(SCAN_BLOCK);
            sums_of.push(storage_init(
                gpu,
                "scan sums",
                &vec![0u8; (blocks * 4) as usize],
                wgpu::BufferUsages::empty(),
            ));
            levels.push((
                if levels.is_empty() {
                    data.clone()
                } else {
                    sums_of[sums_of.len() - 2].clone()
                },
                count,
            ));
            if blocks <= 1 {
                break;
            }
            count = blocks;
        }
        let step = |add: bool, data: &wgpu::Buffer, sums: &wgpu::Buffer, n: u64| {
            let u = uniform_init(
                gpu,
                "scan params",
                bytemuck::bytes_of(&ScanParams {
                    n: n as u32,
                    ..Default::default()
                }),
            );
            let pipeline = if add {
                &gpu.pipelines.scan_add
            } else {
                &gpu.pipelines.scan_blocks
            };
            let bind = bind_buffers(
                gpu,
                "scan",
                &pipeline.get_bind_group_layout(0),
                &[(6, data), (7, sums), (8, &u)],
            );
            (add, bind, grid(gpu, n.div_ceil(SCAN_BLOCK)))
        };
        let mut steps = Vec::new();
        for (k, (buf, n)) in levels.iter().enumerate() {
            steps.push(step(false, buf, &sums_of[k], *n));
        }
        for k in (0..levels.len().saturating_sub(1)).rev() {
            let (buf, n) = &levels[k];
            steps.push(step(true, buf, &sums_of[k], *n));
        }
        Scan { steps }
    }

    pub(crate) fn record(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder) {
        for (add, bind, (x, y)) in &self.steps {
            let pipeline = if *add {
                &gpu.pipelines.scan_add
            } else {
                &gpu.pipelines.scan_blocks
            };
            crate::record_dispatch(enc, "scan", pipeline, bind, [*x, *y, 1]);
        }
    }
}

/// Exclusive prefix sum of the first `n` u32 of `data`, in place.
fn scan(gpu: &Gpu, data: &wgpu::Buffer, n: u64) -> Result<(), GpuError> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    Scan::new(gpu, data, n).record(gpu, &mut enc);
    gpu.submit(enc);
    gpu.wait()
}

/// Returns (offsets, ids, node count).
pub(crate) fn fill_primitives(
    gpu: &Gpu,
    tris: &Chunked,
    views: &wgpu::Buffer,
    build_uniform: &wgpu::Buffer,
    hiz: &wgpu::Buffer,
    build: &BuildParams,
    content: &[u32],
    n_lists: u64,
) -> Result<(wgpu::Buffer, Chunked, u32), GpuError> {
    // Counts, then (after the scan) offsets; one extra zero so offsets[n_lists] is the total.
    let lists = storage_init(
        gpu,
        "lists",
        &vec![0u8; ((n_lists + 1) * 4) as usize],
        wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
    );
    if build.n_tris > 0 {
        let split = tris.is_split();
        let p = &gpu.pipelines_for(split)?.count;
        let bind = bind_buffers(
            gpu,
            "fill_primitives",
            &p.get_bind_group_layout(0),
            &with(
                &[(1, views), (2, build_uniform), (3, hiz), (4, &lists)],
                tris.bindings(gpu, split),
            ),
        );
        draw_coverage(gpu, p, &bind, build, content);
    }
    scan(gpu, &lists, n_lists + 1)?;
    let total = bytemuck::pod_read_unaligned::<u32>(&read_back(gpu, &lists, n_lists * 4, 4)?);
    let ids = Chunked::new(gpu, Kind::Ids, total as u64)?;
    if total > 0 {
        let cursors = storage_init(
            gpu,
            "cursors",
            &vec![0u8; ((n_lists + 1) * 4) as usize],
            wgpu::BufferUsages::COPY_DST,
        );
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&lists, 0, &cursors, 0, (n_lists + 1) * 4);
        gpu.submit(enc);
        let split = tris.is_split() || ids.is_split();
        let p = &gpu.pipelines_for(split)?.fill;
        let mut buffers = with(
            &[(1, views), (2, build_uniform), (3, hiz), (4, &cursors)],
            tris.bindings(gpu, split),
        );
        buffers.extend(ids.bindings(gpu, split));
        let bind = bind_buffers(
            gpu,
            "fill_primitives",
            &p.get_bind_group_layout(0),
            &buffers,
        );
        draw_coverage(gpu, p, &bind, build, content);
        gpu.wait()?;
    }
    Ok((lists, ids, total))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The prefix sum on the GPU equals a sequential one, across several levels.
    #[test]
    fn scan_is_an_exclusive_prefix_sum() {
        // Integers only: the same sums on every adapter.
        let Some(gpu) = crate::testing::any_gpu("scan_is_an_exclusive_prefix_sum") else {
            return;
        };
        for n in [1usize, 5, 256, 257, 70_000] {
            let data: Vec<u32> = (0..n as u32).map(|i| i % 7).collect();
            let buf = storage_init(
                gpu,
                "t",
                bytemuck::cast_slice(&data),
                wgpu::BufferUsages::COPY_SRC,
            );
            scan(gpu, &buf, n as u64).expect("scan");
            let got = bytemuck::pod_collect_to_vec::<u8, u32>(
                &read_back(gpu, &buf, 0, n as u64 * 4).expect("read"),
            );
            let mut acc = 0;
            let want: Vec<u32> = data
                .iter()
                .map(|x| {
                    let v = acc;
                    acc += x;
                    v
                })
                .collect();
            assert_eq!(&got[..n], &want[..], "n = {n}");
        }
    }
}
