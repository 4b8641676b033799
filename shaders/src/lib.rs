//! dirt-shaders: the WGSL of dirt, one file per stage named after it
//! (`fill_depth`, `mip_depth`, `fill_primitives`, `trace`), and shared modules
//! that mirror `dirt-math` function by function, with their naga validation.
//!
//! The CPU reference (`dirt-cpu`) is complete; the WGSL stages land with the
//! GPU backend. Until then this crate lists the stage names both backends use.

/// The stages of the pipeline, in build-then-trace order. `dirt_cpu::<stage>`,
/// `shaders/<stage>.wgsl` and `dirt_gpu::<stage>` carry these names.
pub const STAGES: [&str; 4] = ["fill_depth", "mip_depth", "fill_primitives", "trace"];
