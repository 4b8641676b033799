//! dirt-gpu: DIRT on wgpu, one pass per stage, mirroring `dirt-cpu` one to one.
//!
//! Entry points:
//! - [`Gpu::from_device`] (the application's device and queue) or [`Gpu::new`];
//! - [`DirtGpu`], the [`dirt_core::Tracer`]: `build(&triangles)` and `trace(&rays)` from host
//!   slices, or [`DirtGpu::encode_build`] and [`DirtGpu::encode_trace`] recorded into the
//!   application's encoder ([`DirtGpu::encode_trace_counted`] when the ray count is on the GPU);
//! - underneath, [`GpuAds::build`] (host triangles, each stage waited for), [`GpuAds::frame`]
//!   with [`GpuAds::encode_build`] (the application's [`GpuMesh`]es; see [`frame`] for list
//!   storage, feedback and synchronisation), and [`TraceResources`] (see [`trace`] for the
//!   ray, hit and statistics layouts, byte for byte, and continuation).
//!
//! Ownership: a [`GpuAds`] and a [`TraceResources`] own their buffers and keep them between
//! frames; the caller owns meshes, rays, hits and statistics buffers. Nothing here submits or
//! waits except the host-slice wrappers ([`Gpu::host_syncs`] counts them).
//!
//! | stage | pass | WGSL |
//! |---|---|---|
//! | `gather` | compute (frames only) | `gather.wgsl` |
//! | `views` | compute `bounds`, `views_from_bounds`, `reach`, `leave_out` (frames only) | `views.wgsl` |
//! | `fill_depth` | raster: `cover_vs` + `fill_depth` (+ compute `clear_depth` in frames) | `fill_depth.wgsl` (+ `coverage.wgsl`) |
//! | `mip_depth` | compute, one dispatch per level | `mip_depth.wgsl` |
//! | `fill_primitives` | raster `count`, compute `scan_blocks`/`scan_add`, raster `fill` | `fill_primitives.wgsl` |
//! | `trace` | compute, one thread per ray | `trace.wgsl` |
//!
//! On lavapipe (the CI device) every output equals the CPU reference's to the
//! bit: views, depth bounds, Hi-Z levels, list contents (as sets), hits and
//! statistics. What "exact" means per backend: NoContraction SPIR-V on Vulkan
//! ([`spirv`], decided by [`exact_path`]); elsewhere the driver compiles the
//! WGSL and may contract, and no bits are promised or measured.
//!
//! Tests in every crate get their GPU from [`testing`]: [`testing::any_gpu`]
//! for structure, sizes, errors and the absence of panics (any adapter,
//! hardware included), [`testing::exact_gpu`] for bit-for-bit comparisons with
//! the CPU (only the exact path on llvmpipe). A skip says which test, which
//! adapter and why; `DIRT_REQUIRE_GPU=1` (CI) makes it a failure.

mod chunked;
mod context;
pub mod fill_depth;
pub mod fill_primitives;
pub mod frame;
pub mod gather;
pub mod mip_depth;
pub mod params;
pub mod selftest;
pub mod spirv;
pub mod testing;
pub mod trace;
pub mod tracer;
pub mod views;

pub use context::{Gpu, GpuOptions, HostSyncs, device_descriptor, exact_path};
pub use frame::BuildFeedback;
pub use gather::GpuMesh;
pub use params::{
    BuildParams, FrameState, GatherParams, MipParams, PoolHeader, ScanParams, TraceParams,
    ViewsParams,
};
pub use trace::TraceResources;
pub use tracer::DirtGpu;
/// The wgpu this crate is built with: hand [`Gpu::from_device`] a device of this version.
pub use wgpu;

use dirt_core::{AdsParams, BuildTimings, CoreError, IdLists};
use dirt_math::dda::{hiz_levels, hiz_width};
use dirt_math::{Triangle, ViewGpu, ViewSet};
use web_time::Instant;

/// Errors of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter ({0}); install mesa-vulkan-drivers for the software one and set WGPU_BACKEND=vulkan"
    )]
    NoAdapter(String),
    #[error("GPU device error: {0}")]
    Device(String),
    #[error("shader `{stage}` failed: {message}")]
    Shader {
        stage: &'static str,
        message: String,
    },
    #[error(transparent)]
    Params(#[from] CoreError),
    /// The device lacks something dirt needs (a limit too low).
    #[error("this device cannot run dirt: {0}")]
    Unsupported(String),
    /// A buffer handed in by the caller is too small or lacks a usage.
    #[error("{what}: {problem}")]
    Buffer { what: &'static str, problem: String },
    #[error(
        "{what} needs {bytes} bytes in one binding; this adapter allows {limit} (max_storage_buffer_binding_size): use a lower resolution, fewer buckets or a smaller scene"
    )]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
    },
    /// An array of the structure (triangles, Hi-Z pyramid, list offsets,
    /// list ids) needs more than the device binds, split across
    /// [`Gpu::bindings`] bindings (see [`dirt_core::BindingLimits`]).
    #[error(
        "{what} need {bytes} bytes; this device binds at most {bindings} × {per_binding} bytes of them (max_storage_buffers_per_shader_stage, max_storage_buffer_binding_size): use a lower resolution, fewer buckets or a smaller scene"
    )]
    SplitTooLarge {
        what: &'static str,
        bytes: u64,
        bindings: u32,
        per_binding: u64,
    },
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// wgpu refused an allocation of the named step for lack of memory.
    #[error("{what}: out of GPU memory ({message})")]
    OutOfMemory { what: &'static str, message: String },
    /// wgpu reported a validation error in the named step.
    #[error("{what}: {message}")]
    Validation { what: &'static str, message: String },
    /// The device is lost (destroyed, reset or removed): make a new device and a new [`Gpu`].
    #[error("{what}: the GPU device is lost ({message}); make a new device and Gpu")]
    DeviceLost { what: &'static str, message: String },
}

/// Compiled pipelines, made once per device for one binding per split array, and once more
/// per set of split arrays when a structure first needs it ([`Gpu::pipelines_for`]).
#[derive(Debug)]
pub(crate) struct Pipelines {
    fill_depth: wgpu::RenderPipeline,
    mip_depth: wgpu::ComputePipeline,
    count: wgpu::RenderPipeline,
    scan_blocks: wgpu::ComputePipeline,
    scan_add: wgpu::ComputePipeline,
    fill: wgpu::RenderPipeline,
    trace: wgpu::ComputePipeline,
    trace_continue: wgpu::ComputePipeline,
    schedule: wgpu::ComputePipeline,
    /// `trace.wgsl`'s `size_first`: a counted trace's first dispatch.
    size_first: wgpu::ComputePipeline,
    clear_depth: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    /// `views.wgsl`'s entries, one layout: bounds, views_from_bounds, reach, leave_out.
    views: [wgpu::ComputePipeline; 4],
}

/// Render target format of the raster passes. Nothing is written to it (the
/// passes write storage buffers); WebGPU needs an attachment to rasterize.
const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

fn raster(
    device: &wgpu::Device,
    st: &spirv::Stage,
    fs: &str,
) -> Result<wgpu::RenderPipeline, GpuError> {
    let p = st.prepare(device, &["cover_vs", fs])?;
    let (vs_module, fs_module) = (&p.modules[0], p.modules.last().unwrap_or(&p.modules[0]));
    Ok(
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fs),
            layout: Some(&p.layout),
            vertex: wgpu::VertexState {
                module: vs_module,
                entry_point: Some("cover_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: fs_module,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: TARGET_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::empty(),
                })],
            }),
            multiview_mask: None,
            cache: None,
        }),
    )
}

pub(crate) fn compute(
    device: &wgpu::Device,
    st: &spirv::Stage,
    entry: &str,
) -> Result<wgpu::ComputePipeline, GpuError> {
    let mut p = compute_sharing(device, st, &[entry])?;
    p.pop().ok_or(GpuError::Shader {
        stage: "pipelines",
        message: format!("no pipeline for `{entry}`"),
    })
}

/// Compute pipelines of `entries` with one layout, so that one bind group serves them all.
pub(crate) fn compute_sharing(
    device: &wgpu::Device,
    st: &spirv::Stage,
    entries: &[&str],
) -> Result<Vec<wgpu::ComputePipeline>, GpuError> {
    let p = st.prepare(device, entries)?;
    Ok(entries
        .iter()
        .enumerate()
        .map(|(k, entry)| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&p.layout),
                module: p.modules.get(k).unwrap_or(&p.modules[0]),
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })
        .collect())
}

impl Pipelines {
    /// The pipelines of every stage; the list ids and the triangles split as `chunks` says.
    pub(crate) fn new(
        device: &wgpu::Device,
        passthrough: bool,
        chunks: dirt_shaders::Chunks,
    ) -> Result<Pipelines, GpuError> {
        // A browser resolves a popped scope only on the page's event loop:
        // there a shader error reaches the device's uncaptured-error handler.
        #[cfg(not(target_arch = "wasm32"))]
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let fd = spirv::compile(device, "fill_depth", passthrough, chunks)?;
        let md = spirv::compile(device, "mip_depth", passthrough, chunks)?;
        let fp = spirv::compile(device, "fill_primitives", passthrough, chunks)?;
        let tr = spirv::compile(device, "trace", passthrough, chunks)?;
        let vw = spirv::compile(device, "views", passthrough, chunks)?;
        let ga = spirv::compile(device, "gather", passthrough, chunks)?;
        let views: [wgpu::ComputePipeline; 4] = compute_sharing(
            device,
            &vw,
            &["bounds", "views_from_bounds", "reach", "leave_out"],
        )?
        .try_into()
        .map_err(|_| GpuError::Shader {
            stage: "views",
            message: "expected four pipelines".into(),
        })?;
        let [trace, trace_continue]: [wgpu::ComputePipeline; 2] =
            compute_sharing(device, &tr, &["trace", "trace_continue"])?
                .try_into()
                .map_err(|_| GpuError::Shader {
                    stage: "trace",
                    message: "expected two pipelines".into(),
                })?;
        let p = Pipelines {
            fill_depth: raster(device, &fd, "fill_depth")?,
            mip_depth: compute(device, &md, "mip_depth")?,
            count: raster(device, &fp, "count")?,
            scan_blocks: compute(device, &fp, "scan_blocks")?,
            scan_add: compute(device, &fp, "scan_add")?,
            fill: raster(device, &fp, "fill")?,
            trace,
            trace_continue,
            schedule: compute(device, &tr, "schedule")?,
            size_first: compute(device, &tr, "size_first")?,
            clear_depth: compute(device, &fd, "clear_depth")?,
            gather: compute(device, &ga, "gather")?,
            views,
        };
        #[cfg(not(target_arch = "wasm32"))]
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader {
                stage: "pipelines",
                message: e.to_string(),
            });
        }
        Ok(p)
    }
}

/// The acceleration structure on the GPU.
#[derive(Debug)]
pub struct GpuAds {
    pub params: AdsParams,
    /// The view set, when the host computed it ([`GpuAds::build`]); `None` for
    /// a structure built in a frame ([`GpuAds::frame`]), whose views the GPU
    /// computes ([`GpuAds::read_views`] reads them).
    pub views: Option<ViewSet>,
    pub n_tris: u32,
    /// List entries: exact for [`GpuAds::build`]; for a frame structure, 0
    /// ([`GpuAds::feedback`] has the count of the latest completed build).
    pub nodes: u32,
    /// Wall time of each build stage (submission to completion) of
    /// [`GpuAds::build`]; zero for a frame structure, whose stages are not waited for.
    pub timings: BuildTimings,
    /// Views in the set, and per-view blocks in the per-tile buffers (views
    /// with content for [`GpuAds::build`]; every view for a frame structure).
    pub(crate) n_views: u32,
    pub(crate) n_slots: u32,
    /// The triangles, split across bindings ([`chunked`]).
    pub(crate) tris: chunked::Chunked,
    pub(crate) views_uniform: wgpu::Buffer,
    /// All Hi-Z levels, level 0 (the depth bounds) first; two u32 per cell;
    /// split across bindings ([`chunked`]).
    pub(crate) hiz: chunked::Chunked,
    /// `slots·tiles²·B + 1` offsets after the scan (views without content
    /// have none); split across bindings ([`chunked`]).
    pub(crate) offsets: chunked::Chunked,
    /// The list ids, split across bindings ([`chunked`]).
    pub(crate) ids: chunked::Chunked,
    /// The kept parts of a frame structure ([`GpuAds::frame`]).
    pub(crate) frame: Option<Box<frame::Frame>>,
}

/// A zeroed buffer of `bytes` (at least 16, a multiple of 4: empty bindings are invalid).
pub(crate) fn buffer(
    gpu: &Gpu,
    label: &str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).div_ceil(4) * 4,
        usage,
        mapped_at_creation: false,
    })
}

/// A storage buffer holding `data` (at least 16 bytes: empty bindings are invalid).
pub(crate) fn storage_init(
    gpu: &Gpu,
    label: &str,
    data: &[u8],
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let mut bytes = data.to_vec();
    if bytes.len() < 16 {
        bytes.resize(16, 0);
    }
    buffer_init(gpu, label, &bytes, wgpu::BufferUsages::STORAGE | extra)
}

pub(crate) fn uniform_init(gpu: &Gpu, label: &str, data: &[u8]) -> wgpu::Buffer {
    buffer_init(gpu, label, data, wgpu::BufferUsages::UNIFORM)
}

/// A buffer holding `data`, written through the queue (it also gets
/// `COPY_DST`). Not wgpu's `create_buffer_init`: that panics when the device
/// is lost, where this leaves an error for [`Gpu::scoped`] to report. Public
/// for the passes of the crates above (the GPU renderer's tables).
pub fn buffer_init(gpu: &Gpu, label: &str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let size = (data.len() as u64).max(4).div_ceil(4) * 4;
    let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    if data.len() as u64 == size {
        gpu.queue.write_buffer(&buf, 0, data);
    } else {
        let mut padded = data.to_vec();
        padded.resize(size as usize, 0);
        gpu.queue.write_buffer(&buf, 0, &padded);
    }
    buf
}

/// `fixed` and then the split arrays' chunks: the `(binding, buffer)` pairs of a bind group.
pub(crate) fn with<'a, const N: usize>(
    fixed: &[(u32, &'a wgpu::Buffer)],
    arrays: [Vec<(u32, &'a wgpu::Buffer)>; N],
) -> Vec<(u32, &'a wgpu::Buffer)> {
    let mut out = fixed.to_vec();
    out.extend(arrays.into_iter().flatten());
    out
}

/// Bind group entries binding each buffer whole: `(binding, buffer)` pairs.
pub(crate) fn whole<'a>(
    buffers: impl IntoIterator<Item = (u32, &'a wgpu::Buffer)>,
) -> impl Iterator<Item = wgpu::BindGroupEntry<'a>> {
    buffers
        .into_iter()
        .map(|(binding, buf)| wgpu::BindGroupEntry {
            binding,
            resource: buf.as_entire_binding(),
        })
}

/// A bind group of whole buffers for group 0 of `layout`: `(binding, buffer)` pairs.
pub(crate) fn bind_buffers(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = whole(buffers.iter().copied()).collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// Records one compute pass: `pipeline` over `groups` workgroups with `bind` as group 0.
pub(crate) fn record_dispatch(
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    [x, y, z]: [u32; 3],
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(x, y, z);
}

/// [`record_dispatch`] sized by the three `u32` at the start of `args`
/// (written on the GPU; `args` needs `INDIRECT`).
pub(crate) fn record_dispatch_indirect(
    enc: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    args: &wgpu::Buffer,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups_indirect(args, 0);
}

/// Copies `size` bytes of `src` from `offset` back to the CPU (blocks; see
/// `block`: in a browser, use the async form). `src` needs `COPY_SRC`.
pub fn read_back(
    gpu: &Gpu,
    src: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    block("a read-back", read_back_async(gpu, src, offset, size))
}

/// [`read_back`] without blocking: the form a browser page awaits.
pub async fn read_back_async(
    gpu: &Gpu,
    src: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    let size = size.div_ceil(4) * 4;
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(src, offset, &staging, 0, size);
    gpu.submit(enc);
    map_read_async(gpu, &staging).await
}

/// Maps `staging` (MAP_READ) once the GPU is done and copies it out. A
/// native device runs the map's callback while it is polled (here); a
/// browser runs it on the page's event loop, which the `await` yields to.
pub(crate) async fn map_read_async(gpu: &Gpu, staging: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let (tx, rx) = futures_channel::oneshot::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    #[cfg(not(target_arch = "wasm32"))]
    gpu.wait()?;
    #[cfg(target_arch = "wasm32")]
    let _ = gpu;
    rx.await
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let view = staging
        .get_mapped_range(..)
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let out = view.to_vec();
    drop(view);
    staging.unmap();
    Ok(out)
}

/// Runs `fut`, one of dirt's async GPU operations, to its end on the
/// calling thread. Natively the device completes work while it is polled,
/// so `pollster` suffices. A browser completes it only on the page's event
/// loop, which a blocking call would stall: there `fut` is polled once, and
/// one that is not ready at once is [`GpuError::Unsupported`] (use the
/// `_async` form, e.g. [`DirtGpu::trace_async`]).
pub(crate) fn block<T>(
    what: &'static str,
    fut: impl Future<Output = Result<T, GpuError>>,
) -> Result<T, GpuError> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        let _ = what;
        pollster::block_on(fut)
    }
    #[cfg(target_arch = "wasm32")]
    {
        let mut fut = std::pin::pin!(fut);
        let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
        match fut.as_mut().poll(&mut cx) {
            std::task::Poll::Ready(out) => out,
            std::task::Poll::Pending => Err(GpuError::Unsupported(format!(
                "{what} waits for the GPU, and a browser page cannot block: use the async form"
            ))),
        }
    }
}

/// Cells of every Hi-Z level of `n_slots` views of `tiles`² tiles.
pub(crate) fn hiz_cells(tiles: u32, n_slots: u32) -> u64 {
    (0..hiz_levels(tiles))
        .map(|l| (hiz_width(tiles, l) as u64).pow(2) * n_slots as u64)
        .sum()
}

/// The views as the shaders read them: always six entries (unused ones zero).
pub(crate) fn views_gpu(views: &ViewSet) -> [ViewGpu; 6] {
    let mut out = [ViewGpu::default(); 6];
    for (k, v) in views.views.iter().enumerate().take(6) {
        out[k] = ViewGpu::new(v, views.adjacency.get(k).copied().unwrap_or([0; 4]));
    }
    out
}

impl GpuAds {
    /// Builds the structure on the GPU: `fill_depth`, `mip_depth`,
    /// `fill_primitives`, each submitted and waited for (the host path; see
    /// [`GpuAds::frame`] for builds recorded into a frame). wgpu's errors come
    /// back as [`GpuError`]s, a lost device as [`GpuError::DeviceLost`].
    pub fn build(gpu: &Gpu, tris: &[Triangle], params: &AdsParams) -> Result<GpuAds, GpuError> {
        gpu.scoped("the GPU build", || Self::build_unscoped(gpu, tris, params))
    }

    fn build_unscoped(
        gpu: &Gpu,
        tris: &[Triangle],
        params: &AdsParams,
    ) -> Result<GpuAds, GpuError> {
        let views = dirt_core::views_for(tris, params)?;
        let tiles = params.tiles();
        let n_views = views.views.len() as u32;
        // Views without content get no passes and no memory: buffers hold one block per slot.
        let n_slots = views.slots() as u32;
        let content: Vec<u32> = (0..n_views)
            .filter(|&v| views.views[v as usize].has_content)
            .collect();
        let n_tris = u32::try_from(tris.len()).map_err(|_| {
            CoreError::InvalidParams(format!("{} triangles is more than 2^32-1", tris.len()))
        })?;
        // Everything that must fit its bindings is checked before any work
        // starts, in this order: triangles, Hi-Z pyramid, offsets (the ids once counted).
        let tri_buf =
            chunked::Chunked::with_data(gpu, chunked::Kind::Tris, bytemuck::cast_slice(tris))?;
        let cells = hiz_cells(tiles, n_slots);
        let n_lists = n_slots as u64 * (tiles as u64).pow(2) * params.buckets as u64;
        let hiz = fill_depth::new_hiz(gpu, cells)?;
        // Counts, then (after the scan) offsets; one more so that offsets[n_lists] is the total.
        let offsets = chunked::Chunked::new(gpu, chunked::Kind::Offsets, n_lists + 1)?;

        let views_uniform = uniform_init(gpu, "views", bytemuck::cast_slice(&views_gpu(&views)));
        let build = BuildParams {
            n_tris,
            n_views,
            tiles,
            buckets: params.buckets,
            id_shift: gpu.binding_limits().shift(chunked::Kind::Ids),
            tri_shift: tri_buf.shift(),
            hiz_shift: hiz.shift(),
            offset_shift: offsets.shift(),
        };
        let build_uniform = uniform_init(gpu, "build params", bytemuck::bytes_of(&build));
        let split = chunked::Split::of(&[&tri_buf, &hiz]);

        let t0 = Instant::now();
        fill_depth::fill_depth(
            gpu,
            split,
            &tri_buf,
            &views_uniform,
            &build_uniform,
            &hiz,
            &build,
            &content,
        )?;
        let t1 = Instant::now();
        mip_depth::mip_depth(gpu, split, &hiz, tiles, n_slots)?;
        let t2 = Instant::now();
        let (ids, nodes) = fill_primitives::fill_primitives(
            gpu,
            &tri_buf,
            &views_uniform,
            &build_uniform,
            &hiz,
            &offsets,
            &build,
            &content,
            n_lists,
        )?;
        let t3 = Instant::now();
        Ok(GpuAds {
            params: *params,
            n_views,
            n_slots,
            views: Some(views),
            n_tris,
            nodes,
            timings: BuildTimings {
                fill_depth: t1 - t0,
                mip_depth: t2 - t1,
                fill_primitives: t3 - t2,
            },
            tris: tri_buf,
            views_uniform,
            hiz,
            offsets,
            ids,
            frame: None,
        })
    }

    /// Which of the structure's arrays take more than one binding: the
    /// pipelines its passes run are [`Gpu::pipelines_for`] that.
    pub(crate) fn split(&self) -> chunked::Split {
        chunked::Split::of(&[&self.tris, &self.ids, &self.hiz, &self.offsets])
    }

    /// Buffers the list ids take (one per binding they need; see [`Gpu::id_bindings`]).
    pub fn id_chunks(&self) -> usize {
        self.ids.chunks()
    }

    /// Buffers the triangles take (one per binding they need; see [`Gpu::tri_bindings`]).
    pub fn tri_chunks(&self) -> usize {
        self.tris.chunks()
    }

    /// Buffers the Hi-Z pyramid takes (one per binding it needs; see [`Gpu::bindings`]).
    pub fn hiz_chunks(&self) -> usize {
        self.hiz.chunks()
    }

    /// Buffers the list offsets take (one per binding they need; see [`Gpu::bindings`]).
    pub fn offset_chunks(&self) -> usize {
        self.offsets.chunks()
    }

    /// Bytes of the structure on the GPU: the Hi-Z pyramid (depth bounds
    /// included), list offsets and ids, as allocated.
    pub fn memory_bytes(&self) -> u64 {
        self.hiz.bytes() + self.offsets.bytes() + self.ids.bytes()
    }

    /// The views as the passes read them (six entries; a view without
    /// content has slot [`dirt_math::view::NO_SLOT`]).
    pub fn read_views(&self, gpu: &Gpu) -> Result<Vec<ViewGpu>, GpuError> {
        block("reading the views", self.read_views_async(gpu))
    }

    /// [`GpuAds::read_views`] without blocking (a browser page awaits it).
    pub async fn read_views_async(&self, gpu: &Gpu) -> Result<Vec<ViewGpu>, GpuError> {
        let bytes = read_back_async(
            gpu,
            &self.views_uniform,
            0,
            6 * std::mem::size_of::<ViewGpu>() as u64,
        )
        .await?;
        Ok(bytemuck::pod_collect_to_vec::<u8, ViewGpu>(&bytes))
    }

    /// Hi-Z levels read back, level 0 (the depth bounds) first, in the CPU's layout.
    pub fn read_hiz(&self, gpu: &Gpu) -> Result<Vec<Vec<[u32; 2]>>, GpuError> {
        block("reading the Hi-Z", self.read_hiz_async(gpu))
    }

    /// [`GpuAds::read_hiz`] without blocking (a browser page awaits it).
    pub async fn read_hiz_async(&self, gpu: &Gpu) -> Result<Vec<Vec<[u32; 2]>>, GpuError> {
        let tiles = self.params.tiles();
        let cells = bytemuck::pod_collect_to_vec::<u8, [u32; 2]>(
            &self.hiz.read(gpu, hiz_cells(tiles, self.n_slots)).await?,
        );
        let mut rest = cells.as_slice();
        let mut out = Vec::new();
        for l in 0..hiz_levels(tiles) {
            let n = (hiz_width(tiles, l) as usize).pow(2) * self.n_slots as usize;
            let (level, more) = rest.split_at(n.min(rest.len()));
            out.push(level.to_vec());
            rest = more;
        }
        Ok(out)
    }

    /// The id lists read back (offsets and ids; ids in GPU order inside each list).
    pub fn read_lists(&self, gpu: &Gpu) -> Result<IdLists, GpuError> {
        block("reading the lists", self.read_lists_async(gpu))
    }

    /// [`GpuAds::read_lists`] without blocking (a browser page awaits it).
    pub async fn read_lists_async(&self, gpu: &Gpu) -> Result<IdLists, GpuError> {
        let n_lists =
            self.n_slots as u64 * (self.params.tiles() as u64).pow(2) * self.params.buckets as u64;
        let offsets =
            bytemuck::pod_collect_to_vec::<u8, u32>(&self.offsets.read(gpu, n_lists + 1).await?);
        let total = offsets.last().copied().unwrap_or(0) as u64;
        if total > self.ids.capacity() {
            return Err(GpuError::TooLarge {
                what: "list ids (the build overflowed them; build again)",
                bytes: total * 4,
                limit: self.ids.capacity() * 4,
            });
        }
        let ids = bytemuck::pod_collect_to_vec::<u8, u32>(&self.ids.read(gpu, total).await?);
        Ok(IdLists { offsets, ids })
    }
}

/// `shaders/wgsl/<stage>.wgsl` composed and compiled as plain WGSL (no bits
/// promised: no NoContraction path): for passes of the crates above this
/// one, such as the GPU renderer's shading.
pub fn wgsl_module(gpu: &Gpu, stage: &'static str) -> Result<wgpu::ShaderModule, GpuError> {
    wgsl_module_on(&gpu.device, stage)
}

/// [`wgsl_module`] on any device, one dirt did not open as a [`Gpu`] too
/// (a window's, which presents what the CPU rendered).
pub fn wgsl_module_on(
    device: &wgpu::Device,
    stage: &'static str,
) -> Result<wgpu::ShaderModule, GpuError> {
    let composed = dirt_shaders::compose(stage).map_err(|e| GpuError::Shader {
        stage,
        message: e.to_string(),
    })?;
    Ok(device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(stage),
        source: wgpu::ShaderSource::Wgsl(composed.text.into()),
    }))
}

/// Compute pipelines of `entries` of `shaders/wgsl/<stage>.wgsl`, sharing one
/// layout (one bind group serves them all), compiled as DIRT's own passes
/// are: with NoContraction where [`Gpu::exact`] holds, so that arithmetic
/// which must equal the CPU's bit for bit (an exact ray/triangle test in a
/// crate above this one) does.
pub fn exact_compute_pipelines(
    gpu: &Gpu,
    stage: &'static str,
    entries: &[&str],
) -> Result<Vec<wgpu::ComputePipeline>, GpuError> {
    let st = spirv::compile(&gpu.device, stage, gpu.exact, dirt_shaders::Chunks::ONE)?;
    compute_sharing(&gpu.device, &st, entries)
}
