//! Stage `trace`: a buffer of rays in, one closest hit per ray out, through
//! any [`Tracer`] (`dirt_core`'s one tracer interface). The integrator makes
//! one call per bounce (and one for the shadow rays of the bounce), so a GPU
//! tracer gets every ray of a bounce at once.
//!
//! The tracers: DIRT on the CPU ([`dirt_cpu::DirtCpu`]) and on the GPU
//! ([`dirt_gpu::DirtGpu`]), brute force ([`dirt_cpu::brute_force::Brute`]) and
//! the renderer's BVH [`Reference`](crate::reference::Reference).

pub use dirt_core::Tracer;

use crate::RenderError;
use crate::reference::Reference;
use dirt_core::{BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Triangle, check_lengths};

/// A tracer whose hits may come later: on a browser page a GPU's read-back
/// resolves on the page's event loop, so the renderer awaits each batch
/// ([`crate::Renderer::render_sample_async`]). Every [`Tracer`] is one,
/// through [`Blocking`], whose hits are ready at once.
pub trait AsyncTrace {
    /// The tracer in words.
    fn name(&self) -> String;
    /// The closest hit of every ray, in order.
    fn trace_rays(&mut self, rays: &[Ray]) -> impl Future<Output = Result<Vec<Hit>, RenderError>>;
}

/// A [`Tracer`] as an [`AsyncTrace`]: it traces when asked, so its future is ready.
pub struct Blocking<'t>(pub &'t mut dyn Tracer);

impl std::fmt::Debug for Blocking<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Blocking").field(&self.0.name()).finish()
    }
}

impl AsyncTrace for Blocking<'_> {
    fn name(&self) -> String {
        self.0.name()
    }
    fn trace_rays(&mut self, rays: &[Ray]) -> impl Future<Output = Result<Vec<Hit>, RenderError>> {
        std::future::ready(self.0.trace(rays).map_err(RenderError::from))
    }
}

/// The output of a future that is ready when first polled ([`Blocking`]'s
/// are): the renderer's blocking entry points run its async body with it,
/// so there is one body and no executor.
pub(crate) fn now<T>(fut: impl Future<Output = Result<T, RenderError>>) -> Result<T, RenderError> {
    let mut fut = std::pin::pin!(fut);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    match fut.as_mut().poll(&mut cx) {
        std::task::Poll::Ready(out) => out,
        std::task::Poll::Pending => Err(RenderError::NotReady),
    }
}

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
