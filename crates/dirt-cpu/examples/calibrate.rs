//! Measures build and trace times over scenes and parameters (every view
//! kind) and fits the weights of `dirt_cpu::cost::CostModel` (printed as
//! Rust, ready to paste into `CostModel::CALIBRATED`), then prints how well
//! the fitted model and the one in use rank the measurements. Run in release:
//!
//! ```text
//! cargo run --release -p dirt-cpu --example calibrate
//! ```
//!
//! Rays: origins uniform in the scene bounds, directions uniform on the
//! sphere (a fixed seed), 20 000 per setting; each time is the best of three
//! (builds over a second: one).

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::cost::{CostModel, Counts, rank_correlation};
use dirt_cpu::{Ads, trace};
use dirt_math::{Aabb, Ray, Vec3};
use std::time::Instant;

fn rays(b: &Aabb, n: usize, mut s: u64) -> Vec<Ray> {
    let mut next = move || {
        // splitmix64
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let o = b.min + (b.max - b.min) * Vec3::new(next(), next(), next());
            let d = loop {
                let d = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
                let l = d.length();
                if l > 0.05 && l <= 1.0 {
                    break d / l;
                }
            };
            Ray::new(o, d, 0.0, f32::INFINITY)
        })
        .collect()
}

fn best_of_3(mut f: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut builds = Vec::new();
    let mut traces = Vec::new();
    // (counts, build ms, trace ns per ray) of every (scene, setting, traversal).
    let mut frames = Vec::new();
    println!(
        "scene,views,resolution,buckets,tile,traversal,build_ms,ray_ns,nodes,lists,tiles,buckets_visited,tests"
    );
    for name in ["cornell", "foliage", "layers", "spheres"] {
        let scene = dirt_scene::builtin(name).ok_or("unknown built-in scene")?;
        let tris = &scene.triangles;
        let sample = rays(&scene.bounds(), 20_000, 7);
        for views in ViewsKind::ALL {
            for resolution in [32, 64, 128, 256] {
                for buckets in [1, 4, 8, 16, 32] {
                    let tile = 1;
                    let p = AdsParams {
                        views,
                        resolution,
                        buckets,
                        tile,
                        ..AdsParams::default()
                    };
                    let mut build_ms = f64::INFINITY;
                    let mut ads = None;
                    // Best of three, or of one for builds over a second (rounding matters less there).
                    for _ in 0..3 {
                        let a = Ads::build(tris, &p)?;
                        build_ms = build_ms.min(a.timings.total().as_secs_f64() * 1e3);
                        ads = Some(a);
                        if build_ms > 1000.0 {
                            break;
                        }
                    }
                    let Some(ads) = ads else { continue };
                    for trav in [Traversal::Linear, Traversal::HiZ] {
                        let c = Counts::measure(&ads, tris, &sample, trav);
                        let secs = best_of_3(|| {
                            std::hint::black_box(trace(&ads, tris, &sample, trav));
                        });
                        let ray_ns = secs * 1e9 / sample.len() as f64;
                        println!(
                            "{name},{views},{resolution},{buckets},{tile},{trav:?},{build_ms:.3},{ray_ns:.1},{},{},{:.2},{:.2},{:.2}",
                            c.nodes, c.lists, c.tiles_per_ray, c.buckets_per_ray, c.tests_per_ray
                        );
                        traces.push((c, ray_ns));
                        if trav == Traversal::Linear {
                            builds.push((c, build_ms));
                        }
                        frames.push((c, build_ms, ray_ns));
                    }
                }
            }
        }
    }
    let m =
        CostModel::fit(&builds, &traces).ok_or("the measurements do not determine the model")?;
    let (t, b) = m.median_relative_error(&builds, &traces);
    println!("\n{m:#?}");
    println!(
        "median relative error of the fitted model: trace {:.0}%, build {:.0}% ({} traces, {} builds)",
        t * 100.0,
        b * 100.0,
        traces.len(),
        builds.len()
    );
    // How well a model ranks: Spearman's rank correlation between predicted
    // and measured cost, per part and for whole frames of a few ray counts;
    // for the fitted model and for the one in use (`CostModel::CALIBRATED`).
    let rho = |pred: Vec<f64>, meas: Vec<f64>| {
        rank_correlation(&pred, &meas).map_or("undefined".to_string(), |r| format!("{r:.3}"))
    };
    for (label, m) in [("fitted", m), ("in use", CostModel::CALIBRATED)] {
        println!(
            "rank correlation ({label}), predicted vs measured: trace per ray {}, build {}",
            rho(
                traces.iter().map(|(c, _)| m.ray_ns(c)).collect(),
                traces.iter().map(|(_, ns)| *ns).collect()
            ),
            rho(
                builds.iter().map(|(c, _)| m.build_ms(c)).collect(),
                builds.iter().map(|(_, ms)| *ms).collect()
            )
        );
        for rays in [5_000u64, 100_000, 1_000_000] {
            println!(
                "rank correlation ({label}), predicted vs measured frame of {rays} rays: {}",
                rho(
                    frames.iter().map(|(c, _, _)| m.frame_ms(c, rays)).collect(),
                    frames
                        .iter()
                        .map(|(_, b, ns)| b + ns * rays as f64 * 1e-6)
                        .collect()
                )
            );
        }
    }
    Ok(())
}
