//! Buffers split across bindings (`ids.wgsl`, `tris.wgsl`, `hiz.wgsl`,
//! `offsets.wgsl`): chunk `c` holds elements `c·2^shift ..`, each chunk a
//! buffer and a binding of its own, so that one binding's size
//! (`max_storage_buffer_binding_size`, 128 MiB on lavapipe and in WebGPU by
//! default) bounds none of a structure's arrays; the device's memory and its
//! bindings ([`Gpu::bindings`]) do. [`dirt_core::BindingLimits`] is the rule,
//! shared with the cost model.

use crate::{Gpu, GpuError, read_back_async};
pub(crate) use dirt_core::SplitArray as Kind;

/// Which of a structure's arrays take more than one binding: one bit per
/// [`Kind`]. It chooses the pipelines a structure's passes run
/// ([`Gpu::pipelines_for`]): those with one binding per array when nothing is
/// split, so that a scene pays for the chunk `switch` only where it needs it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct Split(u8);

impl Split {
    /// Nothing split: the pipelines made with the [`Gpu`].
    pub(crate) const NONE: Split = Split(0);

    /// The variants there can be.
    pub(crate) const VARIANTS: usize = 16;

    fn bit(kind: Kind) -> u8 {
        match kind {
            Kind::Ids => 1,
            Kind::Tris => 2,
            Kind::Hiz => 4,
            Kind::Offsets => 8,
        }
    }

    /// The split arrays among `arrays`.
    pub(crate) fn of(arrays: &[&Chunked]) -> Split {
        Split(
            arrays
                .iter()
                .filter(|a| a.is_split())
                .fold(0, |m, a| m | Self::bit(a.kind)),
        )
    }

    /// Whether `kind` is split.
    pub(crate) fn has(self, kind: Kind) -> bool {
        self.0 & Self::bit(kind) != 0
    }

    /// The variant's index, `0..VARIANTS`.
    pub(crate) fn index(self) -> usize {
        self.0 as usize
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

/// The first binding of `kind`'s chunks in the shaders.
fn first_binding(kind: Kind) -> u32 {
    match kind {
        Kind::Ids => dirt_shaders::ID_BINDING,
        Kind::Tris => dirt_shaders::TRI_BINDING,
        Kind::Hiz => dirt_shaders::HIZ_BINDING,
        Kind::Offsets => dirt_shaders::OFFSET_BINDING,
    }
}

impl Chunked {
    /// Room for `count` elements (at least one), zeroed; an error naming the
    /// sizes when the device cannot bind that many.
    pub(crate) fn new(gpu: &Gpu, kind: Kind, count: u64) -> Result<Chunked, GpuError> {
        let limits = gpu.binding_limits();
        let (shift, capacity) = (limits.shift(kind), limits.capacity(kind));
        let elem = kind.elem_bytes();
        if count > capacity {
            return Err(GpuError::SplitTooLarge {
                what: kind.what(),
                bytes: count.saturating_mul(elem),
                bindings: limits.bindings(kind),
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
    /// [`Gpu::pipelines_for`]`(split)` declare, from the kind's first binding.
    pub(crate) fn bindings(&self, gpu: &Gpu, split: Split) -> Vec<(u32, &wgpu::Buffer)> {
        self.bindings_at(first_binding(self.kind), gpu, split)
    }

    /// [`Chunked::bindings`] from binding `first` (the prefix sum binds the
    /// offsets at its own bindings).
    pub(crate) fn bindings_at(
        &self,
        first: u32,
        gpu: &Gpu,
        split: Split,
    ) -> Vec<(u32, &wgpu::Buffer)> {
        (0..gpu.declared(split, self.kind))
            .map(|c| {
                (
                    first + c,
                    self.chunks.get(c as usize).unwrap_or(&self.spare),
                )
            })
            .collect()
    }

    /// The chunk holding element `at`, and the element's byte offset in it.
    pub(crate) fn locate(&self, at: u64) -> Option<(&wgpu::Buffer, u64)> {
        let chunk = self.chunks.get((at >> self.shift) as usize)?;
        Some((
            chunk,
            (at & ((1u64 << self.shift) - 1)) * self.kind.elem_bytes(),
        ))
    }

    /// Records zeroing every chunk.
    pub(crate) fn encode_clear(&self, enc: &mut wgpu::CommandEncoder) {
        for c in &self.chunks {
            enc.clear_buffer(c, 0, None);
        }
    }

    /// Records a copy of every chunk into `dst`'s (an array made alike).
    pub(crate) fn encode_copy(&self, enc: &mut wgpu::CommandEncoder, dst: &Chunked) {
        for (a, b) in self.chunks.iter().zip(&dst.chunks) {
            enc.copy_buffer_to_buffer(a, 0, b, 0, a.size().min(b.size()));
        }
    }

    /// The first `count` elements, read back, as bytes laid end to end.
    pub(crate) async fn read(&self, gpu: &Gpu, count: u64) -> Result<Vec<u8>, GpuError> {
        let elem = self.kind.elem_bytes();
        let per_chunk = 1u64 << self.shift;
        let mut out = Vec::with_capacity((count * elem) as usize);
        for (c, buf) in self.chunks.iter().enumerate() {
            let start = c as u64 * per_chunk;
            if start >= count {
                break;
            }
            let n = (count - start).min(per_chunk);
            out.extend(read_back_async(gpu, buf, 0, n * elem).await?);
        }
        Ok(out)
    }
}
