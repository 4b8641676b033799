//! DIRT on the GPU as a [`Tracer`]: [`DirtGpu`] builds a [`GpuAds`] and traces
//! every ray of a call through its [`TraceResources`], kept between calls.

use crate::trace::TraceResources;
use crate::{Gpu, GpuAds, GpuError};
use dirt_core::{
    AdsParams, BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Traversal,
    Triangle, check_lengths,
};

/// DIRT on the GPU behind [`Tracer`]. Rays that spend the GPU's per-dispatch
/// work budget are continued on the GPU (see [`crate::trace`]); each trace
/// reports its continuation rounds, and [`DirtGpu::rounds`] sums them.
#[derive(Debug)]
pub struct DirtGpu<'g> {
    gpu: &'g Gpu,
    pub params: AdsParams,
    pub traversal: Traversal,
    ads: Option<GpuAds>,
    /// The trace's buffers, kept from call to call.
    pub resources: TraceResources,
    /// Continuation rounds so far.
    pub rounds: u64,
    /// List entries the ids of a frame structure hold at first
    /// ([`DirtGpu::encode_build`]; they grow to fit what builds need).
    pub entries_hint: u64,
    /// [`Tracer::build`] uploads the triangles and records a frame build
    /// ([`DirtGpu::encode_build`]: views on the GPU, one submission, a build
    /// recorded again if its lists outgrew the ids) instead of
    /// [`GpuAds::build`] (views on the host, each stage waited for, the list
    /// total read back). Both give the same hits.
    pub frame_builds: bool,
}

/// [`DirtGpu::entries_hint`] by default: 4 MiB of ids.
pub const ENTRIES_HINT: u64 = 1 << 20;

impl<'g> DirtGpu<'g> {
    /// A tracer that builds with `params` on `gpu`; call [`Tracer::build`] before tracing.
    pub fn new(gpu: &'g Gpu, params: AdsParams, traversal: Traversal) -> Self {
        Self {
            gpu,
            params,
            traversal,
            ads: None,
            resources: TraceResources::new(gpu),
            rounds: 0,
            entries_hint: ENTRIES_HINT,
            frame_builds: false,
        }
    }

    /// [`DirtGpu::new`] and a build over `tris`.
    pub fn built(
        gpu: &'g Gpu,
        tris: &[Triangle],
        params: &AdsParams,
        traversal: Traversal,
    ) -> Result<Self, GpuError> {
        Ok(Self::from_ads(
            gpu,
            GpuAds::build(gpu, tris, params)?,
            traversal,
        ))
    }

    /// A tracer over a structure already built.
    pub fn from_ads(gpu: &'g Gpu, ads: GpuAds, traversal: Traversal) -> Self {
        Self {
            params: ads.params,
            ads: Some(ads),
            ..Self::new(gpu, AdsParams::default(), traversal)
        }
    }

    /// Records a build over the application's meshes into `enc`, without
    /// submitting or waiting (see [`GpuAds::encode_build`]). The first call,
    /// or one after [`Tracer::build`] or a change of [`DirtGpu::params`],
    /// makes the frame structure ([`GpuAds::frame`]); later calls reuse its buffers.
    pub fn encode_build(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        meshes: &[crate::GpuMesh<'_>],
    ) -> Result<(), GpuError> {
        let reuse = self
            .ads
            .as_ref()
            .is_some_and(|a| a.feedback().is_some() && a.params == self.params);
        let ads = match self.ads.as_mut() {
            Some(ads) if reuse => ads,
            _ => self
                .ads
                .insert(GpuAds::frame(self.gpu, &self.params, self.entries_hint)?),
        };
        ads.encode_build(self.gpu, enc, meshes)
    }

    /// [`Tracer::build`] with [`DirtGpu::frame_builds`]: the host-slice
    /// wrapper of a frame build. Its one stage, `frame`, is the wall time of
    /// every submission it took (two when the lists outgrew the ids).
    fn build_in_frame(&mut self, tris: &[Triangle]) -> Result<BuildReport, GpuError> {
        crate::block("a frame build", self.build_async(tris))
    }

    /// Builds over `tris` without blocking: the triangles uploaded and a
    /// frame build recorded ([`DirtGpu::encode_build`]), submitted and
    /// awaited until its feedback is in, again if its lists outgrew the ids.
    /// The form a browser page awaits; natively it is what
    /// [`Tracer::build`] does with [`DirtGpu::frame_builds`].
    pub async fn build_async(&mut self, tris: &[Triangle]) -> Result<BuildReport, GpuError> {
        let gpu = self.gpu;
        gpu.scoped_async("a frame build", self.build_async_unscoped(tris))
            .await
    }

    async fn build_async_unscoped(&mut self, tris: &[Triangle]) -> Result<BuildReport, GpuError> {
        u32::try_from(tris.len()).map_err(|_| {
            GpuError::Params(CoreError::InvalidParams(format!(
                "{} triangles is more than 2^32-1",
                tris.len()
            )))
        })?;
        let gpu = self.gpu;
        // One mesh per binding's worth: gather binds each vertex buffer whole.
        let per = 1usize << gpu.binding_limits().shift(dirt_core::SplitArray::Tris);
        let uploads: Vec<(wgpu::Buffer, u32)> = tris
            .chunks(per)
            .map(|part| {
                let buf = crate::buffer_init(
                    gpu,
                    "triangles upload",
                    bytemuck::cast_slice(part),
                    wgpu::BufferUsages::STORAGE,
                );
                (buf, part.len() as u32)
            })
            .collect();
        let meshes: Vec<crate::GpuMesh<'_>> = uploads
            .iter()
            .map(|(buf, count)| crate::GpuMesh {
                vertices: buf,
                indices: None,
                layout: dirt_core::gather::MeshLayout::triangles(*count),
            })
            .collect();
        let t0 = web_time::Instant::now();
        // A build whose lists outgrew the ids grows them for the next: at most one more.
        for _ in 0..3 {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            self.encode_build(&mut enc, &meshes)?;
            gpu.submit(enc);
            let Some(ads) = self.ads.as_ref() else { break };
            let Some(fb) = ads.settle_feedback(gpu).await? else {
                break;
            };
            if let Some(index) = fb.non_finite {
                self.ads = None;
                return Err(GpuError::Params(CoreError::NonFiniteTriangle {
                    index: index as usize,
                }));
            }
            if fb.entries_needed <= fb.capacity {
                let memory = self.ads.as_ref().map(GpuAds::memory_bytes);
                return Ok(BuildReport {
                    stages: vec![("frame", t0.elapsed())],
                    memory,
                });
            }
        }
        Err(GpuError::Device(
            "a frame build's lists did not fit after growing its ids".into(),
        ))
    }

    /// The device it runs on.
    pub fn gpu(&self) -> &'g Gpu {
        self.gpu
    }

    /// The structure of the last build.
    pub fn ads(&self) -> Option<&GpuAds> {
        self.ads.as_ref()
    }

    /// The structure of the last build, or the error that there is none.
    pub fn built_ads(&self) -> Result<&GpuAds, GpuError> {
        built(&self.ads)
    }

    /// Records the trace of `count` rays of `rays` into `enc` without
    /// submitting (see [`TraceResources::encode_trace`] for the buffers).
    #[allow(clippy::too_many_arguments)]
    pub fn encode_trace(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        rays: &wgpu::Buffer,
        hits: &wgpu::Buffer,
        stats: Option<&wgpu::Buffer>,
        count: u32,
    ) -> Result<(), GpuError> {
        let ads = built(&self.ads)?;
        self.resources
            .encode_trace(self.gpu, enc, ads, rays, hits, stats, count, self.traversal)
    }

    /// Records the trace of the rays counted on the GPU: the first
    /// `min(count, capacity)` of `rays`, `count` being the `u32` at byte `at`
    /// of `counter` when the commands run (see
    /// [`TraceResources::encode_trace_counted`]).
    #[allow(clippy::too_many_arguments)]
    pub fn encode_trace_counted(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        rays: &wgpu::Buffer,
        hits: &wgpu::Buffer,
        stats: Option<&wgpu::Buffer>,
        capacity: u32,
        counter: (&wgpu::Buffer, u64),
    ) -> Result<(), GpuError> {
        let ads = built(&self.ads)?;
        self.resources.encode_trace_counted(
            self.gpu,
            enc,
            ads,
            rays,
            hits,
            stats,
            capacity,
            counter,
            self.traversal,
        )
    }
}

impl DirtGpu<'_> {
    /// Closest hits (and per-ray statistics when `with_stats`) of `rays`
    /// without blocking: [`Tracer::trace_into`]'s form for a browser page,
    /// whose read-backs resolve on its event loop.
    pub async fn trace_async(
        &mut self,
        rays: &[Ray],
        with_stats: bool,
    ) -> Result<crate::trace::Traced, GpuError> {
        let ads = built(&self.ads)?;
        if rays.is_empty() {
            return Ok(crate::trace::Traced::default());
        }
        let t = self
            .resources
            .trace_async(self.gpu, ads, rays, self.traversal, with_stats)
            .await?;
        self.rounds += t.rounds as u64;
        Ok(t)
    }
}

/// The structure `ads` holds, or the error that nothing was built (a field
/// borrow, so that the tracer's resources can be borrowed beside it).
fn built(ads: &Option<GpuAds>) -> Result<&GpuAds, GpuError> {
    ads.as_ref().ok_or_else(|| {
        GpuError::Params(CoreError::NotBuilt {
            tracer: "dirt-gpu".into(),
        })
    })
}

impl Tracer for DirtGpu<'_> {
    fn name(&self) -> String {
        format!("dirt-gpu ({})", self.traversal)
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        if self.frame_builds {
            return self.build_in_frame(tris).map_err(CoreError::from);
        }
        self.ads = None;
        let ads = GpuAds::build(self.gpu, tris, &self.params).map_err(CoreError::from)?;
        let report = BuildReport {
            stages: ads.timings.stages(),
            memory: Some(ads.memory_bytes()),
        };
        self.ads = Some(ads);
        Ok(report)
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        check_lengths(rays, hits, stats.as_deref())?;
        if self.ads.is_none() {
            return Err(CoreError::NotBuilt {
                tracer: self.name(),
            });
        }
        if rays.is_empty() {
            return Ok(TraceReport::default());
        }
        let with_stats = stats.is_some();
        let t = crate::block("the trace", self.trace_async(rays, with_stats))?;
        hits.copy_from_slice(&t.hits);
        if let Some(s) = stats {
            s.copy_from_slice(&t.stats);
        }
        Ok(TraceReport {
            continuation_rounds: t.rounds as usize,
            stats: with_stats,
        })
    }

    fn counts_stats(&self) -> bool {
        true
    }
}

impl From<GpuError> for CoreError {
    fn from(e: GpuError) -> Self {
        match e {
            GpuError::Params(e) => e,
            other => CoreError::backend("dirt-gpu", other),
        }
    }
}
