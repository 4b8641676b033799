//! The GPU context: a device and queue (the application's, or one opened
//! here), what dirt decided about them (the exact path, the limits it works
//! within), and the compiled pipelines of every stage.

use crate::GpuError;
use crate::chunked::{Kind, Split};
use dirt_core::BindingLimits;

/// How dirt uses a device. Library users set these; nothing is read from the
/// environment except by [`GpuOptions::from_env`] (the command line and the
/// tests use it).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GpuOptions {
    /// Compile the shaders through wgpu's WGSL path even where the exact path
    /// (NoContraction SPIR-V, see [`crate::spirv`]) is available: to compare
    /// the two; no bits are promised then.
    pub plain_wgsl: bool,
}

impl GpuOptions {
    /// The environment variable that sets [`GpuOptions::plain_wgsl`] when `1`.
    pub const PLAIN_WGSL_ENV: &'static str = "DIRT_GPU_WGSL";

    /// Options from the environment: `DIRT_GPU_WGSL=1` sets [`GpuOptions::plain_wgsl`].
    pub fn from_env() -> GpuOptions {
        GpuOptions {
            plain_wgsl: std::env::var(Self::PLAIN_WGSL_ENV).is_ok_and(|v| v == "1"),
        }
    }
}

/// Storage buffers the trace binds in one compute stage with each split
/// array in one binding (rays, hits, statistics, continuation pool, ids,
/// triangles, Hi-Z, offsets): WebGPU's default limit, which every adapter
/// gives. Each storage buffer a device allows beyond it is one more binding
/// for a split array ([`Gpu::bindings`], dealt by
/// [`BindingLimits::for_device`]).
pub const STORAGE_BUFFERS_PER_STAGE: u32 = BindingLimits::MIN_STORAGE_BUFFERS;

/// The device dirt asks `adapter` for: the adapter's storage-buffer binding
/// and buffer sizes and workgroup counts (the structure's arrays are dealt
/// over bindings by [`BindingLimits::for_device`]), storage buffers per stage
/// raised towards [`BindingLimits::MAX_STORAGE_BUFFERS`] where the adapter
/// allows, and SPIR-V passthrough where it has it (the exact path,
/// [`exact_path`]). An application that opens the device it hands to
/// [`Gpu::from_device`] can ask for the same (adding its own needs).
pub fn device_descriptor<'a>(
    adapter: &wgpu::Adapter,
    label: &'a str,
) -> wgpu::DeviceDescriptor<'a> {
    let supported = adapter.limits();
    wgpu::DeviceDescriptor {
        label: Some(label),
        required_features: adapter.features() & wgpu::Features::PASSTHROUGH_SHADERS,
        required_limits: wgpu::Limits {
            max_storage_buffer_binding_size: supported.max_storage_buffer_binding_size,
            max_storage_buffers_per_shader_stage: supported
                .max_storage_buffers_per_shader_stage
                .min(BindingLimits::MAX_STORAGE_BUFFERS)
                .max(wgpu::Limits::default().max_storage_buffers_per_shader_stage),
            max_buffer_size: supported.max_buffer_size,
            max_compute_workgroups_per_dimension: supported.max_compute_workgroups_per_dimension,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A device ready to run dirt's passes.
#[derive(Debug)]
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// The device's limits, as the device reports them.
    pub limits: wgpu::Limits,
    /// Shaders compiled with NoContraction (see [`crate::spirv`]): the CPU's bits are promised.
    pub exact: bool,
    /// Why [`Gpu::exact`] is what it is, in words.
    pub exactness: &'static str,
    /// The pipelines with one binding per split array: what every structure
    /// that fits them uses.
    pub(crate) pipelines: crate::Pipelines,
    /// The pipelines with the device's bindings for the split arrays of a
    /// [`Split`], each compiled the first time a structure needs it
    /// ([`Gpu::pipelines_for`]).
    split: [std::sync::OnceLock<Result<crate::Pipelines, String>>; Split::VARIANTS],
    /// Bindings each split array takes at most (see [`Gpu::bindings`]);
    /// `max_binding` is not read from here.
    bindings: BindingLimits,
    /// Submissions and host waits dirt made itself (see [`Gpu::host_syncs`]).
    submits: std::sync::atomic::AtomicU64,
    waits: std::sync::atomic::AtomicU64,
    /// Set by the device-lost callback of a device dirt opened itself.
    lost: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

/// What dirt itself submitted and waited for on a [`Gpu`] so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HostSyncs {
    /// Command buffers dirt submitted (not the application's).
    pub submissions: u64,
    /// Times dirt blocked the host until the GPU was done (a read-back or a wait).
    pub waits: u64,
}

/// The one place the exact path is decided: NoContraction SPIR-V needs a
/// Vulkan device with passthrough shaders, and the caller not asking for
/// plain WGSL.
pub fn exact_path(
    backend: wgpu::Backend,
    features: wgpu::Features,
    options: &GpuOptions,
) -> (bool, &'static str) {
    if options.plain_wgsl {
        (
            false,
            "plain WGSL asked for (GpuOptions::plain_wgsl / DIRT_GPU_WGSL=1): no bits promised",
        )
    } else if backend != wgpu::Backend::Vulkan {
        (
            false,
            "not Vulkan: WGSL compiled by wgpu, floating-point contraction up to the driver",
        )
    } else if !features.contains(wgpu::Features::PASSTHROUGH_SHADERS) {
        (
            false,
            "the device was made without Features::PASSTHROUGH_SHADERS: WGSL compiled by wgpu, contraction up to the driver",
        )
    } else {
        (
            true,
            "NoContraction SPIR-V on Vulkan: every float operation as written",
        )
    }
}

impl Gpu {
    /// [`Gpu::new`] with options from the environment ([`GpuOptions::from_env`]:
    /// the command line and the tests), the error in words. A panic inside the driver stack
    /// counts as no usable GPU, not as a crash: callers that fall back to the
    /// CPU (the command line) or skip (the tests) need only the reason.
    pub fn open() -> Result<Gpu, String> {
        Self::open_with(&GpuOptions::from_env())
    }

    /// [`Gpu::open`] with options.
    pub fn open_with(options: &GpuOptions) -> Result<Gpu, String> {
        match std::panic::catch_unwind(|| Gpu::with_options(options)) {
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

    /// A convenience: finds an adapter (wgpu's `WGPU_BACKEND`, e.g. `vulkan`,
    /// is honoured), opens a device for dirt and calls [`Gpu::from_device`]
    /// with the default options.
    pub fn new() -> Result<Gpu, GpuError> {
        Self::with_options(&GpuOptions::default())
    }

    /// [`Gpu::new`] with options.
    pub fn with_options(options: &GpuOptions) -> Result<Gpu, GpuError> {
        let (device, queue) = pollster::block_on(Self::open_device())?;
        let gpu = Self::from_device(&device, &queue, options)?;
        // dirt's own device: its loss is dirt's to hear of (an application's
        // device keeps the application's callback).
        let lost = gpu.lost.clone();
        device.set_device_lost_callback(move |_, _| {
            lost.store(true, std::sync::atomic::Ordering::Release);
        });
        Ok(gpu)
    }

    /// A device as dirt would ask for one: passthrough shaders where the
    /// adapter has them (the exact path on Vulkan), and the adapter's largest
    /// buffers, bindings and dispatch grids; WebGPU's defaults elsewhere.
    pub async fn open_device() -> Result<(wgpu::Device, wgpu::Queue), GpuError> {
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
        adapter
            .request_device(&device_descriptor(&adapter, "dirt"))
            .await
            .map_err(|e| GpuError::Device(e.to_string()))
    }

    /// dirt on the application's device and queue. Features and limits are
    /// read from the device; the exact path is decided by [`exact_path`]; the
    /// pipelines are compiled here, once (those for arrays split across
    /// several bindings when a structure first needs them). The device and queue are shared
    /// (wgpu's handles are reference counted), not copied.
    pub fn from_device(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        options: &GpuOptions,
    ) -> Result<Gpu, GpuError> {
        let info = device.adapter_info();
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS_PER_STAGE {
            return Err(GpuError::Unsupported(format!(
                "the trace binds {STORAGE_BUFFERS_PER_STAGE} storage buffers in one stage; this device allows {} (max_storage_buffers_per_shader_stage)",
                limits.max_storage_buffers_per_shader_stage
            )));
        }
        let (exact, exactness) = exact_path(info.backend, device.features(), options);
        let bindings = BindingLimits::for_device(
            limits.max_storage_buffer_binding_size,
            limits.max_storage_buffers_per_shader_stage,
        );
        let pipelines = crate::Pipelines::new(device, exact, dirt_shaders::Chunks::ONE)?;
        Ok(Gpu {
            device: device.clone(),
            queue: queue.clone(),
            info,
            limits,
            exact,
            exactness,
            pipelines,
            split: Default::default(),
            bindings,
            submits: Default::default(),
            waits: Default::default(),
            lost: Default::default(),
        })
    }

    /// The pipelines for a structure whose split arrays are `split`: with one
    /// binding per array when none is split, else with the device's bindings
    /// for the split ones, compiled on first use. A scene pays for the chunk
    /// switch in its shaders only where it needs it.
    pub(crate) fn pipelines_for(&self, split: Split) -> Result<&crate::Pipelines, GpuError> {
        if split == Split::NONE {
            return Ok(&self.pipelines);
        }
        let chunks = self.chunk_bindings(split);
        self.split[split.index()]
            .get_or_init(|| {
                crate::Pipelines::new(&self.device, self.exact, chunks).map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(|e| GpuError::Shader {
                stage: "pipelines (split bindings)",
                message: e.clone(),
            })
    }

    /// Bindings the pipelines of `split` declare for `kind`: one, or the device's.
    pub(crate) fn declared(&self, split: Split, kind: Kind) -> u32 {
        if split.has(kind) {
            self.bindings.bindings(kind)
        } else {
            1
        }
    }

    /// Bindings the pipelines of `split` declare per split array.
    pub(crate) fn chunk_bindings(&self, split: Split) -> dirt_shaders::Chunks {
        dirt_shaders::Chunks {
            ids: self.declared(split, Kind::Ids),
            tris: self.declared(split, Kind::Tris),
            hiz: self.declared(split, Kind::Hiz),
            offsets: self.declared(split, Kind::Offsets),
        }
    }

    /// The adapter in words, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {})",
            self.info.name, self.info.backend, self.info.driver_info
        )
    }

    /// Bindings `array` is split across at most: one, and the storage
    /// buffers the device allows per stage beyond 8 (WebGPU's default, which
    /// the trace needs), dealt by [`BindingLimits::for_device`]: the list ids
    /// first, then the offsets, the Hi-Z pyramid and the triangles in turn, up
    /// to [`dirt_shaders::MAX_CHUNKS`] each. Fixed when the device is opened.
    pub fn bindings(&self, array: dirt_core::SplitArray) -> u32 {
        self.bindings.bindings(array)
    }

    /// [`Gpu::bindings`] of the list ids.
    pub fn id_bindings(&self) -> u32 {
        self.bindings(Kind::Ids)
    }

    /// [`Gpu::bindings`] of the triangles.
    pub fn tri_bindings(&self) -> u32 {
        self.bindings(Kind::Tris)
    }

    /// What this device binds, as it bounds a structure: the binding size
    /// read from [`Gpu::limits`] each time (tests lower it) and [`Gpu::bindings`].
    pub fn binding_limits(&self) -> BindingLimits {
        BindingLimits {
            max_binding: self
                .limits
                .max_storage_buffer_binding_size
                .min(self.limits.max_buffer_size),
            ..self.bindings
        }
    }

    /// True on lavapipe, the software Vulkan device CI asserts bits on.
    pub fn is_llvmpipe(&self) -> bool {
        self.info.name.contains("llvmpipe")
    }

    /// Submissions and waits dirt made on this device so far. Recording
    /// ([`crate::GpuAds::encode_build`], [`crate::TraceResources::encode_trace`])
    /// makes none: an application's frame can check it.
    pub fn host_syncs(&self) -> HostSyncs {
        use std::sync::atomic::Ordering::Relaxed;
        HostSyncs {
            submissions: self.submits.load(Relaxed),
            waits: self.waits.load(Relaxed),
        }
    }

    /// Runs `f` inside out-of-memory and validation error scopes: what wgpu
    /// reports there becomes a [`GpuError`] naming `what`, instead of going
    /// to the device's uncaptured-error handler (which panics by default).
    /// Popping a scope does not wait for the GPU natively; in a browser it
    /// resolves on the page's event loop, so there `f` runs without scopes
    /// (errors reach the handler) and only the async forms capture them
    /// ([`Gpu::scoped_async`]).
    pub fn scoped<T>(
        &self,
        what: &'static str,
        f: impl FnOnce() -> Result<T, GpuError>,
    ) -> Result<T, GpuError> {
        #[cfg(target_arch = "wasm32")]
        {
            let _ = what;
            f()
        }
        #[cfg(not(target_arch = "wasm32"))]
        crate::block(what, self.scoped_async(what, async { f() }))
    }

    /// [`Gpu::scoped`] around a future: the scopes are popped and awaited
    /// when it is done.
    pub(crate) async fn scoped_async<T>(
        &self,
        what: &'static str,
        fut: impl Future<Output = Result<T, GpuError>>,
    ) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = fut.await;
        let v = validation.pop().await;
        let o = oom.pop().await;
        if let Some(e) = o {
            return Err(GpuError::OutOfMemory {
                what,
                message: e.to_string(),
            });
        }
        if let Some(e) = v {
            return Err(self.classify(what, e.to_string()));
        }
        out
    }

    /// A wgpu error message as a [`GpuError`]: a lost device, or a validation error.
    pub(crate) fn classify(&self, what: &'static str, message: String) -> GpuError {
        // A poll runs the device-lost callback if the device is gone.
        let polled = self.device.poll(wgpu::PollType::Poll);
        let lower = message.to_lowercase();
        if polled.is_err()
            || self.lost.load(std::sync::atomic::Ordering::Acquire)
            || lower.contains("lost")
            || lower.contains("destroyed") && lower.contains("device")
        {
            GpuError::DeviceLost { what, message }
        } else {
            GpuError::Validation { what, message }
        }
    }

    /// Submits dirt's own commands (the host-slice wrappers, host builds and
    /// the GPU renderer), counted in [`Gpu::host_syncs`].
    pub fn submit(&self, enc: wgpu::CommandEncoder) {
        self.submits
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.queue.submit([enc.finish()]);
    }

    /// Waits for all submitted work.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.waits
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact path needs Vulkan, passthrough shaders, and no request for plain WGSL.
    #[test]
    fn the_exact_path_is_decided_in_one_place() {
        let pass = wgpu::Features::PASSTHROUGH_SHADERS;
        let none = wgpu::Features::empty();
        let default = GpuOptions::default();
        let plain = GpuOptions { plain_wgsl: true };
        assert!(exact_path(wgpu::Backend::Vulkan, pass, &default).0);
        assert!(!exact_path(wgpu::Backend::Vulkan, none, &default).0);
        assert!(!exact_path(wgpu::Backend::Metal, pass, &default).0);
        assert!(!exact_path(wgpu::Backend::BrowserWebGpu, none, &default).0);
        let (exact, why) = exact_path(wgpu::Backend::Vulkan, pass, &plain);
        assert!(!exact && why.contains("plain WGSL"), "{why}");
    }

    /// The shaders declare as many chunks as the limits deal bindings.
    #[test]
    fn the_shaders_chunks_are_the_limits_bindings() {
        assert_eq!(dirt_shaders::MAX_CHUNKS, BindingLimits::MAX_BINDINGS);
    }
}
