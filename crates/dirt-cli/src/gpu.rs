//! The lines that say which GPU adapter a command uses, or why it uses none
//! (the GPU itself is opened with `dirt_gpu::Gpu::open`).

use dirt_gpu::Gpu;

/// The line naming the adapter when the GPU is used.
pub fn gpu_line(gpu: &Gpu) -> String {
    format!(
        "gpu adapter: {}; {}",
        gpu.describe(),
        if gpu.exact {
            "exact (NoContraction SPIR-V: the CPU's bits are promised)"
        } else {
            "not exact (plain WGSL: hits may differ from the CPU's in the last bits)"
        }
    )
}

/// The line saying that the GPU is not used, and why.
pub fn fallback_line(reason: &str) -> String {
    format!("dirt: no usable GPU ({reason}); falling back to the CPU backend")
}
