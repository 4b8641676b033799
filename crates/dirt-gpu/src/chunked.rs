//! Buffers split across bindings (`ids.wgsl`, `tris.wgsl`): chunk `c` holds
//! elements `c·2^shift ..`, each chunk a buffer and a binding of its own, so
//! that one binding's size (`max_storage_buffer_binding_size`, 128 MiB on
//! lavapipe and in WebGPU by default) does not bound a scene's triangles or
//! its list entries; the device's memory and its bindings
//! ([`Gpu::id_bindings`], [`Gpu::tri_bindings`]) do.
//! [`dirt_core::BindingLimits`] is the rule, shared with the cost model.

use crate::{Gpu, GpuError, read_back};

/// Which split array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// List ids, 4 bytes each.
    Ids,
    /// Triangles, 36 bytes each.
    Tris,
}

impl Kind {
    fn elem_bytes(self) -> u64 {
        match self {
            Kind::Ids => dirt_core::BindingLimits::ID_BYTES,
            Kind::Tris => dirt_core::BindingLimits::TRI_BYTES,
        }
    }

    fn what(self) -> &'static str {
        match self {
            Kind::Ids => "the list ids",
            Kind::Tris => "the triangles",
        }
    }
}

/// A split array's buffers: as many chunks as its elements need, and a
/// small spare bound in the place of each chunk not needed.
#[derive(Debug)]
pub(crate) struct Chunked {
    kind: Kind,
    chunks: Vec<wgpu::Buffer>,
    spare: wgpu::Buffer,
    /// log2 of the elements per chunk.
    shift: u32,
    /// Elements the chunks hold.
    capacity: u64,
}

impl Chunked {
    /// Room for `count` elements (at least one), zeroed; an error naming the
    /// sizes when the device cannot bind that many.
    pub(crate) fn new(gpu: &Gpu, kind: Kind, count: u64) -> Result<Chunked, GpuError> {
        let limits = gpu.binding_limits();
        let (shift, capacity, bindings) = match kind {
            Kind::Ids => (limits.id_shift(), limits.id_capacity(), limits.id_bindings),
            Kind::Tris => (
                limits.tri_shift(),
                limits.tri_capacity(),
                limits.tri_bindings,
            ),
        };
        let elem = kind.elem_bytes();
        if count > capacity {
            return Err(GpuError::SplitTooLarge {
                what: kind.what(),
                bytes: count.saturating_mul(elem),
                bindings,
                per_binding: elem << shift,
            });
        }
        let per_chunk = 1u64 << shift;
        let count = count.max(1);
        let chunks: Vec<wgpu::Buffer> = (0..count.div_ceil(per_chunk))
            .map(|c| {
                let n = per_chunk.min(count - c * per_chunk);
                crate::buffer(
                    gpu,
                    kind.what(),
                    n * elem,
                    wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                )
            })
            .collect();
        let capacity = chunks.iter().map(|b| b.size() / elem).sum();
        Ok(Chunked {
            kind,
            chunks,
            spare: crate::buffer(gpu, "spare chunk", 16, wgpu::BufferUsages::STORAGE),
            shift,
            capacity,
        })
    }

    /// Chunks holding `data` (elements of the kind's size, laid end to end),
    /// written through the queue.
    pub(crate) fn with_data(gpu: &Gpu, kind: Kind, data: &[u8]) -> Result<Chunked, GpuError> {
        let elem = kind.elem_bytes();
        let out = Self::new(gpu, kind, data.len() as u64 / elem)?;
        let per_chunk = (elem << out.shift) as usize;
        for (buf, part) in out.chunks.iter().zip(data.chunks(per_chunk)) {
            gpu.queue.write_buffer(buf, 0, part);
        }
        Ok(out)
    }

    /// log2 of the elements per chunk, for the passes' uniforms.
    pub(crate) fn shift(&self) -> u32 {
        self.shift
    }

    /// Elements the chunks hold.
    pub(crate) fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Chunks in use.
    pub(crate) fn chunks(&self) -> usize {
        self.chunks.len()
    }

    /// Bytes allocated.
    pub(crate) fn bytes(&self) -> u64 {
        self.chunks.iter().map(|b| b.size()).sum()
    }

    /// Whether this array takes more than one binding.
    pub(crate) fn is_split(&self) -> bool {
        self.chunks.len() > 1
    }

    /// `(binding, buffer)` for every binding of the kind the pipelines of
    /// [`Gpu::pipelines_for`]`(split)` declare.
    pub(crate) fn bindings(&self, gpu: &Gpu, split: bool) -> Vec<(u32, &wgpu::Buffer)> {
        let counts = gpu.chunk_bindings(split);
        let (first, n) = match self.kind {
            Kind::Ids => (dirt_shaders::ID_BINDING, counts.ids),
            Kind::Tris => (dirt_shaders::TRI_BINDING, counts.tris),
        };
        (0..n)
            .map(|c| {
                (
                    first + c,
                    self.chunks.get(c as usize).unwrap_or(&self.spare),
                )
            })
            .collect()
    }

    /// The first `count` elements, read back, as bytes laid end to end.
    pub(crate) fn read(&self, gpu: &Gpu, count: u64) -> Result<Vec<u8>, GpuError> {
        let elem = self.kind.elem_bytes();
        let per_chunk = 1u64 << self.shift;
        let mut out = Vec::with_capacity((count * elem) as usize);
        for (c, buf) in self.chunks.iter().enumerate() {
            let start = c as u64 * per_chunk;
            if start >= count {
                break;
            }
            let n = (count - start).min(per_chunk);
            out.extend(read_back(gpu, buf, 0, n * elem)?);
        }
        Ok(out)
    }
}
