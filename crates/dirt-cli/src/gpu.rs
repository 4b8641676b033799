//! Opening the GPU for a command, and the lines that say which adapter is
//! used or why none is.

use dirt_gpu::Gpu;

/// Opens the GPU; the error is the reason in words. A panic inside the driver
/// stack counts as no usable GPU, not as a crash.
pub fn open_gpu() -> Result<Gpu, String> {
    match std::panic::catch_unwind(Gpu::new) {
        Ok(Ok(gpu)) => Ok(gpu),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .map_or_else(
                || "the GPU stack panicked".to_owned(),
                |m| format!("the GPU stack panicked: {m}"),
            )),
    }
}

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
