//! The GPU context: an adapter chosen as `WGPU_BACKEND` says, its device and
//! queue, and the compiled pipelines of every stage.

use crate::GpuError;

/// A device ready to run dirt's passes.
#[derive(Debug)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Shaders compiled with NoContraction (see [`crate::spirv`]): the CPU's bits are promised.
    pub exact: bool,
    pub(crate) pipelines: crate::Pipelines,
}

impl Gpu {
    /// [`Gpu::new`], with the error in words. A panic inside the driver stack
    /// counts as no usable GPU, not as a crash: callers that fall back to the
    /// CPU (the command line) or skip (the tests) need only the reason.
    pub fn open() -> Result<Gpu, String> {
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

    /// Finds an adapter (honouring `WGPU_BACKEND`, e.g. `vulkan`) and opens it.
    pub fn new() -> Result<Gpu, GpuError> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Gpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::from_env()
                    .unwrap_or(wgpu::PowerPreference::HighPerformance),
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let supported = adapter.limits();
        // WebGPU's defaults (at most 8 storage buffers per stage: the trace uses 7),
        // widened only where dirt needs it and the adapter allows: large buffers
        // and dispatch grids.
        let limits = wgpu::Limits {
            max_storage_buffer_binding_size: supported.max_storage_buffer_binding_size,
            max_buffer_size: supported.max_buffer_size,
            max_compute_workgroups_per_dimension: supported.max_compute_workgroups_per_dimension,
            ..Default::default()
        };
        // NoContraction SPIR-V needs passthrough shaders (Vulkan); elsewhere WGSL goes through wgpu.
        let passthrough_feature = adapter.features() & wgpu::Features::PASSTHROUGH_SHADERS;
        // DIRT_GPU_WGSL=1 forces the plain WGSL path (to compare; no bits promised then).
        let forced_wgsl = std::env::var("DIRT_GPU_WGSL").is_ok_and(|v| v == "1");
        let exact = !forced_wgsl
            && !passthrough_feature.is_empty()
            && info.backend == wgpu::Backend::Vulkan;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("dirt"),
                required_features: passthrough_feature,
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let pipelines = crate::Pipelines::new(&device, exact)?;
        Ok(Gpu {
            device,
            queue,
            info,
            limits,
            pipelines,
            exact,
        })
    }

    /// The adapter in words, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {})",
            self.info.name, self.info.backend, self.info.driver_info
        )
    }

    /// True on lavapipe, the software Vulkan device CI asserts bits on.
    pub fn is_llvmpipe(&self) -> bool {
        self.info.name.contains("llvmpipe")
    }

    /// Waits for all submitted work.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }
}
