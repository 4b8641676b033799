//! DIRT on the CPU as a [`Tracer`]: [`DirtCpu`] owns the structure and a copy
//! of the triangles it was built over.

use crate::{Ads, CpuError, trace_into};
use dirt_core::{
    AdsParams, BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Traversal,
    Triangle, check_lengths,
};

/// DIRT on the CPU: [`Ads::build`] and [`crate::trace`] behind [`Tracer`].
#[derive(Debug)]
pub struct DirtCpu {
    pub params: AdsParams,
    pub traversal: Traversal,
    ads: Option<Ads>,
    tris: Vec<Triangle>,
}

impl DirtCpu {
    /// A tracer that builds with `params` and walks with `traversal`; call
    /// [`Tracer::build`] before tracing.
    pub fn new(params: AdsParams, traversal: Traversal) -> Self {
        Self {
            params,
            traversal,
            ads: None,
            tris: Vec::new(),
        }
    }

    /// [`DirtCpu::new`] and a build over `tris`.
    pub fn built(
        tris: &[Triangle],
        params: &AdsParams,
        traversal: Traversal,
    ) -> Result<Self, CpuError> {
        Ok(Self::from_ads(Ads::build(tris, params)?, tris, traversal))
    }

    /// A tracer over a structure already built from `tris`.
    pub fn from_ads(ads: Ads, tris: &[Triangle], traversal: Traversal) -> Self {
        Self {
            params: ads.params,
            traversal,
            ads: Some(ads),
            tris: tris.to_vec(),
        }
    }

    /// The structure of the last build.
    pub fn ads(&self) -> Option<&Ads> {
        self.ads.as_ref()
    }
}

impl Tracer for DirtCpu {
    fn name(&self) -> String {
        format!("dirt-cpu ({})", self.traversal)
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        self.ads = None;
        let ads = Ads::build(tris, &self.params)?;
        let report = BuildReport {
            stages: ads.timings.stages(),
            memory: Some(ads.memory().total()),
        };
        self.tris.clear();
        self.tris.extend_from_slice(tris);
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
        let with_stats = stats.is_some();
        trace_into(ads, &self.tris, rays, self.traversal, hits, stats);
        Ok(TraceReport {
            finished_elsewhere: 0,
            stats: with_stats,
        })
    }

    fn counts_stats(&self) -> bool {
        true
    }
}
