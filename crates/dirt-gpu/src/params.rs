//! Uniform structs of the passes. Each is declared here once; a test compares
//! size and offsets with the WGSL declarations as naga sees them.

use bytemuck::{Pod, Zeroable};

/// `struct BuildParams` of `coverage.wgsl`. repr(C), Pod, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct BuildParams {
    pub n_tris: u32,
    pub n_views: u32,
    pub tiles: u32,
    pub buckets: u32,
    /// List ids per chunk: `2^id_shift`.
    pub id_shift: u32,
    /// Triangles per chunk: `2^tri_shift`.
    pub tri_shift: u32,
    /// Hi-Z cells per chunk: `2^hiz_shift`.
    pub hiz_shift: u32,
    /// List offsets (counters, cursors) per chunk: `2^offset_shift`.
    pub offset_shift: u32,
}

/// `struct MipParams` of `mip_depth.wgsl`. repr(C), Pod, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct MipParams {
    pub src_base: u32,
    pub dst_base: u32,
    pub src_w: u32,
    pub dst_w: u32,
    /// Hi-Z cells per chunk: `2^shift`.
    pub shift: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `struct ScanParams` of `fill_primitives.wgsl`. repr(C), Pod, 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ScanParams {
    pub n: u32,
    /// Elements per data chunk: `2^shift`.
    pub shift: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `struct TraceParams` of `trace.wgsl`. repr(C), Pod, 64 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct TraceParams {
    pub n_rays: u32,
    pub n_views: u32,
    pub tiles: u32,
    pub buckets: u32,
    pub levels: u32,
    /// 0 = linear, 1 = Hi-Z.
    pub traversal: u32,
    /// Views with content ([`dirt_math::View::slot`]): blocks per Hi-Z level.
    pub n_slots: u32,
    /// Loop iterations per ray and dispatch (at most [`crate::trace::WORK_BUDGET`]).
    pub budget: u32,
    /// Rays the continuation pool has room for.
    pub capacity: u32,
    /// 1: write per-ray statistics.
    pub with_stats: u32,
    /// List ids per chunk: `2^id_shift`.
    pub id_shift: u32,
    /// List ids the chunks hold: a larger scan total means the lists did not fit.
    pub id_capacity: u32,
    /// Triangles per chunk: `2^tri_shift`.
    pub tri_shift: u32,
    /// Hi-Z cells per chunk: `2^hiz_shift`.
    pub hiz_shift: u32,
    /// List offsets per chunk: `2^offset_shift`.
    pub offset_shift: u32,
    /// 1: the first dispatch traces the rays below the count the pool's
    /// [`PoolHeader::count_in`] holds (copied from the caller's buffer,
    /// [`crate::TraceResources::encode_trace_counted`]), not all `n_rays`.
    pub counted: u32,
}

/// `struct PoolHeader` of `trace.wgsl`: the head of the continuation pool.
/// repr(C), Pod, 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct PoolHeader {
    /// Unfinished rays listed for the next continuation dispatch.
    pub count_in: u32,
    /// Unfinished rays listed by the dispatch running (zero between dispatches).
    pub count_out: u32,
    /// Which of the two to-do lists the next continuation reads.
    pub parity: u32,
    /// Continuation dispatches that had rays to continue.
    pub rounds: u32,
}

/// `struct ViewsParams` of `views.wgsl`. repr(C), Pod, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ViewsParams {
    pub n_tris: u32,
    /// 0 = cube, 1 = single, 2 = one orthographic view, 3 = two split.
    pub kind: u32,
    /// 1: `center` is given ([`dirt_core::AdsParams::center`]).
    pub has_center: u32,
    /// Triangles per chunk: `2^tri_shift`.
    pub tri_shift: u32,
    pub center: [f32; 3],
    /// The axis orthographic views look along ([`dirt_core::AdsParams::axis`]):
    /// 0, 1, 2, or 3 for the bounds' thinnest.
    pub axis: u32,
}

/// `struct FrameState` of `views.wgsl`: what the `views` stage reduces.
/// repr(C), Pod, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct FrameState {
    /// `!ordered(min x, y, z)`, `ordered(max x, y, z)` ([`dirt_math::encode`]).
    pub bounds: [u32; 6],
    /// `0xffffffff - index` of the first triangle with a non-finite vertex, or 0.
    pub bad: u32,
    /// Bit `v`: some triangle reaches a tile of view `v`.
    pub reach: u32,
}

/// `struct GatherParams` of `gather.wgsl`: one mesh. repr(C), Pod, 80 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherParams {
    /// Where the mesh's first triangle goes in the structure's triangles.
    pub first_tri: u32,
    pub n_tris: u32,
    /// Vertex stride and position offset in 4-byte words.
    pub stride: u32,
    pub offset: u32,
    /// 0: no indices, 1: u16, 2: u32.
    pub index_format: u32,
    pub first_index: u32,
    pub has_transform: u32,
    /// Triangles per output chunk: `2^tri_shift`.
    pub tri_shift: u32,
    /// [`dirt_core::gather::Affine`], row-major.
    pub rows: [[f32; 4]; 3],
}
