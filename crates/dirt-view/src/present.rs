//! Putting the image on the window: the device (shared with DIRT on the GPU
//! when it traces there) and the window's surface, drawn by the renderer's
//! `output` pass (`dirt_render::gpu::output`): the image either uploaded
//! ([`Presenter::draw`]) or, when the GPU renderer shades it, tone-mapped
//! from its radiance sums where they lie ([`Presenter::draw_sums`]: nothing
//! is read back).

use std::sync::Arc;

use dirt_render::gpu::output::{Drawn, SurfaceOutput};
use winit::window::Window;

use crate::ViewError;

/// The instance, adapter, device and queue: made before the window, so that
/// DIRT on the GPU can be built on the same device.
#[derive(Debug)]
pub struct Device {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl Device {
    /// The adapter wgpu prefers (`WGPU_BACKEND` is honoured), with what DIRT
    /// asks of a device (`dirt_gpu::Gpu::open_device`): passthrough shaders
    /// where there are any (DIRT's exact path), the adapter's largest buffers
    /// and bindings.
    pub fn open(display: winit::event_loop::OwnedDisplayHandle) -> Result<Self, ViewError> {
        let instance = wgpu::Instance::new(
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(display)),
        );
        let adapter =
            pollster::block_on(
                instance.request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::from_env()
                        .unwrap_or(wgpu::PowerPreference::HighPerformance),
                    force_fallback_adapter: false,
                    compatible_surface: None,
                    apply_limit_buckets: false,
                }),
            )
            .map_err(|e| ViewError::NoGpu(e.to_string()))?;
        // The device dirt-gpu asks for, so the exact path and the limits are the library's.
        let (device, queue) = pollster::block_on(
            adapter.request_device(&dirt_gpu::device_descriptor(&adapter, "dirt view")),
        )
        .map_err(|e| ViewError::NoGpu(format!("cannot open a device: {e}")))?;
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
        })
    }

    /// A software adapter (lavapipe, llvmpipe, WARP): DIRT on the CPU is faster there.
    pub fn is_software(&self) -> bool {
        let info = self.adapter.get_info();
        info.device_type == wgpu::DeviceType::Cpu || info.name.contains("llvmpipe")
    }

    /// The adapter in words.
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?}, {})", info.name, info.backend, info.driver_info)
    }
}

/// The window's surface and what draws the image on it.
#[derive(Debug)]
pub struct Presenter {
    out: SurfaceOutput,
}

impl Presenter {
    pub fn new(dev: &Device, window: Arc<Window>) -> Result<Self, ViewError> {
        let size = window.inner_size();
        let surface = dev
            .instance
            .create_surface(window)
            .map_err(|e| ViewError::Surface(e.to_string()))?;
        let out = SurfaceOutput::new(
            surface,
            &dev.adapter,
            &dev.device,
            &dev.queue,
            size.width,
            size.height,
        )?;
        Ok(Self { out })
    }

    /// The window's new size in pixels (a minimised window keeps the old one).
    pub fn resize(&mut self, width: u32, height: u32) {
        self.out.resize(width, height);
    }

    /// Uploads `rgba` (`width` x `height`, 8-bit sRGB) and draws it over the window.
    pub fn draw(&mut self, rgba: &[u8], width: u32, height: u32) -> Result<(), ViewError> {
        self.out.draw(Drawn::Bytes {
            rgba,
            width,
            height,
        })?;
        Ok(())
    }

    /// Draws the mean of `samples` samples of the GPU renderer's radiance
    /// sums (`width` x `height`, [`dirt_render::gpu::GpuRenderer::sums`], on
    /// this presenter's device), tone-mapped at `exposure` stops as
    /// `dirt render` writes its PNG: nothing is read back.
    pub fn draw_sums(
        &mut self,
        sums: &wgpu::Buffer,
        width: u32,
        height: u32,
        samples: u32,
        exposure: f32,
    ) -> Result<(), ViewError> {
        self.out.draw(Drawn::Sums {
            sums,
            width,
            height,
            samples,
            exposure,
        })?;
        Ok(())
    }
}
