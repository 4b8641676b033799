//! dirt-core: what every DIRT tracer shares and no backend owns.
//!
//! - [`Tracer`]: build from triangles, trace a ray buffer into hits (per-ray
//!   statistics optional), report what the build and the trace did. DIRT on the
//!   CPU (`dirt_cpu::DirtCpu`) and on the GPU (`dirt_gpu::DirtGpu`), brute force
//!   (`dirt_cpu::brute_force::Brute`), the renderer's BVH reference and the
//!   evaluation's peers (obvhs, Embree) all implement it.
//! - [`AdsParams`] and [`Traversal`]: the knobs of the structure and of its walk.
//! - [`views_for`]: the view set both backends build over, with the views no
//!   triangle reaches left out ([`left_out_views`] says which and why).
//! - [`gather`]: an application's mesh (vertex and index bytes, stride,
//!   offset, transform) as triangles, the CPU reference of the GPU's `gather`.
//! - [`BindingLimits`]: what a GPU binds, as it bounds a structure's buffers.
//! - [`IdLists`] and [`BuildTimings`]: the structure's lists and stage times, as
//!   both backends produce them.
//!
//! The ray, hit and statistics records are `dirt_math`'s `#[repr(C)]` types,
//! re-exported here.

mod error;
pub mod gather;
mod limits;
mod lists;
mod params;
mod tracer;
mod views;

pub use dirt_math::{Hit, Ray, RayStats, Triangle, ViewSet, ViewsKind};
pub use error::CoreError;
pub use limits::{BindingLimits, SplitArray};
pub use lists::{BuildTimings, IdLists};
pub use params::{AdsParams, Traversal};
pub use tracer::{BuildReport, RAYS_PER_TASK, TraceReport, Tracer, check_lengths, trace_each};
pub use views::{
    LeftOutReason, LeftOutView, bounds_of, first_non_finite, left_out_views, views_for,
    views_for_all, views_for_bounded, views_over, views_reached,
};
