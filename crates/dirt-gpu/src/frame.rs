//! Builds recorded into an application's frame: [`GpuAds::frame`] makes a
//! structure whose buffers are kept between frames, and
//! [`GpuAds::encode_build`] records a whole build — `gather`, `views`,
//! `fill_depth`, `mip_depth`, `fill_primitives` — into the caller's command
//! encoder, from the application's vertex and index buffers, with no
//! submission, no wait and no read-back.
//!
//! **List storage without a read-back.** The number of list entries is known
//! only on the GPU, after the count and the scan. The ids (split across
//! bindings, see [`crate::Gpu::id_bindings`]) are therefore sized ahead: from
//! the caller's hint at first, then from the count of the latest completed
//! build plus a quarter (as far as the id bindings allow). `fill` writes no
//! entry past their end; the trace compares the scan's total with their
//! capacity and, when
//! they did not fit, writes [`crate::trace::STRUCTURE_FULL`] as every ray's
//! hit (statistics zero) — an incomplete structure is never traced. Each
//! build also copies its total into a small buffer mapped when its
//! submission completes ([`wgpu::CommandEncoder::map_buffer_on_submit`]);
//! the next `encode_build` grows the ids to fit. So an overflow costs the
//! frame it happens in, is seen in [`GpuAds::feedback`] (`overflows`), and
//! the caller re-records that frame (or the next one fits by itself).
//!
//! **Synchronisation.** The structure's uniforms are written with
//! [`wgpu::Queue::write_buffer`], which takes effect at the next submission:
//! record at most one build of a structure per submission. The structure
//! owns its buffers; the caller owns the meshes, rays and hits, and must keep
//! them alive until the submission completes (wgpu does this for it).

use crate::chunked::{Chunked, Kind, Split};
use crate::fill_depth::{record_coverage, tile_target};
use crate::fill_primitives::{Scan, grid};
use crate::gather::GpuMesh;
use crate::mip_depth::MipDepth;
use crate::{
    BuildParams, FrameState, Gpu, GpuAds, GpuError, ViewsParams, bind_buffers, buffer, with,
};
use dirt_core::{AdsParams, BuildTimings, CoreError};
use dirt_math::ViewsKind;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};

/// What the completed builds of a frame structure said (see [`GpuAds::feedback`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildFeedback {
    /// Builds recorded so far.
    pub recorded: u64,
    /// Builds whose submission completed (their counts below are known).
    pub completed: u64,
    /// List entries the latest completed build needed.
    pub entries_needed: u64,
    /// List entries the ids buffer holds now.
    pub capacity: u64,
    /// Completed builds whose lists did not fit: their traces reported
    /// [`crate::trace::STRUCTURE_FULL`]; re-record such a frame.
    pub overflows: u64,
    /// Times the ids buffer was grown to fit a completed build's count.
    pub grown: u64,
    /// The first triangle with a non-finite vertex in the latest completed
    /// build: that build has no views with content, and every ray missed.
    pub non_finite: Option<u32>,
}

#[derive(Debug, Default)]
struct Shared {
    completed: AtomicU64,
    needed: AtomicU64,
    overflows: AtomicU64,
    /// `0xffffffff - index` of a non-finite triangle, or 0 (as `FrameState::bad`).
    bad: AtomicU32,
}

/// The kept parts of a frame structure besides the buffers `GpuAds` has.
#[derive(Debug)]
pub(crate) struct Frame {
    state: wgpu::Buffer,
    views_params: wgpu::Buffer,
    build_params: wgpu::Buffer,
    gather_params: Vec<wgpu::Buffer>,
    target: wgpu::TextureView,
    scan: Scan,
    /// The cursors of `fill`: a copy of the offsets, split alike.
    cursors: Chunked,
    mip: MipDepth,
    n_lists: u64,
    cells: u64,
    shared: Arc<Shared>,
    /// Small read-back buffers of the list total and the fault word; the flag
    /// is set while one is in flight.
    staging: Vec<(wgpu::Buffer, Arc<AtomicBool>)>,
    recorded: u64,
    grown: u64,
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE;
const COPY_SRC: wgpu::BufferUsages = wgpu::BufferUsages::COPY_SRC;
const COPY_DST: wgpu::BufferUsages = wgpu::BufferUsages::COPY_DST;

impl GpuAds {
    /// An empty structure for builds recorded with [`GpuAds::encode_build`]:
    /// the Hi-Z pyramid, list offsets and every kept buffer are made here,
    /// sized from `params` for every view; the triangles when the first build
    /// says how many; the ids for `entries_hint` list entries at first (a
    /// guess: a build that needs more overflows once, and the ids grow).
    pub fn frame(gpu: &Gpu, params: &AdsParams, entries_hint: u64) -> Result<GpuAds, GpuError> {
        gpu.scoped("making a frame structure", || {
            Self::frame_unscoped(gpu, params, entries_hint)
        })
    }

    fn frame_unscoped(
        gpu: &Gpu,
        params: &AdsParams,
        entries_hint: u64,
    ) -> Result<GpuAds, GpuError> {
        params.validate()?;
        let tiles = params.tiles();
        let n_views = params.views.view_count() as u32;
        let cells = crate::hiz_cells(tiles, n_views);
        let n_lists = n_views as u64 * (tiles as u64).pow(2) * params.buckets as u64;
        let capacity = entries_hint.max(4);
        let hiz = Chunked::new(gpu, Kind::Hiz, cells)?;
        let offsets = Chunked::new(gpu, Kind::Offsets, n_lists + 1)?;
        let cursors = Chunked::new(gpu, Kind::Offsets, n_lists + 1)?;
        let ids = Chunked::new(gpu, Kind::Ids, capacity)?;
        let tris = Chunked::new(gpu, Kind::Tris, 0)?;
        let split = Split::of(&[&tris, &ids, &hiz, &offsets]);

        let template = crate::views::template(params.views, tiles);
        let views_uniform = crate::buffer_init(
            gpu,
            "views",
            bytemuck::cast_slice(&template),
            wgpu::BufferUsages::UNIFORM | STORAGE | COPY_SRC,
        );
        let uniform = wgpu::BufferUsages::UNIFORM | COPY_DST;
        let frame = Frame {
            state: buffer(
                gpu,
                "frame state",
                std::mem::size_of::<FrameState>() as u64,
                STORAGE | COPY_SRC | COPY_DST,
            ),
            views_params: buffer(
                gpu,
                "views params",
                std::mem::size_of::<ViewsParams>() as u64,
                uniform,
            ),
            build_params: buffer(
                gpu,
                "build params",
                std::mem::size_of::<BuildParams>() as u64,
                uniform,
            ),
            gather_params: Vec::new(),
            target: tile_target(gpu, tiles),
            scan: Scan::new(gpu, split, &offsets, n_lists + 1)?,
            cursors,
            mip: MipDepth::new(gpu, split, &hiz, tiles, n_views)?,
            n_lists,
            cells,
            shared: Arc::default(),
            staging: Vec::new(),
            recorded: 0,
            grown: 0,
        };
        Ok(GpuAds {
            params: *params,
            views: None,
            n_tris: 0,
            nodes: 0,
            timings: BuildTimings::default(),
            n_views,
            n_slots: n_views,
            tris,
            views_uniform,
            hiz,
            offsets,
            ids,
            frame: Some(Box::new(frame)),
        })
    }

    /// What the completed builds said: list entries needed and held,
    /// overflows, non-finite input. `None` for a structure built from host
    /// triangles ([`GpuAds::build`]), whose count is exact.
    pub fn feedback(&self) -> Option<BuildFeedback> {
        let f = self.frame.as_ref()?;
        let bad = f.shared.bad.load(Ordering::Acquire);
        Some(BuildFeedback {
            recorded: f.recorded,
            completed: f.shared.completed.load(Ordering::Acquire),
            entries_needed: f.shared.needed.load(Ordering::Acquire),
            capacity: self.ids.capacity(),
            overflows: f.shared.overflows.load(Ordering::Acquire),
            grown: f.grown,
            non_finite: (bad != 0).then(|| u32::MAX - bad),
        })
    }

    /// The latest build's list total and fault word read back, once its
    /// submission is done: the feedback of that build, awaited instead of
    /// left to the map callback (a browser runs that callback on its event
    /// loop, at no time a page can wait for). What is read is also noted as
    /// the latest completed build's, so the next build grows the ids to fit.
    pub(crate) async fn settle_feedback(
        &self,
        gpu: &Gpu,
    ) -> Result<Option<BuildFeedback>, GpuError> {
        let Some(f) = self.frame.as_ref() else {
            return Ok(None);
        };
        let staging = buffer(
            gpu,
            "build feedback (awaited)",
            8,
            wgpu::BufferUsages::MAP_READ | COPY_DST,
        );
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        f.copy_counts(&mut enc, &self.offsets, &staging)?;
        gpu.submit(enc);
        let bytes = crate::map_read_async(gpu, &staging).await?;
        let words = bytes
            .get(..8)
            .ok_or_else(|| GpuError::Readback("the build feedback came back short".into()))?;
        let [needed, bad]: [u32; 2] = bytemuck::pod_read_unaligned(words);
        f.shared.needed.store(needed as u64, Ordering::Release);
        f.shared.bad.store(bad, Ordering::Release);
        Ok(self.feedback())
    }

    /// Records a build over `meshes` (their triangles in order, ids counted
    /// from the first mesh's first triangle) into `enc`. Nothing is submitted
    /// or waited for. Errors come before anything is recorded: a structure
    /// made by [`GpuAds::build`], a mesh whose buffers or layout are wrong,
    /// or buffers the device cannot bind.
    pub fn encode_build(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        meshes: &[GpuMesh<'_>],
    ) -> Result<(), GpuError> {
        gpu.scoped("encode_build", || {
            self.encode_build_unscoped(gpu, enc, meshes)
        })
    }

    fn encode_build_unscoped(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        meshes: &[GpuMesh<'_>],
    ) -> Result<(), GpuError> {
        let Some(frame) = self.frame.as_mut() else {
            return Err(GpuError::Params(CoreError::InvalidParams(
                "encode_build needs a structure made by GpuAds::frame".into(),
            )));
        };
        let mut n_tris: u32 = 0;
        for m in meshes {
            m.check()?;
            n_tris = n_tris.checked_add(m.layout.triangles).ok_or_else(|| {
                GpuError::Params(CoreError::InvalidParams(
                    "the meshes hold more than 2^32-1 triangles".into(),
                ))
            })?;
        }
        if n_tris as u64 > self.tris.capacity() {
            self.tris = Chunked::new(gpu, Kind::Tris, n_tris as u64)?;
        }
        // Grow what the latest completed build (or this one's count) says is too small.
        let needed = frame.shared.needed.load(Ordering::Acquire);
        if needed > self.ids.capacity() {
            // The quarter of headroom only as far as the device binds; the
            // count itself must fit, or the build is refused by name.
            let limit = gpu.binding_limits().capacity(Kind::Ids);
            let capacity = (needed + needed / 4).min(limit.max(needed));
            self.ids = Chunked::new(gpu, Kind::Ids, capacity)?;
            frame.grown += 1;
        }
        let tiles = self.params.tiles();
        let build = BuildParams {
            n_tris,
            n_views: self.n_views,
            tiles,
            buckets: self.params.buckets,
            id_shift: self.ids.shift(),
            tri_shift: self.tris.shift(),
            hiz_shift: self.hiz.shift(),
            offset_shift: self.offsets.shift(),
        };
        gpu.queue
            .write_buffer(&frame.build_params, 0, bytemuck::bytes_of(&build));
        let center = self.params.center;
        let views_params = ViewsParams {
            n_tris,
            kind: match self.params.views {
                ViewsKind::Cube => 0,
                ViewsKind::Single => 1,
                ViewsKind::Ortho => 2,
                ViewsKind::OrthoSplit => 3,
            },
            axis: self.params.axis.map_or(3, |a| a.index() as u32),
            has_center: center.is_some() as u32,
            tri_shift: self.tris.shift(),
            center: center.map_or([0.0; 3], |c| c.to_array()),
        };
        gpu.queue
            .write_buffer(&frame.views_params, 0, bytemuck::bytes_of(&views_params));
        while frame.gather_params.len() < meshes.len() {
            frame.gather_params.push(buffer(
                gpu,
                "gather params",
                std::mem::size_of::<crate::GatherParams>() as u64,
                wgpu::BufferUsages::UNIFORM | COPY_DST,
            ));
        }

        // The pipelines for this structure's bindings, compiled if need be
        // before anything is recorded (`GpuAds::split`, field by field:
        // `frame` borrows `self.frame`); the kept dispatches remade when the
        // triangles or the ids have come to take more bindings or fewer.
        let split = Split::of(&[&self.tris, &self.ids, &self.hiz, &self.offsets]);
        let pipelines = gpu.pipelines_for(split)?;
        if frame.mip.split() != split {
            frame.mip = MipDepth::new(gpu, split, &self.hiz, tiles, self.n_views)?;
        }
        if frame.scan.split() != split {
            frame.scan = Scan::new(gpu, split, &self.offsets, frame.n_lists + 1)?;
        }

        enc.clear_buffer(&frame.state, 0, None);
        self.offsets.encode_clear(enc);
        let mut first = 0u32;
        for (m, uniform) in meshes.iter().zip(&frame.gather_params) {
            gpu.queue.write_buffer(
                uniform,
                0,
                bytemuck::bytes_of(&m.params(first, self.tris.shift())),
            );
            crate::gather::record(gpu, pipelines, split, enc, m, uniform, &self.tris);
            first += m.layout.triangles;
        }
        crate::views::record(
            gpu,
            pipelines,
            split,
            enc,
            &self.tris,
            &self.views_uniform,
            &frame.state,
            &frame.views_params,
            n_tris,
            self.n_views,
        );
        {
            let p = &pipelines.clear_depth;
            let bind = bind_buffers(
                gpu,
                "clear_depth",
                &p.get_bind_group_layout(0),
                &with(&[(2, &frame.build_params)], [self.hiz.bindings(gpu, split)]),
            );
            let (x, y) = grid(gpu, frame.cells.div_ceil(64));
            crate::record_dispatch(enc, "clear_depth", p, &bind, [x, y, 1]);
        }
        if n_tris > 0 {
            let fd = &pipelines.fill_depth;
            let bind = bind_buffers(
                gpu,
                "fill_depth",
                &fd.get_bind_group_layout(0),
                &with(
                    &[(1, &self.views_uniform), (2, &frame.build_params)],
                    [
                        self.tris.bindings(gpu, split),
                        self.hiz.bindings(gpu, split),
                    ],
                ),
            );
            record_coverage(enc, &frame.target, fd, &bind, n_tris, 0..self.n_views);
        }
        frame.mip.record(gpu, enc)?;
        if n_tris > 0 {
            let count = &pipelines.count;
            let bind = bind_buffers(
                gpu,
                "fill_primitives count",
                &count.get_bind_group_layout(0),
                &with(
                    &[(1, &self.views_uniform), (2, &frame.build_params)],
                    [
                        self.tris.bindings(gpu, split),
                        self.hiz.bindings(gpu, split),
                        self.offsets.bindings(gpu, split),
                    ],
                ),
            );
            record_coverage(enc, &frame.target, count, &bind, n_tris, 0..self.n_views);
        }
        frame.scan.record(gpu, enc)?;
        if n_tris > 0 {
            self.offsets.encode_copy(enc, &frame.cursors);
            let fill = &pipelines.fill;
            let bind = bind_buffers(
                gpu,
                "fill_primitives fill",
                &fill.get_bind_group_layout(0),
                &with(
                    &[(1, &self.views_uniform), (2, &frame.build_params)],
                    [
                        self.tris.bindings(gpu, split),
                        self.hiz.bindings(gpu, split),
                        frame.cursors.bindings(gpu, split),
                        self.ids.bindings(gpu, split),
                    ],
                ),
            );
            record_coverage(enc, &frame.target, fill, &bind, n_tris, 0..self.n_views);
        }
        frame.record_feedback(gpu, enc, &self.offsets, self.ids.capacity())?;
        frame.recorded += 1;
        self.n_tris = n_tris;
        Ok(())
    }
}

impl Frame {
    /// Records copies of the list total (the offsets' last entry) and the
    /// fault word into the first 8 bytes of `dst`: a build's feedback.
    fn copy_counts(
        &self,
        enc: &mut wgpu::CommandEncoder,
        offsets: &Chunked,
        dst: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let (total, total_at) = offsets
            .locate(self.n_lists)
            .ok_or_else(|| GpuError::Device("the list offsets have no total".into()))?;
        enc.copy_buffer_to_buffer(total, total_at, dst, 0, 4);
        let bad_at = std::mem::offset_of!(FrameState, bad) as u64;
        enc.copy_buffer_to_buffer(&self.state, bad_at, dst, 4, 4);
        Ok(())
    }

    /// Copies the list total and the fault word into a free read-back
    /// buffer, mapped when the submission completes; the callback records
    /// them in `shared`. Nothing waits for it.
    fn record_feedback(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        offsets: &Chunked,
        capacity: u64,
    ) -> Result<(), GpuError> {
        let free = self
            .staging
            .iter()
            .position(|(_, busy)| !busy.load(Ordering::Acquire));
        let k = free.unwrap_or_else(|| {
            self.staging.push((
                buffer(
                    gpu,
                    "build feedback",
                    8,
                    wgpu::BufferUsages::MAP_READ | COPY_DST,
                ),
                Arc::new(AtomicBool::new(false)),
            ));
            self.staging.len() - 1
        });
        let (buf, busy) = self.staging[k].clone();
        self.copy_counts(enc, offsets, &buf)?;
        busy.store(true, Ordering::Release);
        let shared = self.shared.clone();
        let mapped = buf.clone();
        enc.map_buffer_on_submit(&buf, wgpu::MapMode::Read, 0..8, move |r| {
            if r.is_ok() {
                if let Ok(view) = mapped.get_mapped_range(0..8) {
                    let [total, bad]: [u32; 2] = bytemuck::pod_read_unaligned(&view[..8]);
                    drop(view);
                    shared.needed.store(total as u64, Ordering::Release);
                    shared.bad.store(bad, Ordering::Release);
                    if total as u64 > capacity {
                        shared.overflows.fetch_add(1, Ordering::AcqRel);
                    }
                    shared.completed.fetch_add(1, Ordering::AcqRel);
                }
                mapped.unmap();
            }
            busy.store(false, Ordering::Release);
        });
        Ok(())
    }
}
