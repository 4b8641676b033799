//! dirt-math: the math of DIRT, shared by the CPU reference and (mirrored in
//! WGSL) the GPU passes. Depends on no GPU crate.

pub mod types;

pub use glam::Vec3;
pub use types::{Aabb, Hit, INVALID_ID, Ray, RayProblem, Triangle};
