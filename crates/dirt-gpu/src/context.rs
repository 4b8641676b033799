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
    pub(crate) pipelines: crate::Pipelines,
}

impl Gpu {
    /// Finds an adapter (honouring `WGPU_BACKEND`, e.g. `vulkan`) and opens it.
    pub fn new() -> Result<Gpu, GpuError> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Gpu, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::from_env().unwrap_or(wgpu::PowerPreference::HighPerformance),
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let supported = adapter.limits();
        // WebGPU's defaults, widened only where the adapter allows and dirt needs:
        // large storage buffers and 9 storage buffers in the trace (rays, hits,
        // triangles, Hi-Z, offsets, ids, statistics).
        let mut limits = wgpu::Limits::default();
        limits.max_storage_buffer_binding_size = supported.max_storage_buffer_binding_size;
        limits.max_buffer_size = supported.max_buffer_size;
        limits.max_storage_buffers_per_shader_stage = supported.max_storage_buffers_per_shader_stage.min(16);
        limits.max_compute_workgroups_per_dimension = supported.max_compute_workgroups_per_dimension;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("dirt"),
                required_features: wgpu::Features::empty(),
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let pipelines = crate::Pipelines::new(&device)?;
        Ok(Gpu { device, queue, info, limits, pipelines })
    }

    /// The adapter in words, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn describe(&self) -> String {
        format!("{} ({:?}, {})", self.info.name, self.info.backend, self.info.driver_info)
    }

    /// True on lavapipe, the software Vulkan device CI asserts bits on.
    pub fn is_llvmpipe(&self) -> bool {
        self.info.name.contains("llvmpipe")
    }

    /// Waits for all submitted work.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }
}
