//! Stage `trace`: a buffer of rays in, one closest hit per ray out, through
//! any [`Tracer`] (`dirt_core`'s one tracer interface). The integrator makes
//! one call per bounce (and one for the shadow rays of the bounce), so a GPU
//! tracer gets every ray of a bounce at once.
//!
//! The tracers: DIRT on the CPU ([`dirt_cpu::DirtCpu`]) and on the GPU
//! ([`dirt_gpu::DirtGpu`]), brute force ([`dirt_cpu::brute_force::Brute`]) and
//! the renderer's BVH [`Reference`](crate::reference::Reference).

pub use dirt_core::Tracer;

use crate::reference::Reference;
use dirt_core::{BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Triangle, check_lengths};

impl Tracer for Reference {
    fn name(&self) -> String {
        "reference (obvhs bvh2)".to_string()
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        *self = Reference::new(tris);
        Ok(BuildReport {
            stages: Vec::new(),
            memory: Some(self.memory_bytes()),
        })
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        check_lengths(rays, hits, stats.as_deref())?;
        self.trace_to(rays, hits);
        Ok(TraceReport::default())
    }
}

/// A tracer that keeps every batch of rays and hits it passed on, to compare
/// two tracers bounce by bounce.
#[derive(Debug)]
pub struct Recording<T> {
    pub inner: T,
    /// `(rays, hits)` of every call, in order.
    pub calls: Vec<(Vec<Ray>, Vec<Hit>)>,
}

impl<T: Tracer> Recording<T> {
    pub fn new(inner: T) -> Self {
        Self {
            inner,
            calls: Vec::new(),
        }
    }
}

impl<T: Tracer> Tracer for Recording<T> {
    fn name(&self) -> String {
        self.inner.name()
    }
    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        self.inner.build(tris)
    }
    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        let report = self.inner.trace_into(rays, hits, stats)?;
        self.calls.push((rays.to_vec(), hits.to_vec()));
        Ok(report)
    }
    fn counts_stats(&self) -> bool {
        self.inner.counts_stats()
    }
}
