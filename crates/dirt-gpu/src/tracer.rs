//! DIRT on the GPU as a [`Tracer`]: [`DirtGpu`] builds a [`GpuAds`] and traces
//! every ray of a call in one [`trace_report`].

use crate::trace::trace_report;
use crate::{Gpu, GpuAds, GpuError};
use dirt_core::{
    AdsParams, BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Traversal,
    Triangle, check_lengths,
};

/// DIRT on the GPU behind [`Tracer`]. Rays that spend the GPU's per-ray work
/// budget are finished by the CPU reference inside [`trace_report`] (the same
/// bits); each trace reports how many, and [`DirtGpu::cpu_finished`] sums them.
#[derive(Debug)]
pub struct DirtGpu<'g> {
    gpu: &'g Gpu,
    pub params: AdsParams,
    pub traversal: Traversal,
    ads: Option<GpuAds>,
    /// Rays finished by the CPU so far.
    pub cpu_finished: usize,
}

impl<'g> DirtGpu<'g> {
    /// A tracer that builds with `params` on `gpu`; call [`Tracer::build`] before tracing.
    pub fn new(gpu: &'g Gpu, params: AdsParams, traversal: Traversal) -> Self {
        Self {
            gpu,
            params,
            traversal,
            ads: None,
            cpu_finished: 0,
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
            gpu,
            params: ads.params,
            traversal,
            ads: Some(ads),
            cpu_finished: 0,
        }
    }

    /// The structure of the last build.
    pub fn ads(&self) -> Option<&GpuAds> {
        self.ads.as_ref()
    }
}

impl Tracer for DirtGpu<'_> {
    fn name(&self) -> String {
        format!("dirt-gpu ({})", self.traversal)
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
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
        let ads = self.ads.as_ref().ok_or_else(|| CoreError::NotBuilt {
            tracer: self.name(),
        })?;
        if rays.is_empty() {
            return Ok(TraceReport::default());
        }
        let t = trace_report(self.gpu, ads, rays, self.traversal).map_err(CoreError::from)?;
        hits.copy_from_slice(&t.hits);
        let with_stats = stats.is_some();
        if let Some(s) = stats {
            s.copy_from_slice(&t.stats);
        }
        self.cpu_finished += t.cpu_finished;
        Ok(TraceReport {
            finished_elsewhere: t.cpu_finished,
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
