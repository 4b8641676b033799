//! The page's bindings (`wasm-bindgen`): what `web/main.js` calls.

use crate::{Backend, Page, WebError};
use dirt_core::{AdsParams, Traversal};
use dirt_gpu::{Gpu, GpuOptions, wgpu};
use dirt_render::gpu::output::SurfaceOutput;
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;
use web_sys::{CanvasRenderingContext2d, HtmlCanvasElement, ImageData};

/// The page's one device and what it came from (a canvas's surface is made
/// by the instance and configured for the adapter).
#[derive(Clone, Debug)]
struct PageDevice {
    gpu: &'static Gpu,
    instance: wgpu::Instance,
    adapter: wgpu::Adapter,
}

thread_local! {
    /// The page's one device, opened at the first use (and kept: the tracer borrows it).
    static GPU: RefCell<Option<PageDevice>> = const { RefCell::new(None) };
}

fn js(e: WebError) -> JsError {
    JsError::new(&e.to_string())
}

#[wasm_bindgen(start)]
fn start() {
    // A panic says what it was in the console, not only "unreachable".
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&JsValue::from_str(&info.to_string()));
    }));
}

/// The page's WebGPU device as dirt uses it (opened once).
pub async fn page_gpu() -> Result<&'static Gpu, WebError> {
    Ok(page_device().await?.gpu)
}

async fn page_device() -> Result<PageDevice, WebError> {
    if let Some(d) = GPU.with(|g| g.borrow().clone()) {
        return Ok(d);
    }
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::BROWSER_WEBGPU,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = instance
        .request_adapter(&wgpu::RequestAdapterOptions::default())
        .await
        .map_err(|e| WebError::NoWebGpu(e.to_string()))?;
    let (device, queue) = adapter
        .request_device(&dirt_gpu::device_descriptor(&adapter, "dirt-web"))
        .await
        .map_err(|e| WebError::NoWebGpu(e.to_string()))?;
    // The browser reports a shader the page's compiler refuses here (a
    // blocking scope inside `from_device` cannot wait for it in a page).
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let made = Gpu::from_device(&device, &queue, &GpuOptions::default());
    if let Some(e) = scope.pop().await {
        return Err(WebError::Gpu(dirt_gpu::GpuError::Shader {
            stage: "pipelines",
            message: e.to_string(),
        }));
    }
    let gpu: &'static Gpu = Box::leak(Box::new(made?));
    let d = PageDevice {
        gpu,
        instance,
        adapter,
    };
    GPU.with(|g| *g.borrow_mut() = Some(d.clone()));
    Ok(d)
}

/// The names of the built-in scenes.
#[wasm_bindgen]
pub fn builtin_scenes() -> Vec<String> {
    dirt_scene::BUILTIN_NAMES
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// A page path-tracing a scene on a canvas.
#[wasm_bindgen]
#[derive(Debug)]
pub struct WebPage {
    page: Rc<RefCell<Page>>,
    /// The canvas's 2D context, where the CPU backend's mean is drawn (the
    /// GPU backend's canvas is a WebGPU context the page presents on).
    ctx: Option<CanvasRenderingContext2d>,
    /// Why the page runs on the CPU, when it does.
    fallback: Option<String>,
}

/// Opens `scene` — a built-in name, or the bytes of a dropped `.glb` /
/// data-URI `.gltf` (`file`, named `scene`) — on `canvas` at its size.
/// `backend` is `"auto"` (WebGPU, the CPU where the browser has none),
/// `"gpu"` (WebGPU or an error) or `"cpu"`. The canvas takes a WebGPU
/// context with the GPU backend and a 2D one with the CPU's: a canvas keeps
/// the kind it was first given, so pass a fresh one when the backend changes.
#[wasm_bindgen]
pub async fn open_page(
    canvas: HtmlCanvasElement,
    scene: String,
    file: Option<Vec<u8>>,
    backend: String,
) -> Result<WebPage, JsError> {
    let loaded = match file {
        Some(bytes) => dirt_scene::load_gltf_bytes(&scene, bytes),
        None => dirt_scene::open(&scene),
    }
    .map_err(|e| js(e.into()))?;
    let params = AdsParams::default();
    let traversal = Traversal::HiZ;
    let (tracer, device, fallback) = match backend.as_str() {
        "cpu" => (Backend::cpu(params, traversal), None, None),
        "gpu" => {
            let d = page_device().await.map_err(js)?;
            (Backend::gpu(d.gpu, params, traversal), Some(d), None)
        }
        "auto" => match page_device().await {
            Ok(d) => (Backend::gpu(d.gpu, params, traversal), Some(d), None),
            Err(e) => (Backend::cpu(params, traversal), None, Some(e.to_string())),
        },
        other => {
            return Err(JsError::new(&format!(
                "backend {other:?}: expected auto, gpu or cpu"
            )));
        }
    };
    let (width, height) = (canvas.width(), canvas.height());
    let mut page = Page::new(loaded, width, height, tracer).await.map_err(js)?;
    let ctx = match device {
        Some(d) => {
            let surface = d
                .instance
                .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
                .map_err(|e| {
                    JsError::new(&format!(
                        "the canvas gives no WebGPU context ({e}): open the page again with a fresh canvas"
                    ))
                })?;
            // The browser reports a shader or pipeline it refuses here, not
            // at the first draw.
            let scope = d.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
            let out = SurfaceOutput::new(
                surface,
                &d.adapter,
                &d.gpu.device,
                &d.gpu.queue,
                width,
                height,
            );
            if let Some(e) = scope.pop().await {
                return Err(JsError::new(&format!("the canvas's output pass: {e}")));
            }
            let out = out.map_err(|e| js(e.into()))?;
            page.present_on(out).map_err(js)?;
            None
        }
        None => Some(
            canvas
                .get_context("2d")
                .ok()
                .flatten()
                .and_then(|c| c.dyn_into::<CanvasRenderingContext2d>().ok())
                .ok_or_else(|| {
                    JsError::new("the canvas has no 2d context (it was given another kind)")
                })?,
        ),
    };
    Ok(WebPage {
        page: Rc::new(RefCell::new(page)),
        ctx,
        fallback,
    })
}

#[wasm_bindgen]
impl WebPage {
    /// Renders one more sample pass and draws the mean. Resolves when done;
    /// call the next step after it (a step in flight refuses another).
    pub fn step(&self) -> js_sys::Promise {
        let page = self.page.clone();
        let ctx = self.ctx.clone();
        // The borrow is the step's in-flight mark: every other method tries
        // to borrow and gets an error, not a panic, while it is held.
        #[allow(clippy::await_holding_refcell_ref)]
        wasm_bindgen_futures::future_to_promise(async move {
            let Ok(mut p) = page.try_borrow_mut() else {
                return Err(JsValue::from_str("a step is already running"));
            };
            p.step()
                .await
                .map_err(|e| JsValue::from_str(&e.to_string()))?;
            // The GPU backend has drawn on its canvas already.
            if let (Some(ctx), Some(rgba)) = (ctx, p.rgba()) {
                let (w, h) = p.size();
                let image = ImageData::new_with_u8_clamped_array_and_sh(
                    wasm_bindgen::Clamped(&rgba),
                    w,
                    h,
                )?;
                ctx.put_image_data(&image, 0.0, 0.0)?;
            }
            Ok(JsValue::from(p.samples()))
        })
    }

    /// Turns the camera by a mouse drag of `(dx, dy)` pixels; the mean restarts.
    pub fn orbit(&self, dx: f32, dy: f32) -> Result<(), JsError> {
        self.moved(|p| p.orbit.drag_orbit(dx, dy))
    }

    /// Moves the camera towards (`steps` > 0) or away from its target.
    pub fn zoom(&self, steps: f32) -> Result<(), JsError> {
        self.moved(|p| p.orbit.zoom(steps))
    }

    fn moved(&self, f: impl FnOnce(&mut Page)) -> Result<(), JsError> {
        let mut p = self
            .page
            .try_borrow_mut()
            .map_err(|_| JsError::new("a step is running: move the camera after it"))?;
        f(&mut p);
        p.restart();
        Ok(())
    }

    fn read<T>(&self, f: impl FnOnce(&Page) -> T) -> Result<T, JsError> {
        let p = self
            .page
            .try_borrow()
            .map_err(|_| JsError::new("a step is running: ask after it"))?;
        Ok(f(&p))
    }

    /// Sample passes in the image.
    pub fn samples(&self) -> Result<u32, JsError> {
        self.read(Page::samples)
    }

    /// Rays per second since the camera last moved.
    pub fn rays_per_second(&self) -> Result<f64, JsError> {
        self.read(Page::rays_per_second)
    }

    /// The camera as `dirt render` takes it.
    pub fn camera_args(&self) -> Result<String, JsError> {
        self.read(Page::camera_args)
    }

    /// What traces, on what, and how many triangles, in words.
    pub fn status(&self) -> Result<String, JsError> {
        self.read(|p| {
            let (w, h) = p.size();
            let on = match p.backend() {
                Backend::Gpu(_) => GPU
                    .with(|g| g.borrow().as_ref().map(|d| d.gpu))
                    .map(|g| format!("WebGPU: {} ({})", g.describe(), g.exactness))
                    .unwrap_or_else(|| "WebGPU".into()),
                Backend::Cpu(_) => match &self.fallback {
                    Some(why) => format!("the CPU (wasm), because {why}"),
                    None => "the CPU (wasm)".into(),
                },
            };
            format!(
                "{} triangles, {w}x{h}, {} on {on}{}",
                p.triangles(),
                dirt_render::AsyncTrace::name(p.backend()),
                match (p.shaded_on_gpu(), p.presents()) {
                    (true, true) =>
                        "; shaded on the GPU and presented on the canvas, no image read back",
                    (true, false) => "; shaded on the GPU, one read-back a sample",
                    _ => "",
                }
            )
        })
    }
}

/// The portable path measured on the page's device: built-in `scene` built
/// with cube r`resolution` B`buckets` on WebGPU and traced with `rays`
/// random rays, against the CPU reference in this page and brute force.
#[wasm_bindgen]
pub async fn check_builtin(
    scene: String,
    resolution: u32,
    buckets: u32,
    rays: u32,
) -> Result<String, JsError> {
    let gpu = page_gpu().await.map_err(js)?;
    let s = dirt_scene::open(&scene).map_err(|e| js(e.into()))?;
    let params = AdsParams {
        resolution,
        buckets,
        ..AdsParams::default()
    };
    let rays = crate::probe_rays(&s.triangles, rays as usize, 1);
    let mut lines = Vec::new();
    for traversal in [Traversal::Linear, Traversal::HiZ] {
        let c = crate::check(gpu, &s.triangles, &rays, &params, traversal)
            .await
            .map_err(js)?;
        lines.push(format!("{traversal}: {}", c.summary()));
    }
    Ok(lines.join("\n"))
}
