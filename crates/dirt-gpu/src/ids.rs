//! The list ids on the GPU, split across bindings (`ids.wgsl`): chunk `c`
//! holds entries `c·2^shift ..`, so that one binding's size
//! (`max_storage_buffer_binding_size`, 128 MiB on lavapipe and in WebGPU by
//! default) does not bound how many list entries a structure has; the
//! device's memory and [`Gpu::id_bindings`] do. [`dirt_core::BindingLimits`]
//! is the rule, shared with the cost model.

use crate::{Gpu, GpuError, read_back};

/// The ids' buffers: as many chunks as the entries need, each a buffer of
/// its own (so no buffer exceeds one binding), and a small spare bound in
/// the place of each chunk not needed.
#[derive(Debug)]
pub(crate) struct Ids {
    chunks: Vec<wgpu::Buffer>,
    spare: wgpu::Buffer,
    /// log2 of the entries per chunk.
    shift: u32,
    /// Entries the chunks hold.
    capacity: u64,
}

impl Ids {
    /// Room for `entries` list entries (at least 4), zeroed; an error naming
    /// the sizes when the device cannot bind that many.
    pub(crate) fn new(gpu: &Gpu, entries: u64) -> Result<Ids, GpuError> {
        let limits = gpu.binding_limits();
        if entries > limits.id_capacity() {
            return Err(GpuError::IdsTooLarge {
                bytes: entries * 4,
                bindings: limits.id_bindings,
                per_binding: 4u64 << limits.id_shift(),
            });
        }
        let shift = limits.id_shift();
        let per_chunk = 1u64 << shift;
        let entries = entries.max(4);
        let chunks: Vec<wgpu::Buffer> = (0..entries.div_ceil(per_chunk))
            .map(|c| {
                let n = per_chunk.min(entries - c * per_chunk);
                crate::new_buffer(gpu, "ids", n * 4, wgpu::BufferUsages::COPY_SRC)
            })
            .collect();
        let capacity = chunks.iter().map(|b| b.size() / 4).sum();
        Ok(Ids {
            chunks,
            spare: crate::new_buffer(gpu, "ids (spare)", 16, wgpu::BufferUsages::empty()),
            shift,
            capacity,
        })
    }

    /// log2 of the entries per chunk, for the passes' uniforms.
    pub(crate) fn shift(&self) -> u32 {
        self.shift
    }

    /// Entries the chunks hold.
    pub(crate) fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Chunks in use.
    pub(crate) fn chunks(&self) -> usize {
        self.chunks.len()
    }

    /// Bytes allocated for the ids.
    pub(crate) fn bytes(&self) -> u64 {
        self.chunks.iter().map(|b| b.size()).sum()
    }

    /// `(binding, buffer)` for every id binding of the pipelines.
    pub(crate) fn bindings(&self, gpu: &Gpu) -> Vec<(u32, &wgpu::Buffer)> {
        (0..gpu.id_bindings())
            .map(|c| {
                (
                    dirt_shaders::ID_BINDING + c,
                    self.chunks.get(c as usize).unwrap_or(&self.spare),
                )
            })
            .collect()
    }

    /// The first `total` entries, read back.
    pub(crate) fn read(&self, gpu: &Gpu, total: u64) -> Result<Vec<u32>, GpuError> {
        let per_chunk = 1u64 << self.shift;
        let mut out = Vec::with_capacity(total as usize);
        for (c, buf) in self.chunks.iter().enumerate() {
            let start = c as u64 * per_chunk;
            if start >= total {
                break;
            }
            let n = (total - start).min(per_chunk);
            out.extend(bytemuck::pod_collect_to_vec::<u8, u32>(&read_back(
                gpu,
                buf,
                0,
                n * 4,
            )?));
        }
        Ok(out)
    }
}
