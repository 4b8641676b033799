//! Putting the image on the window: the device (shared with DIRT on the GPU
//! when it traces there), the surface, and a fullscreen triangle that copies
//! the tone-mapped image, texel for texel, to the window (nearest texel when
//! the window is larger than the image). The image is either uploaded
//! ([`Presenter::draw`]) or, when the GPU renderer shades it, tone-mapped
//! from its radiance sums where they lie ([`Presenter::draw_sums`]: nothing
//! is read back).

use std::sync::Arc;

use winit::window::Window;

use crate::ViewError;

const SHADER: &str = r#"
struct Out {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@group(0) @binding(0) var img: texture_2d<f32>;

// One triangle covering the screen: (-1,-1), (3,-1), (-1,3).
@vertex
fn vs(@builtin(vertex_index) i: u32) -> Out {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var o: Out;
    o.pos = vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
    o.uv = vec2<f32>(p.x, 1.0 - p.y);
    return o;
}

fn texel(uv: vec2<f32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(img));
    let xy = clamp(vec2<i32>(floor(uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    return textureLoad(img, xy, 0);
}

// The texels are sRGB bytes already: written as they are to a plain target...
@fragment
fn fs_plain(in: Out) -> @location(0) vec4<f32> {
    return texel(in.uv);
}

// ...and decoded for an sRGB target, which encodes them again.
fn decode(c: vec3<f32>) -> vec4<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return vec4<f32>(select(hi, lo, c <= vec3<f32>(0.04045)), 1.0);
}

@fragment
fn fs_srgb(in: Out) -> @location(0) vec4<f32> {
    return decode(texel(in.uv).rgb);
}

// The GPU renderer's radiance sums (dirt_render::gpu::GpuRenderer::sums) and
// how to tone-map their mean as dirt_render::Image::to_srgb8 does.
struct Tone {
    width: u32,
    height: u32,
    inv_samples: f32,
    // 2^exposure
    scale: f32,
}

@group(0) @binding(1) var<storage, read> sums: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> tone: Tone;

fn aces(x: f32) -> f32 {
    let y = max(x, 0.0);
    return clamp((y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14), 0.0, 1.0);
}

fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// One channel as the 8-bit value to_srgb8 writes, over 255 (non-finite: 0).
fn byte(c: f32) -> f32 {
    let v = select(0.0, c, abs(c) <= 3.4028235e38);
    return floor(clamp(linear_to_srgb(aces(v * tone.scale)) * 255.0 + 0.5, 0.0, 255.0)) / 255.0;
}

fn mean_texel(uv: vec2<f32>) -> vec3<f32> {
    let size = vec2<i32>(i32(tone.width), i32(tone.height));
    let xy = clamp(vec2<i32>(floor(uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    let m = sums[u32(xy.y) * tone.width + u32(xy.x)].rgb * tone.inv_samples;
    return vec3<f32>(byte(m.r), byte(m.g), byte(m.b));
}

@fragment
fn fs_sums_plain(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(mean_texel(in.uv), 1.0);
}

@fragment
fn fs_sums_srgb(in: Out) -> @location(0) vec4<f32> {
    return decode(mean_texel(in.uv));
}
"#;

/// `struct Tone` of the present shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Tone {
    width: u32,
    height: u32,
    inv_samples: f32,
    scale: f32,
}

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
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    pipeline: wgpu::RenderPipeline,
    /// The image's texture and bind group, remade when its size changes.
    image: Option<(wgpu::Texture, wgpu::BindGroup)>,
    /// Tone-mapping the GPU renderer's sums in place.
    sums_pipeline: wgpu::RenderPipeline,
    tone: wgpu::Buffer,
    /// The sums buffer last drawn and its bind group, kept while it is the same.
    sums_bind: Option<(wgpu::Buffer, wgpu::BindGroup)>,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

/// The fullscreen triangle with fragment entry `fs` of `module`, drawing to `format`.
fn fullscreen(
    dev: &Device,
    module: &wgpu::ShaderModule,
    format: wgpu::TextureFormat,
    fs: &str,
) -> wgpu::RenderPipeline {
    dev.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fs),
            layout: None,
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
}

impl Presenter {
    pub fn new(dev: &Device, window: Arc<Window>) -> Result<Self, ViewError> {
        let size = window.inner_size();
        let surface = dev
            .instance
            .create_surface(window)
            .map_err(|e| ViewError::Surface(e.to_string()))?;
        let caps = surface.get_capabilities(&dev.adapter);
        // A plain 8-bit format shows the bytes as they are; else decode for an sRGB one.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| {
                ViewError::Surface(format!(
                    "the adapter {} cannot present to this window",
                    dev.describe()
                ))
            })?;
        let alpha_mode = caps
            .alpha_modes
            .first()
            .copied()
            .unwrap_or(wgpu::CompositeAlphaMode::Auto);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            desired_maximum_frame_latency: 2,
            // Fifo: every surface has it.
            present_mode: wgpu::PresentMode::Fifo,
            alpha_mode,
            view_formats: vec![],
        };
        surface.configure(&dev.device, &config);
        let module = dev
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("dirt view present"),
                source: wgpu::ShaderSource::Wgsl(SHADER.into()),
            });
        let srgb = format.is_srgb();
        let pipeline = fullscreen(
            dev,
            &module,
            format,
            if srgb { "fs_srgb" } else { "fs_plain" },
        );
        let sums_pipeline = fullscreen(
            dev,
            &module,
            format,
            if srgb {
                "fs_sums_srgb"
            } else {
                "fs_sums_plain"
            },
        );
        let tone = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dirt view tone"),
            size: std::mem::size_of::<Tone>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            surface,
            config,
            pipeline,
            image: None,
            sums_pipeline,
            tone,
            sums_bind: None,
            device: dev.device.clone(),
            queue: dev.queue.clone(),
        })
    }

    /// The window's new size in pixels (a minimised window keeps the old one).
    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Uploads `rgba` (`width` x `height`, 8-bit sRGB) and draws it over the window.
    pub fn draw(&mut self, rgba: &[u8], width: u32, height: u32) -> Result<(), ViewError> {
        let same = self
            .image
            .as_ref()
            .is_some_and(|(t, _)| t.width() == width && t.height() == height);
        if !same {
            let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("dirt view image"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("dirt view image"),
                layout: &self.pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            self.image = Some((texture, bind));
        }
        let Some((texture, bind)) = &self.image else {
            return Err(ViewError::Internal("no image texture".into()));
        };
        if rgba.len() != 4 * width as usize * height as usize {
            return Err(ViewError::Internal(format!(
                "{} bytes for a {width}x{height} RGBA image",
                rgba.len()
            )));
        }
        self.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            rgba,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * width),
                rows_per_image: Some(height),
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        present(
            &self.surface,
            &self.config,
            &self.device,
            &self.queue,
            &self.pipeline,
            bind,
        )
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
        if sums.size() < 16 * u64::from(width) * u64::from(height) {
            return Err(ViewError::Internal(format!(
                "{} bytes of sums for a {width}x{height} image",
                sums.size()
            )));
        }
        let tone = Tone {
            width,
            height,
            inv_samples: if samples == 0 {
                0.0
            } else {
                1.0 / samples as f32
            },
            scale: exposure.exp2(),
        };
        self.queue
            .write_buffer(&self.tone, 0, bytemuck::bytes_of(&tone));
        if self.sums_bind.as_ref().is_none_or(|(b, _)| b != sums) {
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("dirt view sums"),
                layout: &self.sums_pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: sums.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: self.tone.as_entire_binding(),
                    },
                ],
            });
            self.sums_bind = Some((sums.clone(), bind));
        }
        let Some((_, bind)) = &self.sums_bind else {
            return Err(ViewError::Internal("no bind group for the sums".into()));
        };
        present(
            &self.surface,
            &self.config,
            &self.device,
            &self.queue,
            &self.sums_pipeline,
            bind,
        )
    }
}

/// Draws `pipeline` with `bind` over the window's next image and presents it.
fn present(
    surface: &wgpu::Surface<'static>,
    config: &wgpu::SurfaceConfiguration,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pipeline: &wgpu::RenderPipeline,
    bind: &wgpu::BindGroup,
) -> Result<(), ViewError> {
    let frame = match surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
        // Hidden or mid-resize: skip this one, the next redraw tries again.
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
            return Ok(());
        }
        wgpu::CurrentSurfaceTexture::Outdated => {
            surface.configure(device, config);
            return Ok(());
        }
        other => {
            return Err(ViewError::Surface(format!(
                "cannot get the window's next image: {other:?}"
            )));
        }
    };
    let target = frame
        .texture
        .create_view(&wgpu::TextureViewDescriptor::default());
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("dirt view present"),
    });
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("dirt view present"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.draw(0..3, 0..1);
    }
    queue.submit([enc.finish()]);
    queue.present(frame);
    Ok(())
}
