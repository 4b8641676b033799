//! The one tracer interface: every tracer of the project implements
//! [`Tracer`], and everything that measures or renders takes `&mut dyn Tracer`.

use crate::CoreError;
use dirt_math::{Hit, Ray, RayStats, Triangle};
use std::time::Duration;

/// What a [`Tracer::build`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildReport {
    /// Wall time of each named stage, in order; empty for a tracer without stages.
    pub stages: Vec<(&'static str, Duration)>,
    /// Bytes of the structure built, where the tracer can say.
    pub memory: Option<u64>,
}

/// What a [`Tracer::trace_into`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceReport {
    /// Extra dispatches the trace needed: the GPU continues rays that spent
    /// their per-dispatch work budget in further rounds (0 for the CPU).
    pub continuation_rounds: usize,
    /// Whether per-ray statistics were written.
    pub stats: bool,
}

/// Closest hits of rays against the triangles of the last build.
///
/// Hits follow `dirt_math`'s rules: the watertight test
/// (`dirt_math::triangle::intersect`) for exact tracers, `t` in
/// `[tmin, tmax]` inclusive, ties broken by [`Hit::closer_than`], and a miss
/// ([`Hit::MISS`]) for a ray that fails [`Ray::validate`]. A triangle's
/// primitive id is its index in the slice given to [`Tracer::build`].
pub trait Tracer {
    /// A short name for reports, e.g. `dirt-cpu (hiz)`.
    fn name(&self) -> String;

    /// Builds (or rebuilds, for a new frame) over `tris`.
    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError>;

    /// The closest hit of every ray into `hits` (one per ray, in order), and
    /// per-ray statistics into `stats` when given and the tracer counts them
    /// ([`TraceReport::stats`] says whether it did).
    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError>;

    /// Whether [`Tracer::trace_into`] writes per-ray statistics.
    fn counts_stats(&self) -> bool {
        false
    }

    /// One hit per ray, in order.
    fn trace(&mut self, rays: &[Ray]) -> Result<Vec<Hit>, CoreError> {
        let mut hits = vec![Hit::MISS; rays.len()];
        self.trace_into(rays, &mut hits, None)?;
        Ok(hits)
    }
}

/// Checks that `hits` (and `stats`, if given) hold one entry per ray; every
/// `trace_into` calls it first.
pub fn check_lengths(
    rays: &[Ray],
    hits: &[Hit],
    stats: Option<&[RayStats]>,
) -> Result<(), CoreError> {
    let expected = rays.len();
    if hits.len() != expected {
        return Err(CoreError::BufferLength {
            what: "the hit buffer",
            expected,
            got: hits.len(),
        });
    }
    if let Some(s) = stats
        && s.len() != expected
    {
        return Err(CoreError::BufferLength {
            what: "the statistics buffer",
            expected,
            got: s.len(),
        });
    }
    Ok(())
}

/// Most rays a task of a parallel trace takes.
pub const RAYS_PER_TASK: usize = 512;

/// The body of a [`Tracer::trace_into`] whose rays are independent and
/// count no statistics: checks the lengths, then `hits[i] = closest(&rays[i])`
/// on rayon's pool, at most [`RAYS_PER_TASK`] rays a task (rays differ in
/// cost, and halves split only as rayon sees fit can leave one thread the
/// dear ones), as `dirt_cpu::trace` takes them.
pub fn trace_each(
    rays: &[Ray],
    hits: &mut [Hit],
    stats: Option<&[RayStats]>,
    closest: impl Fn(&Ray) -> Hit + Sync,
) -> Result<TraceReport, CoreError> {
    use rayon::prelude::*;
    check_lengths(rays, hits, stats)?;
    rays.par_iter()
        .zip(hits.par_iter_mut())
        .with_max_len(RAYS_PER_TASK)
        .for_each(|(r, h)| *h = closest(r));
    Ok(TraceReport::default())
}

impl<T: Tracer + ?Sized> Tracer for &mut T {
    fn name(&self) -> String {
        (**self).name()
    }
    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        (**self).build(tris)
    }
    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        (**self).trace_into(rays, hits, stats)
    }
    fn counts_stats(&self) -> bool {
        (**self).counts_stats()
    }
}

impl<T: Tracer + ?Sized> Tracer for Box<T> {
    fn name(&self) -> String {
        (**self).name()
    }
    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        (**self).build(tris)
    }
    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        (**self).trace_into(rays, hits, stats)
    }
    fn counts_stats(&self) -> bool {
        (**self).counts_stats()
    }
}
