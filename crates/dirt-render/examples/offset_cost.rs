//! What moving secondary ray origins off their surface costs, measured.
//!
//! The renderer starts every secondary ray at `p + offset · n_g` (see
//! `Renderer::offset`) so that it cannot hit its own triangle by rounding.
//! The exact answer is the ray from `p` itself that skips only the triangle
//! it starts on. This example samples the BSDF at the primary hits of a
//! render (and at the hits of those rays: two bounces), traces both rays by
//! brute force and counts the rays whose closest primitive differs.
//!
//! `cargo run --release -p dirt-render --example offset_cost [SCENE...]`

use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::{Hit, Ray, Triangle};
use dirt_render::bsdf::Bsdf;
use dirt_render::fetch::SurfacePoint;
use dirt_render::rng::{Sampler, dim};
use dirt_render::shade::offset_origin;
use dirt_render::{Camera, Renderer, Settings};
use rayon::prelude::*;

/// A surface point and the point the ray to it came from.
type Vertex = (SurfacePoint, [f32; 3]);

/// Brute force, leaving out primitive `skip`.
fn closest_skipping(tris: &[Triangle], ray: &Ray, skip: u32) -> Hit {
    let sh = RayShear::new(ray);
    let mut best = Hit::MISS;
    for (i, t) in tris.iter().enumerate() {
        if i as u32 != skip {
            intersect_closest(ray, &sh, t, i as u32, &mut best);
        }
    }
    best
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scenes = if args.is_empty() {
        vec!["cornell".to_string(), "spheres".to_string()]
    } else {
        args
    };
    for spec in scenes {
        let scene = match dirt_scene::open(&spec) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{spec}: {e}");
                continue;
            }
        };
        let s = Settings {
            width: 64,
            height: 48,
            spp: 1,
            ..Settings::default()
        };
        let Ok(camera) = Camera::for_scene(&scene, 4.0 / 3.0) else {
            continue;
        };
        let Ok(r) = Renderer::new(&scene, camera, s) else {
            continue;
        };
        let tris = &scene.triangles;
        let rays = r.primary_rays(0);
        let hits = dirt_cpu::brute_force::trace(tris, &rays);
        let mut points: Vec<Vertex> = rays
            .iter()
            .zip(&hits)
            .filter_map(|(ray, h)| r.fetcher.fetch(ray, h).map(|sp| (sp, ray.origin)))
            .collect();
        let (mut total, mut differ, mut self_hits) = (0usize, 0usize, 0usize);
        for bounce in 1..=2u32 {
            let results: Vec<(bool, bool, Option<Vertex>)> = points
                .par_iter()
                .enumerate()
                .filter_map(|(i, (sp, from))| {
                    let wo = (glam::Vec3::from_array(*from) - sp.p).normalize_or_zero();
                    let smp = Sampler::new(99, i as u32, 0);
                    let b = Bsdf::of(sp).sample(
                        sp.ns,
                        sp.ng,
                        wo,
                        smp.get(bounce, dim::LOBE),
                        smp.get(bounce, dim::DIR_U),
                        smp.get(bounce, dim::DIR_V),
                    )?;
                    let offset = Ray::new(offset_origin(sp, r.offset), b.wi, 0.0, f32::INFINITY);
                    let exact = Ray::new(sp.p, b.wi, 0.0, f32::INFINITY);
                    let h_off = dirt_cpu::brute_force::trace_ray(tris, &offset);
                    let h_exact = closest_skipping(tris, &exact, sp.prim);
                    let h_self = dirt_cpu::brute_force::trace_ray(tris, &exact);
                    let next = r
                        .fetcher
                        .fetch(&exact, &h_exact)
                        .map(|n| (n, sp.p.to_array()));
                    Some((h_off.prim != h_exact.prim, h_self.prim == sp.prim, next))
                })
                .collect();
            total += results.len();
            differ += results.iter().filter(|x| x.0).count();
            self_hits += results.iter().filter(|x| x.1).count();
            points = results.into_iter().filter_map(|x| x.2).collect();
        }
        println!(
            "{}: offset {:e} (2^-16 of the largest coordinate): {differ} of {total} secondary rays ({:.4} %) hit another primitive than the exact ray from the surface point that skips its own triangle; without offset and without skipping, {self_hits} ({:.2} %) would hit their own triangle",
            scene.name,
            r.offset,
            100.0 * differ as f64 / total.max(1) as f64,
            100.0 * self_hits as f64 / total.max(1) as f64,
        );
    }
}
