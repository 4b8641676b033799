//! The wavefront integrator: per sample, `direct_visibility` → `fetch` →
//! per bounce { `shade` (next-event estimation: shadow rays → `trace`),
//! `shade` (BSDF sampling) → `trace` → `fetch` → `shade` (three-point
//! throughput, emission, roulette) → `shift` }.

use crate::camera::Camera;
use crate::direct_visibility::{self, Raster, VisibilityStats};
use crate::fetch::{Fetcher, SurfacePoint};
use crate::lights::Lights;
use crate::output::Image;
use crate::rng::{Sampler, dim};
use crate::shade::{ShadeContext, offset_origin};
use crate::shading_buffer::ShadingBuffer;
use crate::trace::{AsyncTrace, Blocking, Tracer, now};
use crate::{Mode, RenderError, Settings, shift};
use dirt_math::{Hit, Ray, Vec3};
use dirt_scene::Scene;
use rayon::prelude::*;
use std::time::Duration;
use web_time::Instant;

/// Reported after every sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub samples_done: u32,
    pub spp: u32,
    /// Rays traced so far (primary, continuation and shadow rays); zero
    /// while they are counted on the GPU (`gpu::GpuRenderer` reads its
    /// count back with the image, at the end).
    pub rays: u64,
    pub elapsed: Duration,
}

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub image: Image,
    /// Rays traced in total.
    pub rays: u64,
    pub visibility: VisibilityStats,
    /// Time spent inside the tracer; zero when the trace is not timed apart
    /// from the shading (a render shaded on the GPU: `gpu::GpuRenderer`).
    pub trace_time: Duration,
    pub elapsed: Duration,
    pub tracer: String,
}

/// One sample of every pixel ([`Renderer::render_sample`]): what
/// [`Renderer::render`] adds up per sample, for callers that accumulate
/// themselves (a progressive viewer).
#[derive(Clone, Debug)]
pub struct SamplePass {
    /// Linear radiance per pixel, rows top to bottom.
    pub radiance: Vec<Vec3>,
    /// Rays traced for this sample (primary, continuation and shadow rays).
    pub rays: u64,
    pub visibility: VisibilityStats,
    /// Time spent inside the tracer.
    pub trace_time: Duration,
}

/// Everything fixed for a render of one scene from one camera.
#[derive(Debug)]
pub struct Renderer<'s> {
    pub scene: &'s Scene,
    pub settings: Settings,
    pub camera: Camera,
    pub fetcher: Fetcher<'s>,
    pub lights: Lights,
    /// Radiance of rays leaving the scene: white (1) when the scene has no
    /// emitters and no punctual lights, so that it is lit at all; else black.
    pub environment: Vec3,
    /// Offset of secondary ray origins along the geometric normal:
    /// 2^-16 of the scene's largest absolute coordinate.
    pub offset: f32,
    pub ao_radius: f32,
    pub raster: Raster,
}

struct Counters {
    rays: u64,
    trace_time: Duration,
    visibility: VisibilityStats,
}

impl Counters {
    async fn trace<T: AsyncTrace + ?Sized>(
        &mut self,
        tracer: &mut T,
        rays: &[Ray],
    ) -> Result<Vec<Hit>, RenderError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let t = Instant::now();
        let hits = tracer.trace_rays(rays).await?;
        self.trace_time += t.elapsed();
        self.rays += rays.len() as u64;
        if hits.len() != rays.len() {
            return Err(RenderError::HitCount {
                expected: rays.len(),
                got: hits.len(),
            });
        }
        Ok(hits)
    }
}

impl<'s> Renderer<'s> {
    pub fn new(scene: &'s Scene, camera: Camera, settings: Settings) -> Result<Self, RenderError> {
        settings.validate()?;
        if scene.is_empty() {
            return Err(RenderError::EmptyScene);
        }
        scene.validate().map_err(RenderError::BadScene)?;
        let lights = Lights::new(scene);
        let environment = if lights.is_empty() {
            Vec3::ONE
        } else {
            Vec3::ZERO
        };
        let b = scene.bounds();
        let scale = b.min.abs().max(b.max.abs()).max_element();
        let offset = scale * (1.0 / 65536.0);
        let ao_radius = settings
            .ao_radius
            .unwrap_or_else(|| (b.extent().length() * 0.25).max(f32::MIN_POSITIVE));
        let raster = direct_visibility::rasterize(
            &scene.triangles,
            &camera,
            settings.width,
            settings.height,
        );
        Ok(Self {
            scene,
            settings,
            camera,
            fetcher: if settings.mode == Mode::Ao {
                Fetcher::geometry(scene)
            } else {
                Fetcher::new(scene)
            },
            lights,
            environment,
            offset,
            ao_radius,
            raster,
        })
    }

    /// Renders all samples, calling `progress` after each.
    pub fn render(
        &self,
        tracer: &mut dyn Tracer,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Rendered, RenderError> {
        let start = Instant::now();
        let s = &self.settings;
        let n = s.width as usize * s.height as usize;
        let mut sum = vec![Vec3::ZERO; n];
        let mut counters = Counters {
            rays: 0,
            trace_time: Duration::ZERO,
            visibility: VisibilityStats::default(),
        };
        for sample in 0..s.spp {
            let radiance = now(self.sample(&mut Blocking(tracer), sample, &mut counters))?;
            sum.par_iter_mut()
                .zip(&radiance)
                .for_each(|(acc, r)| *acc += *r);
            progress(&Progress {
                samples_done: sample + 1,
                spp: s.spp,
                rays: counters.rays,
                elapsed: start.elapsed(),
            });
        }
        let inv = 1.0 / s.spp as f32;
        let image = Image {
            width: s.width,
            height: s.height,
            pixels: sum.iter().map(|v| (*v * inv).to_array()).collect(),
        };
        Ok(Rendered {
            image,
            rays: counters.rays,
            visibility: counters.visibility,
            trace_time: counters.trace_time,
            elapsed: start.elapsed(),
            tracer: tracer.name(),
        })
    }

    /// Sample number `sample` of every pixel alone, with the random numbers
    /// [`Renderer::render`] uses for it: the passes `0..n` added up in order
    /// and scaled by `1 / n` (as `f32`) give the image of an `n`-spp render,
    /// bit for bit. [`Settings::spp`] is not read.
    pub fn render_sample(
        &self,
        tracer: &mut dyn Tracer,
        sample: u32,
    ) -> Result<SamplePass, RenderError> {
        now(self.render_sample_async(&mut Blocking(tracer), sample))
    }

    /// [`Renderer::render_sample`] through a tracer whose hits come later
    /// (a browser page's GPU): the same passes, bit for bit, awaited.
    pub async fn render_sample_async<T: AsyncTrace + ?Sized>(
        &self,
        tracer: &mut T,
        sample: u32,
    ) -> Result<SamplePass, RenderError> {
        let mut counters = Counters {
            rays: 0,
            trace_time: Duration::ZERO,
            visibility: VisibilityStats::default(),
        };
        let radiance = self.sample(tracer, sample, &mut counters).await?;
        Ok(SamplePass {
            radiance,
            rays: counters.rays,
            visibility: counters.visibility,
            trace_time: counters.trace_time,
        })
    }

    /// The primary rays of one sample (pixel index order), jittered in the pixel.
    pub fn primary_rays(&self, sample: u32) -> Vec<Ray> {
        let (w, h) = (self.settings.width, self.settings.height);
        (0..w * h)
            .into_par_iter()
            .map(|i| {
                let s = Sampler::new(self.settings.seed, i, sample);
                let x = (i % w) as f32 + s.get(0, dim::PIXEL_X);
                let y = (i / w) as f32 + s.get(0, dim::PIXEL_Y);
                self.camera.ray(x, y, w, h)
            })
            .collect()
    }

    fn fetch_all(&self, rays: &[Ray], hits: &[Hit]) -> Vec<Option<SurfacePoint>> {
        rays.par_iter()
            .zip(hits)
            .map(|(r, h)| self.fetcher.fetch(r, h))
            .collect()
    }

    /// The radiance of every pixel for one sample.
    async fn sample<T: AsyncTrace + ?Sized>(
        &self,
        tracer: &mut T,
        sample: u32,
        counters: &mut Counters,
    ) -> Result<Vec<Vec3>, RenderError> {
        let s = &self.settings;
        let rays = self.primary_rays(sample);
        let pixels: Vec<usize> = (0..rays.len()).collect();
        let t = Instant::now();
        let proposed =
            direct_visibility::Proposed::new(&self.scene.triangles, &self.raster, &rays, &pixels);
        let traced = tracer.trace_rays(&proposed.limited).await?;
        let (hits, vis) = proposed.settle(traced)?;
        counters.trace_time += t.elapsed();
        counters.rays += rays.len() as u64;
        counters.visibility.confirmed += vis.confirmed;
        counters.visibility.fallback += vis.fallback;
        let primary = self.fetch_all(&rays, &hits);

        if s.mode == Mode::Ao {
            return self
                .ambient_occlusion(tracer, sample, &primary, counters)
                .await;
        }

        let eye: Vec<Vec3> = rays.iter().map(|r| r.origin()).collect();
        let mut buf = ShadingBuffer::new(eye, primary);
        let (bounces, roulette_from) = match s.mode {
            Mode::Direct => (1, None),
            _ => (s.bounces, s.russian_roulette),
        };
        let ctx = ShadeContext {
            scene: self.scene,
            lights: &self.lights,
            environment: self.environment,
            offset: self.offset,
            seed: s.seed,
            sample,
            roulette_from,
        };
        ctx.primary(&mut buf);
        for bounce in 1..=bounces {
            // Next-event estimation at G(k).
            let (shadow_rays, shadows) = ctx.next_event(&buf, bounce);
            let shadow_hits = counters.trace(tracer, &shadow_rays).await?;
            ctx.apply_shadows(&mut buf, &shadows, &shadow_hits);
            // The ray from G(k) to G(k+1).
            let (rays, owner) = ctx.sample_scatter(&mut buf, bounce);
            if rays.is_empty() {
                break;
            }
            let hits = counters.trace(tracer, &rays).await?;
            let fetched = self.fetch_all(&rays, &hits);
            for (i, sp) in owner.iter().zip(fetched) {
                buf.next[*i] = sp;
            }
            ctx.scatter(&mut buf, bounce);
            shift::shift(&mut buf);
        }
        Ok(buf.paths.iter().map(|p| p.radiance).collect())
    }

    /// One cosine-distributed occlusion ray per primary hit, `ao_radius` long:
    /// 1 when it hits nothing, else 0. Pixels whose primary ray misses get 1.
    async fn ambient_occlusion<T: AsyncTrace + ?Sized>(
        &self,
        tracer: &mut T,
        sample: u32,
        primary: &[Option<SurfacePoint>],
        counters: &mut Counters,
    ) -> Result<Vec<Vec3>, RenderError> {
        let mut owner = Vec::new();
        let mut rays = Vec::new();
        for (i, sp) in primary.iter().enumerate() {
            if let Some(sp) = sp {
                let s = Sampler::new(self.settings.seed, i as u32, sample);
                let d =
                    crate::bsdf::cosine_sample(sp.ns, s.get(1, dim::DIR_U), s.get(1, dim::DIR_V));
                if d.dot(sp.ng) > 0.0 {
                    rays.push(Ray::new(
                        offset_origin(sp, self.offset),
                        d,
                        0.0,
                        self.ao_radius,
                    ));
                    owner.push(i);
                }
            }
        }
        let hits = counters.trace(tracer, &rays).await?;
        let mut out: Vec<Vec3> = primary
            .iter()
            .map(|sp| if sp.is_some() { Vec3::ZERO } else { Vec3::ONE })
            .collect();
        for (i, h) in owner.iter().zip(&hits) {
            if !h.is_hit() {
                out[*i] = Vec3::ONE;
            }
        }
        Ok(out)
    }
}
