//! In a real browser (`wasm-bindgen-test-runner` driving headless Chromium,
//! `scripts/web-test`): DIRT built and traced on the page's WebGPU against
//! the CPU reference compiled into the same page, and the page's renderer.

#![cfg(target_arch = "wasm32")]

use dirt_core::{AdsParams, Traversal};
use dirt_web::{check, probe_rays};
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// The CPU reference in the page (wasm, one thread) equals brute force, bit for bit.
#[wasm_bindgen_test]
fn the_cpu_reference_in_the_page_is_exact() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let rays = probe_rays(&scene.triangles, 2000, 3);
    let truth = dirt_cpu::brute_force::trace(&scene.triangles, &rays);
    for params in [
        AdsParams::default(),
        AdsParams {
            resolution: 32,
            buckets: 4,
            ..AdsParams::default()
        },
    ] {
        let ads = dirt_cpu::Ads::build(&scene.triangles, &params).expect("build");
        for traversal in [Traversal::Linear, Traversal::HiZ] {
            let hits = dirt_cpu::trace(&ads, &scene.triangles, &rays, traversal);
            let d = dirt_web::compare::hits(&hits, &truth, None);
            assert!(d.is_empty(), "{traversal}: {d:?}");
        }
    }
}

/// The portable path: WGSL compiled by the browser (Tint) for its device
/// (SwiftShader in headless Chromium), no NoContraction. Every frame build
/// and trace is compared with the CPU reference in the same page: structure
/// (views, every Hi-Z cell, every list) and hits (prim, `t`, `u`, `v` bits,
/// statistics), and both against brute force. Measured on Chromium 156 /
/// SwiftShader, both walks on both scenes: nothing differs (12 000 rays, 8
/// structures). This run keeps cornell's 4; any difference fails it, with
/// its first instance in words.
#[wasm_bindgen_test]
async fn webgpu_against_the_cpu_reference() {
    let t0 = web_time::Instant::now();
    let gpu = dirt_web::bind::page_gpu().await.expect("the page's WebGPU");
    console_log!("device and pipelines: {:?}", t0.elapsed());
    console_log!("adapter: {} — {}", gpu.describe(), gpu.exactness);
    // Every setting asserts its own; the total says how much was compared.
    let (mut settings, mut compared) = (0, 0);
    // Spheres passed too when measured (above); CI keeps cornell, for time.
    let name = "cornell";
    let scene = dirt_scene::open(name).expect("scene");
    let rays = probe_rays(&scene.triangles, 1500, 11);
    for params in dirt_web::check_params() {
        for traversal in [Traversal::Linear, Traversal::HiZ] {
            let t0 = web_time::Instant::now();
            let c = check(gpu, &scene.triangles, &rays, &params, traversal)
                .await
                .expect("check");
            console_log!(
                "{name} {:?} r{} B{} {traversal} ({:?}): {}",
                params.views,
                params.resolution,
                params.buckets,
                t0.elapsed(),
                c.summary()
            );
            assert!(
                c.cpu_truth.is_empty(),
                "the CPU reference: {:?}",
                c.cpu_truth
            );
            assert!(c.structure.is_empty(), "structure: {:?}", c.structure);
            assert!(c.gpu_cpu.is_empty(), "hits: {:?}", c.gpu_cpu);
            assert!(c.gpu_truth.is_empty(), "brute force: {:?}", c.gpu_truth);
            settings += 1;
            compared += c.gpu_cpu.rays;
        }
    }
    console_log!("total: {compared} rays over {settings} settings, none differ from the CPU");
}
