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

/// The portable path: WGSL compiled by the browser (Tint) for its device.
/// Left out of the default run: on headless Chromium's SwiftShader the
/// `trace` pipeline alone takes about 400 s to compile (measured: every other
/// pipeline under 1 s), and the first read-back after it then fails with a
/// map error. Run it with `-- --include-ignored` (and
/// `WASM_BINDGEN_TEST_TIMEOUT=1500`) on a browser with a hardware adapter.
#[wasm_bindgen_test]
#[ignore = "SwiftShader compiles the trace pipeline for ~400 s; see the doc comment"]
async fn webgpu_against_the_cpu_reference() {
    let t0 = web_time::Instant::now();
    let gpu = dirt_web::bind::page_gpu().await.expect("the page's WebGPU");
    console_log!("device and pipelines: {:?}", t0.elapsed());
    console_log!("adapter: {} — {}", gpu.describe(), gpu.exactness);
    let mut all = Vec::new();
    for name in ["cornell", "spheres"] {
        let scene = dirt_scene::open(name).expect("scene");
        let rays = probe_rays(&scene.triangles, 1500, 11);
        for params in dirt_web::check_params() {
            for traversal in [Traversal::Linear, Traversal::HiZ] {
                let t0 = web_time::Instant::now();
                let c = check(gpu, &scene.triangles, &rays, &params, traversal)
                    .await
                    .expect("check");
                console_log!(
                    "{name} {params:?} {traversal} ({:?}): {}",
                    t0.elapsed(),
                    c.summary()
                );
                assert!(
                    c.cpu_truth.is_empty(),
                    "the CPU reference: {:?}",
                    c.cpu_truth
                );
                all.push(c);
            }
        }
    }
}
