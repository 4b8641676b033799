//! Stage `output` on the GPU (the CPU's is [`crate::output`]): the image
//! drawn on a texture a window or canvas shows. [`Output`] records one
//! fullscreen triangle that either tone-maps [`super::GpuRenderer::sums`]
//! where they lie, as [`crate::Image::to_srgb8`] writes its bytes (nothing
//! is read back), or copies an image uploaded as sRGB bytes.
//! [`SurfaceOutput`] adds the surface: its format, its size and the present.

use super::types::Tone;
use crate::RenderError;
use dirt_gpu::wgpu;

/// The `output` pass for targets of one format, on one device.
#[derive(Debug)]
pub struct Output {
    bytes_pipeline: wgpu::RenderPipeline,
    sums_pipeline: wgpu::RenderPipeline,
    tone: wgpu::Buffer,
    /// The uploaded image's texture and bind group, made again when its size changes.
    image: Option<(wgpu::Texture, wgpu::BindGroup)>,
    /// The sums buffer last drawn and its bind group, kept while it is the same.
    sums_bind: Option<(wgpu::Buffer, wgpu::BindGroup)>,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

/// The fullscreen triangle with fragment entry `fs` of `module`, drawing to `format`.
fn fullscreen(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    format: wgpu::TextureFormat,
    fs: &str,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
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

impl Output {
    /// The pass drawing to textures of `format` (an sRGB format gets the
    /// decoding entries, so the bytes shown are the same).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        format: wgpu::TextureFormat,
    ) -> Result<Self, RenderError> {
        let module = dirt_gpu::wgsl_module_on(device, "output")?;
        let srgb = format.is_srgb();
        let pick = |plain, srgb_entry| if srgb { srgb_entry } else { plain };
        let bytes_pipeline = fullscreen(
            device,
            &module,
            format,
            pick("fs_bytes_plain", "fs_bytes_srgb"),
        );
        let sums_pipeline = fullscreen(
            device,
            &module,
            format,
            pick("fs_sums_plain", "fs_sums_srgb"),
        );
        let tone = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("output tone"),
            size: std::mem::size_of::<Tone>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            bytes_pipeline,
            sums_pipeline,
            tone,
            image: None,
            sums_bind: None,
            device: device.clone(),
            queue: queue.clone(),
        })
    }

    /// Records the mean of `samples` samples of `sums` (`width` x `height`
    /// pixels, [`super::GpuRenderer::sums`] on this device) at `exposure`
    /// stops, drawn over `target`. The tone (16 bytes) is written to the
    /// queue now, so record one draw of the sums per submission.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_sums(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        sums: &wgpu::Buffer,
        width: u32,
        height: u32,
        samples: u32,
        exposure: f32,
    ) -> Result<(), RenderError> {
        if width == 0 || height == 0 || sums.size() < 16 * u64::from(width) * u64::from(height) {
            return Err(RenderError::Unsupported(format!(
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
                label: Some("output sums"),
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
        if let Some((_, bind)) = &self.sums_bind {
            draw(enc, target, &self.sums_pipeline, bind);
        }
        Ok(())
    }

    /// Uploads `rgba` (`width` x `height` sRGB bytes with alpha, rows top to
    /// bottom: [`crate::Image::to_rgba8`]) and records its copy over `target`.
    pub fn encode_bytes(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        rgba: &[u8],
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
        if width == 0 || height == 0 || rgba.len() != 4 * width as usize * height as usize {
            return Err(RenderError::Unsupported(format!(
                "{} bytes for a {width}x{height} RGBA image",
                rgba.len()
            )));
        }
        let same = self
            .image
            .as_ref()
            .is_some_and(|(t, _)| t.width() == width && t.height() == height);
        if !same {
            let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("output image"),
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
                label: Some("output image"),
                layout: &self.bytes_pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            self.image = Some((texture, bind));
        }
        if let Some((texture, bind)) = &self.image {
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
            draw(enc, target, &self.bytes_pipeline, bind);
        }
        Ok(())
    }
}

/// One render pass: `pipeline` with `bind`, the fullscreen triangle over `target`.
fn draw(
    enc: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    bind: &wgpu::BindGroup,
) {
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("output"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
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

/// What [`SurfaceOutput`] draws: the renderer's sums or uploaded bytes.
#[derive(Clone, Copy, Debug)]
pub enum Drawn<'a> {
    /// [`Output::encode_sums`]'s arguments after the target.
    Sums {
        sums: &'a wgpu::Buffer,
        width: u32,
        height: u32,
        samples: u32,
        exposure: f32,
    },
    /// [`Output::encode_bytes`]'s arguments after the target.
    Bytes {
        rgba: &'a [u8],
        width: u32,
        height: u32,
    },
}

/// A window's or canvas's surface with the [`Output`] pass drawing on it.
#[derive(Debug)]
pub struct SurfaceOutput {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The pass, and the device and queue the surface is configured on.
    output: Output,
}

impl SurfaceOutput {
    /// `surface` (of `adapter`) configured at `width` x `height` on
    /// `device`: a plain 8-bit format where it has one (the bytes shown as
    /// they are), else its first, decoded for when sRGB.
    pub fn new(
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let caps = surface.get_capabilities(adapter);
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
                RenderError::Surface(format!(
                    "the adapter {} cannot present to this surface",
                    adapter.get_info().name
                ))
            })?;
        // Opaque where offered: the image has no transparency to blend.
        let alpha_mode = if caps.alpha_modes.contains(&wgpu::CompositeAlphaMode::Opaque) {
            wgpu::CompositeAlphaMode::Opaque
        } else {
            caps.alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto)
        };
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: width.max(1),
            height: height.max(1),
            desired_maximum_frame_latency: 2,
            // Fifo: every surface has it.
            present_mode: wgpu::PresentMode::Fifo,
            alpha_mode,
            view_formats: vec![],
        };
        surface.configure(device, &config);
        Ok(Self {
            surface,
            config,
            output: Output::new(device, queue, format)?,
        })
    }

    /// The surface's format.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.config.format
    }

    /// The surface's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// The window's new size in pixels (a minimised window keeps the old one).
    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 && (width, height) != self.size() {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.output.device, &self.config);
        }
    }

    /// Draws `what` over the surface's next texture and presents it (one
    /// submission). Whether it was shown: a hidden window, or one being
    /// resized, skips the frame.
    pub fn draw(&mut self, what: Drawn<'_>) -> Result<bool, RenderError> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            // Hidden or mid-resize: skip this one, the next draw tries again.
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(false);
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&self.output.device, &self.config);
                return Ok(false);
            }
            other => {
                return Err(RenderError::Surface(format!(
                    "cannot get the surface's next texture: {other:?}"
                )));
            }
        };
        let target = frame
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self
            .output
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("output"),
            });
        match what {
            Drawn::Sums {
                sums,
                width,
                height,
                samples,
                exposure,
            } => self
                .output
                .encode_sums(&mut enc, &target, sums, width, height, samples, exposure)?,
            Drawn::Bytes {
                rgba,
                width,
                height,
            } => self
                .output
                .encode_bytes(&mut enc, &target, rgba, width, height)?,
        }
        self.output.queue.submit([enc.finish()]);
        self.output.queue.present(frame);
        Ok(true)
    }
}
