//! Stage `trace`: a buffer of rays in, one closest hit per ray out, through
//! any [`Tracer`]. The integrator makes one call per bounce (and one for the
//! shadow rays of the bounce), so a GPU tracer gets every ray of a bounce at once.

use crate::RenderError;
use crate::reference::Reference;
use dirt_cpu::{Ads, AdsParams, Traversal};
use dirt_gpu::{Gpu, GpuAds};
use dirt_math::{Hit, Ray, Triangle};

/// Closest hits of a batch of rays against the (static) scene the tracer
/// was built for. Hits must follow `dirt_math`'s rules: the watertight test,
/// `t` in `[tmin, tmax]` inclusive, ties broken by [`Hit::closer_than`].
pub trait Tracer {
    /// A short name for reports, e.g. `dirt-cpu (linear)`.
    fn name(&self) -> String;
    /// One hit per ray, in order.
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError>;
}

/// DIRT on the CPU (`dirt_cpu`), built once: the scene is static.
#[derive(Debug)]
pub struct DirtCpu {
    pub ads: Ads,
    tris: Vec<Triangle>,
    pub traversal: Traversal,
}

impl DirtCpu {
    pub fn build(
        tris: &[Triangle],
        params: &AdsParams,
        traversal: Traversal,
    ) -> Result<Self, RenderError> {
        Ok(Self {
            ads: Ads::build(tris, params)?,
            tris: tris.to_vec(),
            traversal,
        })
    }
}

impl Tracer for DirtCpu {
    fn name(&self) -> String {
        format!("dirt-cpu ({})", traversal_name(self.traversal))
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        Ok(dirt_cpu::trace(&self.ads, &self.tris, rays, self.traversal))
    }
}

/// DIRT on the GPU (`dirt_gpu`): the rays of a call go to the GPU in one
/// `trace_report`. Rays that spend the GPU's per-ray work budget are finished
/// by the CPU reference inside `dirt_gpu` (the same bits); they are counted.
#[derive(Debug)]
pub struct DirtGpu<'g> {
    gpu: &'g Gpu,
    pub ads: GpuAds,
    pub traversal: Traversal,
    /// Rays finished by the CPU so far.
    pub cpu_finished: usize,
}

impl<'g> DirtGpu<'g> {
    pub fn build(
        gpu: &'g Gpu,
        tris: &[Triangle],
        params: &AdsParams,
        traversal: Traversal,
    ) -> Result<Self, RenderError> {
        Ok(Self {
            gpu,
            ads: GpuAds::build(gpu, tris, params)?,
            traversal,
            cpu_finished: 0,
        })
    }

    /// A tracer over a structure already built.
    pub fn from_ads(gpu: &'g Gpu, ads: GpuAds, traversal: Traversal) -> Self {
        Self {
            gpu,
            ads,
            traversal,
            cpu_finished: 0,
        }
    }
}

impl Tracer for DirtGpu<'_> {
    fn name(&self) -> String {
        format!("dirt-gpu ({})", traversal_name(self.traversal))
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let t = dirt_gpu::trace::trace_report(self.gpu, &self.ads, rays, self.traversal)?;
        self.cpu_finished += t.cpu_finished;
        Ok(t.hits)
    }
}

/// Every ray against every triangle: the ground truth.
#[derive(Debug)]
pub struct Brute {
    tris: Vec<Triangle>,
}

impl Brute {
    pub fn new(tris: &[Triangle]) -> Self {
        Self {
            tris: tris.to_vec(),
        }
    }
}

impl Tracer for Brute {
    fn name(&self) -> String {
        "brute".to_string()
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        Ok(dirt_cpu::brute_force::trace(&self.tris, rays))
    }
}

impl Tracer for Reference {
    fn name(&self) -> String {
        "reference (obvhs bvh2)".to_string()
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        Ok(Reference::trace(self, rays))
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
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        let hits = self.inner.trace(rays)?;
        self.calls.push((rays.to_vec(), hits.clone()));
        Ok(hits)
    }
}

impl<T: Tracer + ?Sized> Tracer for &mut T {
    fn name(&self) -> String {
        (**self).name()
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        (**self).trace(rays)
    }
}

impl<T: Tracer + ?Sized> Tracer for Box<T> {
    fn name(&self) -> String {
        (**self).name()
    }
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, RenderError> {
        (**self).trace(rays)
    }
}

fn traversal_name(t: Traversal) -> &'static str {
    match t {
        Traversal::Linear => "linear",
        Traversal::HiZ => "hiz",
    }
}
