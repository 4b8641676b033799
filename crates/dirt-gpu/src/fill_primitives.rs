//! Pass `fill_primitives` (`fill_primitives.wgsl`): counts per list (raster
//! `count`), an exclusive prefix sum in place (compute `scan_blocks`,
//! `scan_add`), the total read back to size the ids exactly, then the
//! lists filled through atomic cursors (raster `fill`). Nothing is ever
//! dropped: the ids (split across bindings, see `ids.wgsl`) hold as many as
//! the count says, or the build fails before filling with
//! [`GpuError::SplitTooLarge`]. Mirrors `dirt_cpu::fill_primitives`.

use crate::chunked::{Chunked, Kind, Split};
use crate::fill_depth::draw_coverage;
use crate::{
    BuildParams, Gpu, GpuError, ScanParams, bind_buffers, read_back, storage_init, uniform_init,
    with,
};

const SCAN_BLOCK: u64 = 256;

/// A shift that keeps every index of a level's sums in chunk 0.
const SUMS_SHIFT: u32 = 30;

/// Workgroups for `n` elements, as a 2D grid when one dimension is not enough.
pub(crate) fn grid(gpu: &Gpu, groups: u64) -> (u32, u32) {
    let max = gpu.limits.max_compute_workgroups_per_dimension as u64;
    if groups <= max {
        (groups.max(1) as u32, 1)
    } else {
        (max as u32, groups.div_ceil(max) as u32)
    }
}

/// The dispatches of an exclusive prefix sum of the first `n` elements of a
/// split array, in place: made once for the array and the pipelines of
/// `split` (block sums, uniforms, bind groups) and kept.
#[derive(Debug)]
pub(crate) struct Scan {
    split: Split,
    /// (pipeline is scan_add, bind group, workgroups) in recording order.
    steps: Vec<(bool, wgpu::BindGroup, (u32, u32))>,
}

impl Scan {
    pub(crate) fn new(gpu: &Gpu, split: Split, data: &Chunked, n: u64) -> Result<Scan, GpuError> {
        let pipelines = gpu.pipelines_for(split)?;
        // Levels: the data (n), then per-block sums until one block holds everything.
        let mut counts = vec![n];
        while counts[counts.len() - 1] > SCAN_BLOCK {
            counts.push(counts[counts.len() - 1].div_ceil(SCAN_BLOCK));
        }
        let sums: Vec<wgpu::Buffer> = counts
            .iter()
            .map(|c| {
                storage_init(
                    gpu,
                    "scan sums",
                    &vec![0u8; (c.div_ceil(SCAN_BLOCK) * 4) as usize],
                    wgpu::BufferUsages::empty(),
                )
            })
            .collect();
        let declared = gpu.declared(split, Kind::Offsets);
        let step = |add: bool, level: usize| {
            let n = counts[level];
            // Level 0 is the array's chunks; a level above is the sums below it, alone in chunk 0.
            let (shift, chunks) = if level == 0 {
                (
                    data.shift(),
                    data.bindings_at(dirt_shaders::SCAN_BINDING, gpu, split),
                )
            } else {
                let below = &sums[level - 1];
                (
                    SUMS_SHIFT,
                    (0..declared)
                        .map(|c| (dirt_shaders::SCAN_BINDING + c, below))
                        .collect(),
                )
            };
            let u = uniform_init(
                gpu,
                "scan params",
                bytemuck::bytes_of(&ScanParams {
                    n: n as u32,
                    shift,
                    ..Default::default()
                }),
            );
            let pipeline = if add {
                &pipelines.scan_add
            } else {
                &pipelines.scan_blocks
            };
            let bind = bind_buffers(
                gpu,
                "scan",
                &pipeline.get_bind_group_layout(0),
                &with(&[(7, &sums[level]), (8, &u)], [chunks]),
            );
            (add, bind, grid(gpu, n.div_ceil(SCAN_BLOCK)))
        };
        let mut steps = Vec::new();
        for level in 0..counts.len() {
            steps.push(step(false, level));
        }
        for level in (0..counts.len() - 1).rev() {
            steps.push(step(true, level));
        }
        Ok(Scan { split, steps })
    }

    /// The pipelines these dispatches were made for.
    pub(crate) fn split(&self) -> Split {
        self.split
    }

    pub(crate) fn record(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder) -> Result<(), GpuError> {
        let pipelines = gpu.pipelines_for(self.split)?;
        for (add, bind, (x, y)) in &self.steps {
            let pipeline = if *add {
                &pipelines.scan_add
            } else {
                &pipelines.scan_blocks
            };
            crate::record_dispatch(enc, "scan", pipeline, bind, [*x, *y, 1]);
        }
        Ok(())
    }
}

/// Exclusive prefix sum of the first `n` elements of `data`, in place.
fn scan(gpu: &Gpu, split: Split, data: &Chunked, n: u64) -> Result<(), GpuError> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    Scan::new(gpu, split, data, n)?.record(gpu, &mut enc)?;
    gpu.submit(enc);
    gpu.wait()
}

/// Counts into `lists` (zeroed, `n_lists + 1` elements: the last becomes the
/// total), scans them into offsets in place, and fills the ids it sizes from
/// the total read back. Returns (ids, node count).
#[allow(clippy::too_many_arguments)]
pub(crate) fn fill_primitives(
    gpu: &Gpu,
    tris: &Chunked,
    views: &wgpu::Buffer,
    build_uniform: &wgpu::Buffer,
    hiz: &Chunked,
    lists: &Chunked,
    build: &BuildParams,
    content: &[u32],
    n_lists: u64,
) -> Result<(Chunked, u32), GpuError> {
    let split = Split::of(&[tris, hiz, lists]);
    if build.n_tris > 0 {
        let p = &gpu.pipelines_for(split)?.count;
        let bind = bind_buffers(
            gpu,
            "fill_primitives",
            &p.get_bind_group_layout(0),
            &with(
                &[(1, views), (2, build_uniform)],
                [
                    tris.bindings(gpu, split),
                    hiz.bindings(gpu, split),
                    lists.bindings(gpu, split),
                ],
            ),
        );
        draw_coverage(gpu, p, &bind, build, content);
    }
    scan(gpu, split, lists, n_lists + 1)?;
    let (chunk, at) = lists
        .locate(n_lists)
        .ok_or_else(|| GpuError::Device("the list offsets have no total".into()))?;
    let total = bytemuck::pod_read_unaligned::<u32>(&read_back(gpu, chunk, at, 4)?);
    let ids = Chunked::new(gpu, Kind::Ids, total as u64)?;
    if total > 0 {
        let cursors = Chunked::new(gpu, Kind::Offsets, n_lists + 1)?;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        lists.encode_copy(&mut enc, &cursors);
        gpu.submit(enc);
        let split = Split::of(&[tris, hiz, lists, &ids]);
        let p = &gpu.pipelines_for(split)?.fill;
        let bind = bind_buffers(
            gpu,
            "fill_primitives",
            &p.get_bind_group_layout(0),
            &with(
                &[(1, views), (2, build_uniform)],
                [
                    tris.bindings(gpu, split),
                    hiz.bindings(gpu, split),
                    cursors.bindings(gpu, split),
                    ids.bindings(gpu, split),
                ],
            ),
        );
        draw_coverage(gpu, p, &bind, build, content);
        gpu.wait()?;
    }
    Ok((ids, total))
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
            let buf =
                Chunked::with_data(gpu, Kind::Offsets, bytemuck::cast_slice(&data)).expect("fits");
            scan(gpu, Split::of(&[&buf]), &buf, n as u64).expect("scan");
            let got = bytemuck::pod_collect_to_vec::<u8, u32>(
                &crate::block("a test read", buf.read(gpu, n as u64)).expect("read"),
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

    /// Across chunks too: the offsets split into bindings of 256 words.
    #[test]
    fn the_prefix_sum_runs_across_chunks() {
        if crate::testing::any_gpu("the_prefix_sum_runs_across_chunks").is_none() {
            return;
        }
        let mut gpu = Gpu::new().expect("a second context");
        gpu.limits.max_storage_buffer_binding_size = 1024;
        let bindings = gpu.bindings(Kind::Offsets) as usize;
        for n in [300usize, 256 * bindings - 3] {
            let data: Vec<u32> = (0..n as u32).map(|i| (i * 7919) % 13).collect();
            let buf =
                Chunked::with_data(&gpu, Kind::Offsets, bytemuck::cast_slice(&data)).expect("fits");
            assert!(buf.is_split(), "n = {n}");
            scan(&gpu, Split::of(&[&buf]), &buf, n as u64).expect("scan");
            let got = bytemuck::pod_collect_to_vec::<u8, u32>(
                &crate::block("a test read", buf.read(&gpu, n as u64)).expect("read"),
            );
            let want: Vec<u32> = data
                .iter()
                .scan(0, |acc, x| {
                    let v = *acc;
                    *acc += x;
                    Some(v)
                })
                .collect();
            assert_eq!(got, want, "n = {n}");
        }
    }
}
