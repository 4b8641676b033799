//! Pass `trace` (`trace.wgsl`): closest hits of a ray buffer into a hit
//! buffer, recorded into the caller's command encoder. Mirrors `dirt_cpu::trace`.
//!
//! Each ray has a budget of loop iterations per dispatch ([`WORK_BUDGET`]):
//! lavapipe silently ends all loops of an invocation after 65535 iterations,
//! and a long dispatch stalls any GPU. A ray that spends its budget saves
//! where its walk stands in the continuation pool and is listed as
//! unfinished; the `schedule` pass turns the list into an indirect dispatch
//! of `trace_continue`, which resumes each listed ray exactly where it
//! stopped. Hits and statistics are those of one uninterrupted walk, bit for
//! bit; no CPU takes part. [`TraceResources::encode_trace`] records the first
//! dispatch and [`TraceResources::rounds`] continuation rounds;
//! [`TraceResources::encode_continue`] records more, and the pool's
//! [`PoolHeader`] says how many rays are still unfinished and how many
//! rounds ran.
//!
//! Buffer layouts, byte for byte: rays are `dirt_math::Ray` (32 bytes:
//! origin xyz, tmin, dir xyz, tmax, all f32), hits `dirt_math::Hit` (16
//! bytes: prim u32, t, u, v f32; prim `0xffffffff` a miss, [`UNFINISHED`] a
//! ray still being traced), statistics `dirt_math::RayStats` (16 bytes: views,
//! tiles, buckets, tests, u32), little-endian, tightly packed.

use crate::fill_primitives::grid;
use crate::{Gpu, GpuAds, GpuError, PoolHeader, TraceParams, map_read_async, read_back};
use dirt_core::Traversal;
use dirt_math::dda::hiz_levels;
use dirt_math::{Hit, Ray, RayStats};
use std::collections::HashMap;

/// Rays per submission of the host-slice wrapper: keeps each submission short.
const CHUNK: usize = 1 << 18;

/// The primitive id of a ray that is still being traced (its budget spent,
/// its continuation not yet run).
pub const UNFINISHED: u32 = 0xffff_fffe;

/// The primitive id of every ray traced through a frame structure whose
/// lists did not fit their ids (see [`crate::frame`]): the structure is
/// incomplete and the hits unknown; build again and trace again.
pub const STRUCTURE_FULL: u32 = 0xffff_fffd;

/// Loop iterations a ray may run per dispatch, at most. Lavapipe ends every
/// loop of a SIMD group silently after 65535 iterations in all, and a group's
/// count is more than the sum of its lanes' budgets: measured on cornell, cube
/// r1024 B4, 2,000 rays with walks of up to 60,000 iterations, budgets of 7000
/// and 3000 left 72 and 1 rays with a walk cut short (a miss where the CPU
/// hits); 1000 left none, at either traversal.
pub const WORK_BUDGET: u32 = 1000;

/// Words of a ray's saved walk in the pool (`trace.wgsl`'s `STATE_WORDS`).
pub const STATE_WORDS: u64 = 16;

/// Continuation rounds recorded after the first dispatch, by default.
pub const ROUNDS: u32 = 4;

/// Pool bytes per ray: a place in each of the two to-do lists and a saved walk.
const POOL_BYTES_PER_RAY: u64 = (2 + STATE_WORDS) * 4;
const HEADER_BYTES: u64 = std::mem::size_of::<PoolHeader>() as u64;

/// Closest hits and per-ray statistics of `rays`. Rays that fail
/// [`Ray::validate`] (non-finite values, a zero direction, a bad range) miss,
/// as in `dirt_cpu::trace` and `dirt_cpu::brute_force::trace`; so does a
/// valid ray whose hit parameter `t` would overflow `f32`.
pub fn trace(
    gpu: &Gpu,
    ads: &GpuAds,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
    let t = trace_report(gpu, ads, rays, traversal)?;
    Ok((t.hits, t.stats))
}

/// What [`trace_report`] returns.
#[derive(Clone, Debug, Default)]
pub struct Traced {
    pub hits: Vec<Hit>,
    pub stats: Vec<RayStats>,
    /// Continuation dispatches that had rays to continue, summed over submissions.
    pub rounds: u32,
    /// Submissions made (one per chunk of rays, plus one per extra batch of rounds).
    pub submissions: u32,
}

/// [`trace`], also saying how many continuation rounds it took.
pub fn trace_report(
    gpu: &Gpu,
    ads: &GpuAds,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<Traced, GpuError> {
    TraceResources::new(gpu).trace_host(gpu, ads, rays, traversal, true)
}

/// The trace's buffers that live from frame to frame: the continuation pool,
/// the indirect dispatch arguments, the parameter uniforms (one per distinct
/// set of parameters, kept) and the last bind group (for
/// [`TraceResources::encode_continue`]). Make one per tracer and reuse it.
#[derive(Debug)]
pub struct TraceResources {
    /// Loop iterations per ray and dispatch (1..=[`WORK_BUDGET`]). Lower
    /// values make more continuation rounds (the tests force them so).
    pub budget: u32,
    /// Continuation rounds recorded by each encode call.
    pub rounds: u32,
    pool: Option<wgpu::Buffer>,
    capacity: u32,
    dispatch: wgpu::Buffer,
    no_stats: wgpu::Buffer,
    params: HashMap<TraceParams, wgpu::Buffer>,
    /// The last trace's bind group, and the split arrays of its pipelines.
    bind: Option<(wgpu::BindGroup, crate::chunked::Split)>,
    schedule_bind: Option<wgpu::BindGroup>,
}

fn check_buffer(
    what: &'static str,
    buf: &wgpu::Buffer,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> Result<(), GpuError> {
    if buf.size() < bytes {
        return Err(GpuError::Buffer {
            what,
            problem: format!("holds {} bytes, the trace needs {bytes}", buf.size()),
        });
    }
    if !buf.usage().contains(usage) {
        return Err(GpuError::Buffer {
            what,
            problem: format!("has usage {:?}, the trace needs {usage:?}", buf.usage()),
        });
    }
    Ok(())
}

fn binding(buf: &wgpu::Buffer, bytes: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer: buf,
        offset: 0,
        size: wgpu::BufferSize::new(bytes.max(4)),
    })
}

impl TraceResources {
    /// Resources for tracing on `gpu`; the pool is made at the first trace,
    /// sized for its rays, and grows when a trace needs more.
    pub fn new(gpu: &Gpu) -> Self {
        let dispatch = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("trace dispatch"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let no_stats = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("no statistics"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        TraceResources {
            budget: WORK_BUDGET,
            rounds: ROUNDS,
            pool: None,
            capacity: 0,
            dispatch,
            no_stats,
            params: HashMap::new(),
            bind: None,
            schedule_bind: None,
        }
    }

    /// The most rays one encode call takes on `gpu`: the pool must fit one
    /// binding, and a continuation dispatch one row of workgroups.
    pub fn max_rays(gpu: &Gpu) -> u32 {
        // The pool (72 bytes a ray) is the largest binding; rays take 32, hits 16.
        let by_binding = gpu
            .limits
            .max_storage_buffer_binding_size
            .saturating_sub(HEADER_BYTES)
            / POOL_BYTES_PER_RAY;
        let by_grid = gpu.limits.max_compute_workgroups_per_dimension as u64 * 64;
        by_binding.min(by_grid).min(u32::MAX as u64) as u32
    }

    /// Bytes of the continuation pool as allocated (0 before the first trace).
    pub fn pool_bytes(&self) -> u64 {
        self.pool.as_ref().map_or(0, |p| p.size())
    }

    /// The pool: its first 16 bytes are a [`PoolHeader`] (copy them out
    /// after a trace to learn how many rays are unfinished). `None` before
    /// the first trace.
    pub fn pool(&self) -> Option<&wgpu::Buffer> {
        self.pool.as_ref()
    }

    fn ensure_pool(&mut self, gpu: &Gpu, count: u32) -> Result<(), GpuError> {
        let max = Self::max_rays(gpu);
        if count > max {
            return Err(GpuError::TooLarge {
                what: "rays of one trace (continuation pool)",
                bytes: HEADER_BYTES + count as u64 * POOL_BYTES_PER_RAY,
                limit: gpu.limits.max_storage_buffer_binding_size,
            });
        }
        if self.pool.is_some() && count <= self.capacity {
            return Ok(());
        }
        // Headroom so that slowly growing ray counts do not remake it every frame.
        let capacity = count
            .max(64)
            .checked_next_power_of_two()
            .unwrap_or(max)
            .min(max);
        self.pool = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("trace pool"),
            size: HEADER_BYTES + capacity as u64 * POOL_BYTES_PER_RAY,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }));
        self.capacity = capacity;
        self.schedule_bind = None;
        Ok(())
    }

    /// Records the trace of `count` rays of `rays` against `ads` into `enc`:
    /// the first dispatch, then [`TraceResources::rounds`] continuation
    /// rounds. Nothing is submitted or waited for. `rays` needs `STORAGE`
    /// usage and `32·count` bytes, `hits` and `stats` (when given) `STORAGE`
    /// and `16·count` bytes. After the commands run, every hit is final
    /// unless the pool's [`PoolHeader::count_in`] is not zero; then those rays
    /// hold [`UNFINISHED`] until [`TraceResources::encode_continue`] records
    /// more rounds.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_trace(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        ads: &GpuAds,
        rays: &wgpu::Buffer,
        hits: &wgpu::Buffer,
        stats: Option<&wgpu::Buffer>,
        count: u32,
        traversal: Traversal,
    ) -> Result<(), GpuError> {
        gpu.scoped("encode_trace", || {
            self.encode_trace_unscoped(gpu, enc, ads, rays, hits, stats, count, None, traversal)
        })
    }

    /// [`TraceResources::encode_trace`] for a ray count only the GPU knows
    /// (a wavefront's live rays, counted by an atomic): `rays` has room for
    /// `capacity` rays, and the count is the `u32` at byte `at` of `counter`
    /// (which needs `COPY_SRC`; `at` a multiple of 4) when the commands run.
    /// The first dispatch is indirect and covers the first
    /// `min(count, capacity)` rays only; the hits (and statistics) of the
    /// slots past them are left as they were. Buffers are checked against
    /// `capacity`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_trace_counted(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        ads: &GpuAds,
        rays: &wgpu::Buffer,
        hits: &wgpu::Buffer,
        stats: Option<&wgpu::Buffer>,
        capacity: u32,
        counter: (&wgpu::Buffer, u64),
        traversal: Traversal,
    ) -> Result<(), GpuError> {
        let (buf, at) = counter;
        check_buffer(
            "the ray counter",
            buf,
            at.saturating_add(4),
            wgpu::BufferUsages::COPY_SRC,
        )?;
        if at % 4 != 0 {
            return Err(GpuError::Buffer {
                what: "the ray counter",
                problem: format!("the count is at byte {at}, not a multiple of 4"),
            });
        }
        gpu.scoped("encode_trace_counted", || {
            self.encode_trace_unscoped(
                gpu,
                enc,
                ads,
                rays,
                hits,
                stats,
                capacity,
                Some(counter),
                traversal,
            )
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn encode_trace_unscoped(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        ads: &GpuAds,
        rays: &wgpu::Buffer,
        hits: &wgpu::Buffer,
        stats: Option<&wgpu::Buffer>,
        count: u32,
        counter: Option<(&wgpu::Buffer, u64)>,
        traversal: Traversal,
    ) -> Result<(), GpuError> {
        let n = count as u64;
        check_buffer("the ray buffer", rays, n * 32, wgpu::BufferUsages::STORAGE)?;
        check_buffer("the hit buffer", hits, n * 16, wgpu::BufferUsages::STORAGE)?;
        if let Some(s) = stats {
            check_buffer(
                "the statistics buffer",
                s,
                n * 16,
                wgpu::BufferUsages::STORAGE,
            )?;
        }
        if !(1..=WORK_BUDGET).contains(&self.budget) {
            return Err(GpuError::Params(dirt_core::CoreError::InvalidParams(
                format!(
                    "the trace's work budget must be in 1..={WORK_BUDGET}, got {}",
                    self.budget
                ),
            )));
        }
        // The structure's bindings choose the pipelines (compiled if need
        // be), before anything is recorded.
        let split = ads.split();
        let pipelines = gpu.pipelines_for(split)?;
        self.ensure_pool(gpu, count)?;
        let Some(pool) = self.pool.clone() else {
            return Err(GpuError::Device("the trace pool was not made".into()));
        };
        enc.clear_buffer(&pool, 0, Some(HEADER_BYTES));
        if count == 0 {
            self.bind = None;
            return Ok(());
        }
        let tiles = ads.params.tiles();
        let params = TraceParams {
            n_rays: count,
            n_views: ads.n_views,
            n_slots: ads.n_slots,
            tiles,
            buckets: ads.params.buckets,
            levels: hiz_levels(tiles),
            traversal: match traversal {
                Traversal::Linear => 0,
                Traversal::HiZ => 1,
            },
            budget: self.budget,
            capacity: self.capacity,
            with_stats: stats.is_some() as u32,
            id_shift: ads.ids.shift(),
            id_capacity: ads.ids.capacity().min(u32::MAX as u64) as u32,
            tri_shift: ads.tris.shift(),
            hiz_shift: ads.hiz.shift(),
            offset_shift: ads.offsets.shift(),
            counted: counter.is_some() as u32,
        };
        let uniform = self
            .params
            .entry(params)
            .or_insert_with(|| {
                crate::uniform_init(gpu, "trace params", bytemuck::bytes_of(&params))
            })
            .clone();
        let stats_buf = stats.unwrap_or(&self.no_stats);
        let stats_bytes = if stats.is_some() { n * 16 } else { 16 };
        let mut entries: Vec<wgpu::BindGroupEntry<'_>> = [
            (0, binding(rays, n * 32)),
            (1, binding(hits, n * 16)),
            (3, ads.views_uniform.as_entire_binding()),
            (4, uniform.as_entire_binding()),
            (8, binding(stats_buf, stats_bytes)),
            (9, pool.as_entire_binding()),
        ]
        .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource })
        .into();
        entries.extend(crate::whole(crate::with(
            &[],
            [
                ads.ids.bindings(gpu, split),
                ads.tris.bindings(gpu, split),
                ads.hiz.bindings(gpu, split),
                ads.offsets.bindings(gpu, split),
            ],
        )));
        let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("trace"),
            layout: &pipelines.trace.get_bind_group_layout(0),
            entries: &entries,
        });
        match counter {
            None => {
                let (x, y) = grid(gpu, n.div_ceil(64));
                crate::record_dispatch(enc, "trace", &pipelines.trace, &bind, [x, y, 1]);
            }
            Some((buf, at)) => {
                // The count into the cleared header, then `size_first` turns
                // it into the first dispatch's size (and the bound `trace` checks).
                enc.copy_buffer_to_buffer(buf, at, &pool, 0, 4);
                let size = crate::bind_buffers(
                    gpu,
                    "trace size_first",
                    &gpu.pipelines.size_first.get_bind_group_layout(0),
                    &[(4, &uniform), (9, &pool), (10, &self.dispatch)],
                );
                crate::record_dispatch(
                    enc,
                    "trace size_first",
                    &gpu.pipelines.size_first,
                    &size,
                    [1, 1, 1],
                );
                crate::record_dispatch_indirect(
                    enc,
                    "trace",
                    &pipelines.trace,
                    &bind,
                    &self.dispatch,
                );
            }
        }
        self.bind = Some((bind, split));
        self.encode_schedule(gpu, enc, &pool);
        self.encode_continue(gpu, enc)
    }

    fn encode_schedule(&mut self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder, pool: &wgpu::Buffer) {
        let bind = self.schedule_bind.get_or_insert_with(|| {
            crate::bind_buffers(
                gpu,
                "trace schedule",
                &gpu.pipelines.schedule.get_bind_group_layout(0),
                &[(9, pool), (10, &self.dispatch)],
            )
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("trace schedule"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&gpu.pipelines.schedule);
        pass.set_bind_group(0, &*bind, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Records [`TraceResources::rounds`] more continuation rounds of the
    /// last trace recorded (a round with no ray left dispatches nothing).
    pub fn encode_continue(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let (Some((bind, split)), Some(pool)) = (self.bind.clone(), self.pool.clone()) else {
            // No trace recorded, or an empty one: nothing is unfinished.
            return Ok(());
        };
        // Compiled when the trace was recorded: the same pipelines.
        let pipelines = gpu.pipelines_for(split)?;
        for _ in 0..self.rounds {
            crate::record_dispatch_indirect(
                enc,
                "trace_continue",
                &pipelines.trace_continue,
                &bind,
                &self.dispatch,
            );
            self.encode_schedule(gpu, enc, &pool);
        }
        Ok(())
    }

    /// Records a copy of the pool's [`PoolHeader`] into `dst` at `offset`
    /// (which needs `COPY_DST`).
    pub fn encode_copy_header(
        &self,
        enc: &mut wgpu::CommandEncoder,
        dst: &wgpu::Buffer,
        offset: u64,
    ) {
        if let Some(pool) = &self.pool {
            enc.copy_buffer_to_buffer(pool, 0, dst, offset, HEADER_BYTES);
        }
    }

    /// The pool's header read back (waits for the GPU).
    pub fn read_header(&self, gpu: &Gpu) -> Result<PoolHeader, GpuError> {
        match &self.pool {
            None => Ok(PoolHeader::default()),
            Some(pool) => Ok(bytemuck::pod_read_unaligned(&read_back(
                gpu,
                pool,
                0,
                HEADER_BYTES,
            )?)),
        }
    }

    /// The host-slice wrapper: uploads `rays`, records the trace, submits,
    /// reads the hits (and statistics) back; records more rounds while rays
    /// are unfinished.
    pub fn trace_host(
        &mut self,
        gpu: &Gpu,
        ads: &GpuAds,
        rays: &[Ray],
        traversal: Traversal,
        with_stats: bool,
    ) -> Result<Traced, GpuError> {
        crate::block(
            "the trace",
            self.trace_async(gpu, ads, rays, traversal, with_stats),
        )
    }

    /// [`TraceResources::trace_host`] without blocking: the form a browser
    /// page awaits (its read-backs resolve on the page's event loop).
    pub async fn trace_async(
        &mut self,
        gpu: &Gpu,
        ads: &GpuAds,
        rays: &[Ray],
        traversal: Traversal,
        with_stats: bool,
    ) -> Result<Traced, GpuError> {
        gpu.scoped_async(
            "the trace",
            self.trace_host_unscoped(gpu, ads, rays, traversal, with_stats),
        )
        .await
    }

    async fn trace_host_unscoped(
        &mut self,
        gpu: &Gpu,
        ads: &GpuAds,
        rays: &[Ray],
        traversal: Traversal,
        with_stats: bool,
    ) -> Result<Traced, GpuError> {
        let mut out = Traced {
            hits: Vec::with_capacity(rays.len()),
            stats: Vec::with_capacity(if with_stats { rays.len() } else { 0 }),
            ..Default::default()
        };
        let chunk = CHUNK.min(Self::max_rays(gpu).max(1) as usize);
        for part in rays.chunks(chunk) {
            let n = part.len() as u64;
            let ray_buf = crate::storage_init(
                gpu,
                "rays",
                bytemuck::cast_slice(part),
                wgpu::BufferUsages::empty(),
            );
            let out_buf = |label| {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: (n * 16).max(16),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            let hit_buf = out_buf("hits");
            let stat_buf = with_stats.then(|| out_buf("stats"));
            let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("trace readback"),
                size: HEADER_BYTES + n * 32,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            self.encode_trace(
                gpu,
                &mut enc,
                ads,
                &ray_buf,
                &hit_buf,
                stat_buf.as_ref(),
                part.len() as u32,
                traversal,
            )?;
            loop {
                self.encode_copy_header(&mut enc, &staging, 0);
                enc.copy_buffer_to_buffer(&hit_buf, 0, &staging, HEADER_BYTES, n * 16);
                if let Some(s) = &stat_buf {
                    enc.copy_buffer_to_buffer(s, 0, &staging, HEADER_BYTES + n * 16, n * 16);
                }
                gpu.submit(enc);
                out.submissions += 1;
                let bytes = map_read_async(gpu, &staging).await?;
                let head: PoolHeader =
                    bytemuck::pod_read_unaligned(&bytes[..HEADER_BYTES as usize]);
                if head.count_in == 0 {
                    out.rounds += head.rounds;
                    let at = HEADER_BYTES as usize;
                    let hit_end = at + (n * 16) as usize;
                    out.hits
                        .extend(bytemuck::pod_collect_to_vec::<u8, Hit>(&bytes[at..hit_end]));
                    if with_stats {
                        out.stats
                            .extend(bytemuck::pod_collect_to_vec::<u8, RayStats>(
                                &bytes[hit_end..hit_end + (n * 16) as usize],
                            ));
                    }
                    break;
                }
                enc = gpu.device.create_command_encoder(&Default::default());
                self.encode_continue(gpu, &mut enc)?;
            }
        }
        Ok(out)
    }
}
