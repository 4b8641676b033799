//! The examples are tests: each runs here as a user would run it, and what it
//! produced is checked.

#[allow(dead_code)]
#[path = "../../crates/dirt-gpu/examples/deforming.rs"]
mod deforming;

use dirt_core::{AdsParams, Traversal};
use dirt_cpu::{Ads, trace_with_stats};
use std::path::PathBuf;

/// `deforming`: every frame of the deforming engine, built and traced in the
/// example's own encoder on its own device, equals the CPU's build and trace
/// over that frame's triangles, bit for bit; the images are written.
#[test]
fn the_deforming_example_is_exact_every_frame() {
    let required = std::env::var("DIRT_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("deforming");
    let params = AdsParams {
        resolution: 32,
        buckets: 4,
        ..AdsParams::default()
    };
    let opts = deforming::Options {
        model: PathBuf::from(deforming::DEFAULT_MODEL),
        frames: 2,
        size: 32,
        out: Some(out.clone()),
        params,
    };
    let run = match deforming::run(&opts) {
        Ok(r) => r,
        Err(e) if !required => {
            eprintln!("SKIP the_deforming_example_is_exact_every_frame: {e}");
            return;
        }
        Err(e) => panic!("the example failed: {e}"),
    };
    if !run.exact {
        assert!(!required, "{} is not on the exact path", run.adapter);
        eprintln!(
            "SKIP bits of the deforming example: {} is not on the exact path",
            run.adapter
        );
        return;
    }
    assert_eq!(run.frames.len(), 2);
    assert_eq!(
        run.feedback.recorded as u32,
        2 + run.frames.iter().map(|f| f.rerecorded).sum::<u32>()
    );
    for (k, f) in run.frames.iter().enumerate() {
        assert!(
            f.triangles.len() > 10_000,
            "{} triangles",
            f.triangles.len()
        );
        let cpu = Ads::build(&f.triangles, &params).expect("cpu build");
        let (hits, _) = trace_with_stats(&cpu, &f.triangles, &f.rays, Traversal::HiZ);
        let hit = hits.iter().filter(|h| h.is_hit()).count();
        assert!(
            hit > f.rays.len() / 10,
            "frame {k}: the camera sees the model ({hit} hits)"
        );
        for (r, (a, b)) in f.hits.iter().zip(&hits).enumerate() {
            assert_eq!(a.bits(), b.bits(), "frame {k} ray {r}: gpu {a:?} cpu {b:?}");
        }
        assert!(out.join(format!("frame-{k:03}.png")).exists());
    }
    // The model moves: frames differ.
    assert_ne!(
        run.frames[0].triangles[0].vertex(0),
        run.frames[1].triangles[0].vertex(0)
    );
}
