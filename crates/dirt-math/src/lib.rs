//! dirt-math: the math of DIRT, shared by the CPU reference and, mirrored
//! operation for operation in WGSL, by the GPU passes. Depends on no GPU crate.
//!
//! - [`types`]: `#[repr(C)]` Pod types shared with WGSL (`Ray`, `Hit`, `Triangle`).
//! - [`triangle`]: the watertight ray/triangle test and the deterministic tie-break.
//! - [`view`]: perspective and orthographic views, tile grids, the cubemap, single-view and orthographic sets.
//! - [`clip`]: dilated half-spaces, ray and polygon clipping, per-tile depth extents.
//! - [`dda`]: the conservative tile walk and the Hi-Z stepping helpers.
//! - [`bucket`]: depth buckets (001 eq. 1).
//! - [`encode`]: order-preserving f32 <-> u32 for atomic min/max.

pub mod bucket;
pub mod clip;
pub mod dda;
pub mod divide;
pub mod encode;
pub mod num;
pub mod triangle;
pub mod types;
pub mod view;

pub use glam::Vec3;
pub use types::{Aabb, Hit, INVALID_ID, Ray, RayProblem, RayStats, Triangle, ViewGpu};
pub use view::{View, ViewRay, ViewSet, ViewsKind};
