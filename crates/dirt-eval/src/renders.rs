//! Image error of `dirt-render` path tracing against a converged reference:
//! RMSE (linear radiance) and FLIP (`nv-flip`, on the tone-mapped sRGB
//! images) as samples accumulate, against wall time, for DIRT on the CPU,
//! the renderer's obvhs BVH reference tracer and the approximate methods
//! ([`crate::approx`]). The renderer confirms primary hits with the exact
//! triangle test (`direct_visibility`), so an approximate tracer's error
//! shows in the bounces and shadow rays, as it would in a deferred renderer.
//!
//! The renderer's random numbers are a pure function of (seed, pixel,
//! sample, ...), so a render of `k` samples is exactly the first `k` samples
//! of a longer one; each point of the curve is its own render, timed. The
//! converged reference uses another seed and many more samples, so its noise
//! is independent of the test images' (and sets the curve's floor).

use std::time::Instant;

use dirt_core::Tracer;
use dirt_cpu::DirtCpu;
use dirt_cpu::screen_space::ScreenSpace;
use dirt_render::output::Image;
use dirt_render::reference::Reference;
use dirt_render::{Camera, Renderer, Settings};
use serde::Serialize;

use crate::EvalError;
use crate::approx::ApproxPoint;
use crate::measure::ms;

/// What to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderConfig {
    /// A built-in scene name or a glTF/OBJ path.
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub bounces: u32,
    /// Samples per pixel of the converged reference.
    pub reference_spp: u32,
    /// Sample counts of the curve.
    pub spp: Vec<u32>,
    /// Approximate methods rendered beside the exact tracers (the single
    /// layer looks from the render's camera).
    pub approx: Vec<ApproxPoint>,
}

/// The render's row of DIRT, the library's default (`DirtCpu::auto`).
pub const DIRT_TRACER: &str = "dirt-cpu (the cost model's choice)";

/// The render's row of the renderer's own BVH, which made the reference.
pub const REFERENCE_TRACER: &str = "obvhs bvh2 (renderer reference)";

/// One render.
#[derive(Clone, Debug, Serialize)]
pub struct RenderRow {
    pub scene: String,
    pub tracer: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Wall time of the whole render (structure build included for DIRT).
    pub wall_ms: f64,
    /// Time inside the tracer.
    pub trace_ms: f64,
    pub rays: u64,
    pub rmse: f64,
    /// Mean FLIP error (0 = identical to the reference as seen).
    pub flip: f64,
    /// Whether the tracer promises brute force's hits.
    pub exact: bool,
    /// Whether the image equals, bit for bit, the reference tracer's image of
    /// the same samples (an exact tracer's must).
    pub same_bits_as_reference_tracer: bool,
}

/// The converged reference of a run, for the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RenderReference {
    pub scene: String,
    pub spp: u32,
    pub wall_ms: f64,
}

fn render_err(e: impl std::fmt::Display) -> EvalError {
    EvalError::Render(e.to_string())
}

/// Mean FLIP of `test` against `reference`, both tone-mapped as the renderer
/// writes PNGs (exposure 0 stops).
pub fn flip(reference: &Image, test: &Image) -> Result<f64, EvalError> {
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(EvalError::Render(format!(
            "FLIP needs images of one size, got {}x{} and {}x{}",
            reference.width, reference.height, test.width, test.height
        )));
    }
    let r = nv_flip::FlipImageRgb8::with_data(
        reference.width,
        reference.height,
        &reference.to_srgb8(0.0),
    );
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.to_srgb8(0.0));
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(f64::from(nv_flip::FlipPool::from_image(&err).mean()))
}

/// Renders the reference and the curves. Returns the rows, the reference and
/// the converged reference image.
pub fn run(cfg: &RenderConfig) -> Result<(Vec<RenderRow>, RenderReference, Image), EvalError> {
    if cfg.spp.is_empty() || cfg.spp.contains(&0) || cfg.reference_spp == 0 {
        return Err(EvalError::Config(
            "render sample counts must be at least 1".into(),
        ));
    }
    let scene = dirt_scene::open(&cfg.scene).map_err(|source| EvalError::Scene {
        spec: cfg.scene.clone(),
        source,
    })?;
    // The scene's first camera, else a view of the bounds from the front.
    let camera = match scene.cameras.first() {
        Some(c) => Camera::look_at(
            c.position,
            c.position + c.forward,
            c.yfov_radians.to_degrees(),
        ),
        None => {
            let b = scene.bounds();
            let eye = b.center() + dirt_math::Vec3::new(0.0, 0.2, 1.6) * b.extent().length();
            Camera::look_at(eye, b.center(), 45.0)
        }
    }
    .map_err(render_err)?;
    let settings = |spp: u32, seed: u64| Settings {
        width: cfg.width,
        height: cfg.height,
        spp,
        bounces: cfg.bounces,
        seed,
        ..Settings::default()
    };
    let start = Instant::now();
    let renderer =
        Renderer::new(&scene, camera, settings(cfg.reference_spp, 0x5eed)).map_err(render_err)?;
    let mut reference_tracer = Reference::new(&scene.triangles);
    let reference = renderer
        .render(&mut reference_tracer, &mut |_| {})
        .map_err(render_err)?
        .image;
    let reference_info = RenderReference {
        scene: scene.name.clone(),
        spp: cfg.reference_spp,
        wall_ms: ms(start.elapsed()),
    };

    let mut rows = Vec::new();
    // The tracers of the curve: 0 DIRT, 1 the renderer's reference, then the approximate ones.
    let approx: Vec<(String, dirt_cpu::screen_space::ScreenSpaceParams)> = cfg
        .approx
        .iter()
        .filter_map(|p| {
            let params = p.params(Some(camera.eye))?;
            Some((format!("{} {}", p.method.name(), p.setting().label), params))
        })
        .collect();
    for &spp in &cfg.spp {
        let run_settings = settings(spp, 1);
        let renderer = Renderer::new(&scene, camera, run_settings).map_err(render_err)?;
        let first = rows.len();
        let mut images = Vec::new();
        for which in 0..2 + approx.len() {
            let start = Instant::now();
            let (name, mut tracer): (String, Box<dyn Tracer>) = match which {
                // The library's default: the cost model chooses for this render's
                // rays (an upper bound), inside the wall time. One name for every
                // spp (the plot draws a line per tracer); the choice, which may
                // differ per spp, is in the notes' tracer names.
                0 => {
                    let mut dirt = DirtCpu::auto(None, run_settings.max_rays());
                    dirt.build(&scene.triangles).map_err(render_err)?;
                    (DIRT_TRACER.into(), Box::new(dirt))
                }
                1 => (
                    REFERENCE_TRACER.into(),
                    Box::new(Reference::new(&scene.triangles)),
                ),
                k => {
                    let (name, params) = &approx[k - 2];
                    let mut t = ScreenSpace::new(*params).map_err(render_err)?;
                    t.build(&scene.triangles).map_err(render_err)?;
                    (name.clone(), Box::new(t))
                }
            };
            let r = renderer
                .render(&mut tracer, &mut |_| {})
                .map_err(render_err)?;
            let wall_ms = ms(start.elapsed());
            let rmse = dirt_render::metrics::rmse(&reference, &r.image).map_err(render_err)?;
            let flip = flip(&reference, &r.image)?;
            rows.push(RenderRow {
                scene: scene.name.clone(),
                tracer: name,
                width: cfg.width,
                height: cfg.height,
                spp,
                wall_ms,
                trace_ms: ms(r.trace_time),
                rays: r.rays,
                rmse,
                flip,
                exact: which < 2,
                same_bits_as_reference_tracer: false,
            });
            images.push(r.image);
        }
        for (row, image) in rows[first..].iter_mut().zip(&images) {
            row.same_bits_as_reference_tracer = image.bits() == images[1].bits();
        }
    }
    Ok((rows, reference_info, reference))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_difference() {
        let mut a = Image::new(16, 16);
        for (i, p) in a.pixels.iter_mut().enumerate() {
            *p = [(i % 7) as f32 * 0.1, 0.3, (i % 5) as f32 * 0.2];
        }
        assert_eq!(flip(&a, &a).expect("same size"), 0.0);
        let mut b = a.clone();
        for p in b.pixels.iter_mut().step_by(3) {
            *p = [1.0, 0.0, 1.0];
        }
        let f = flip(&a, &b).expect("same size");
        assert!(f > 0.01 && f <= 1.0, "{f}");
        assert!(flip(&a, &Image::new(8, 8)).is_err());
    }

    #[test]
    fn more_samples_get_closer_and_tracers_agree() {
        let cfg = RenderConfig {
            scene: "cornell".into(),
            width: 24,
            height: 18,
            bounces: 2,
            reference_spp: 32,
            spp: vec![1, 8],
            approx: vec![crate::approx::MMRT_DEFAULT],
        };
        let (rows, reference, _) = run(&cfg).expect("render");
        assert_eq!(rows.len(), 6);
        assert_eq!(reference.spp, 32);
        assert!(
            rows.iter()
                .filter(|r| r.exact)
                .all(|r| r.same_bits_as_reference_tracer)
        );
        // The approximate tracer renders, and its image is not the exact one.
        let mmrt: Vec<&RenderRow> = rows.iter().filter(|r| !r.exact).collect();
        assert_eq!(mmrt.len(), 2);
        assert!(mmrt[0].tracer.starts_with("mmrt"));
        assert!(mmrt.iter().all(|r| r.rmse.is_finite() && r.rays > 0));
        let dirt: Vec<&RenderRow> = rows
            .iter()
            .filter(|r| r.tracer.starts_with("dirt"))
            .collect();
        assert!(
            dirt[1].rmse < dirt[0].rmse,
            "{} !< {}",
            dirt[1].rmse,
            dirt[0].rmse
        );
    }
}
