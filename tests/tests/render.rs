//! The renderer across crates: the obvhs reference tracer equals brute force
//! on adversarial rays, and a render traced on the GPU (lavapipe) equals the
//! same render traced on the CPU, hit for hit on every bounce and bit for bit
//! in every pixel (shading runs on the host for both, with the same code).

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_gpu::testing::exact_gpu;
use dirt_gpu::{DirtGpu, GpuAds};
use dirt_math::{Triangle, Vec3};
use dirt_render::reference::Reference;
use dirt_render::trace::Recording;
use dirt_render::{Camera, Mode, Renderer, Settings};
use dirt_tests::{Rng, adversarial_rays};

fn soup(seed: u64, n: usize) -> Vec<Triangle> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let c = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            Triangle::new(
                c + rng.dir() * 0.3,
                c + rng.dir() * 0.3,
                c + rng.dir() * 0.3,
            )
        })
        .collect()
}

#[test]
fn reference_equals_brute_force_on_adversarial_rays() {
    let mut scenes: Vec<(String, Vec<Triangle>)> = ["cornell", "spheres", "layers"]
        .iter()
        .map(|n| {
            (
                n.to_string(),
                dirt_scene::open(n).expect("built-in").triangles,
            )
        })
        .collect();
    scenes.push(("soup".into(), soup(3, 400)));
    // Far from the origin: the dilation must scale with the coordinates.
    let far: Vec<Triangle> = soup(4, 200)
        .iter()
        .map(|t| {
            let o = Vec3::new(1e4, -3e3, 5e3);
            Triangle::new(t.vertex(0) + o, t.vertex(1) + o, t.vertex(2) + o)
        })
        .collect();
    scenes.push(("far soup".into(), far));
    for (name, tris) in &scenes {
        let rays = adversarial_rays(tris, 300, 11);
        let reference = Reference::new(tris).trace(&rays).expect("reference trace");
        let truth = dirt_cpu::brute_force::trace(tris, &rays);
        let bad: Vec<usize> = (0..rays.len())
            .filter(|&i| reference[i].bits() != truth[i].bits())
            .collect();
        assert!(
            bad.is_empty(),
            "{name}: {} of {} rays differ, first {:?}: {:?} vs {:?}",
            bad.len(),
            rays.len(),
            bad.first().map(|&i| rays[i]),
            bad.first().map(|&i| reference[i]),
            bad.first().map(|&i| truth[i])
        );
        let hits = truth.iter().filter(|h| h.is_hit()).count();
        assert!(hits > rays.len() / 10, "{name}: only {hits} hits");
    }
}

/// Path tracing at 3 bounces, the rest as by default.
fn path_traced(width: u32, height: u32, spp: u32, seed: u64) -> Settings {
    Settings {
        width,
        height,
        spp,
        bounces: 3,
        mode: Mode::Pt,
        seed,
        ..Settings::default()
    }
}

#[test]
fn gpu_render_equals_cpu_render_hit_for_hit_and_bit_for_bit() {
    let Some(g) = exact_gpu("gpu_render_equals_cpu_render_hit_for_hit_and_bit_for_bit") else {
        return;
    };
    let scene = dirt_scene::open("cornell").expect("cornell");
    let s = path_traced(24, 24, 2, 5);
    let camera = Camera::for_scene(&scene, 1.0).expect("camera");
    let renderer = Renderer::new(&scene, camera, s).expect("renderer");
    let params = AdsParams::default();
    let mut cpu = Recording::new(
        DirtCpu::built(&scene.triangles, &params, Traversal::Linear).expect("cpu build"),
    );
    let gpu_ads = GpuAds::build(g, &scene.triangles, &params).expect("gpu build");
    let mut gpu_tracer = Recording::new(DirtGpu::from_ads(g, gpu_ads, Traversal::Linear));
    let a = renderer.render(&mut cpu, &mut |_| {}).expect("cpu render");
    let b = renderer
        .render(&mut gpu_tracer, &mut |_| {})
        .expect("gpu render");
    assert_eq!(cpu.calls.len(), gpu_tracer.calls.len(), "trace calls");
    let mut rays = 0;
    for (k, ((ra, ha), (rb, hb))) in cpu.calls.iter().zip(&gpu_tracer.calls).enumerate() {
        assert_eq!(ra.len(), rb.len(), "call {k}: ray count");
        for i in 0..ra.len() {
            assert_eq!(
                bytemuck::bytes_of(&ra[i]),
                bytemuck::bytes_of(&rb[i]),
                "call {k}: ray {i}"
            );
            assert_eq!(ha[i].bits(), hb[i].bits(), "call {k}: hit of ray {i}");
        }
        rays += ra.len();
    }
    assert!(rays > 24 * 24 * 2 * 3, "only {rays} rays");
    assert_eq!(a.image.bits(), b.image.bits(), "images differ");
    assert!(a.image.pixels.iter().flatten().any(|&c| c > 0.0));
    eprintln!(
        "{} trace calls, {rays} rays; {} continuation rounds on the GPU",
        cpu.calls.len(),
        gpu_tracer.inner.rounds
    );
    let _ = gpu_tracer.inner.name();
}

/// The image shaded on the GPU (`dirt_render::gpu`) against the CPU
/// renderer's at equal samples, by RMSE (linear radiance) and FLIP (the
/// tone-mapped images, `dirt_eval::renders::flip`): shading on the GPU uses
/// its own `sqrt`, `sin` and division, so the bound is relative to what a
/// change of seed alone gives (the noise at these samples).
#[test]
fn gpu_shaded_image_matches_the_cpu_renderer_by_rmse_and_flip() {
    let Some(g) =
        dirt_gpu::testing::any_gpu("gpu_shaded_image_matches_the_cpu_renderer_by_rmse_and_flip")
    else {
        return;
    };
    let scene = dirt_scene::open("cornell").expect("cornell");
    let s = path_traced(48, 36, 8, 3);
    let camera = Camera::for_scene(&scene, 48.0 / 36.0).expect("camera");
    let params = AdsParams::default();
    let mut cpu = DirtCpu::built(&scene.triangles, &params, Traversal::Linear).expect("cpu build");
    let render_cpu = |s: Settings, cpu: &mut DirtCpu| {
        Renderer::new(&scene, camera, s)
            .expect("renderer")
            .render(cpu, &mut |_| {})
            .expect("cpu render")
            .image
    };
    let on_cpu = render_cpu(s, &mut cpu);
    let other_seed = render_cpu(Settings { seed: 4, ..s }, &mut cpu);
    let renderer = Renderer::new(&scene, camera, s).expect("renderer");
    let ads = GpuAds::build(g, &scene.triangles, &params).expect("gpu build");
    let on_gpu = dirt_render::gpu::GpuRenderer::new(g, &renderer)
        .expect("GPU renderer")
        .render(&ads, Traversal::Linear, &mut |_| {})
        .expect("GPU render")
        .image;
    let rmse = dirt_render::metrics::rmse;
    let flip = dirt_eval::renders::flip;
    let (e_rmse, e_flip) = (
        rmse(&on_gpu, &on_cpu).expect("size"),
        flip(&on_cpu, &on_gpu).expect("size"),
    );
    let (n_rmse, n_flip) = (
        rmse(&other_seed, &on_cpu).expect("size"),
        flip(&on_cpu, &other_seed).expect("size"),
    );
    eprintln!(
        "GPU vs CPU renderer at {} spp: RMSE {e_rmse:.5}, FLIP {e_flip:.5}; another seed: RMSE {n_rmse:.5}, FLIP {n_flip:.5}",
        s.spp
    );
    assert!(
        n_rmse > 0.0 && n_flip > 0.0,
        "the seeds gave the same image"
    );
    assert!(
        e_rmse < 0.1 * n_rmse,
        "RMSE {e_rmse} against noise {n_rmse}"
    );
    assert!(
        e_flip < 0.1 * n_flip,
        "FLIP {e_flip} against noise {n_flip}"
    );
}
