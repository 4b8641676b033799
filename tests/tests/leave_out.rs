//! Views no triangle reaches are left out of the structure (no passes, no
//! memory) and that changes no hit, on either backend.

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, brute_force, trace_with_stats};
use dirt_gpu::testing::exact_gpu;
use dirt_math::{Triangle, Vec3};
use dirt_tests::{adversarial_rays, grid, uv_sphere};

/// Geometry on the +X and +Y sides of a cube centred at (1, 1, 0): the bounds
/// reach every face's frustum, but no triangle reaches the -X, -Y, +Z, -Z faces.
fn lopsided() -> (Vec<Triangle>, AdsParams) {
    let mut tris = uv_sphere(Vec3::new(9.0, 1.0, 0.0), 0.8, 8, 12);
    // A floor-like grid high on +Y, moved to x ∈ [0, 2].
    tris.extend(grid(4, 2.0, 0.0).into_iter().map(|t| {
        let m = |p: Vec3| Vec3::new(p.x + 1.0, 9.0 + p.z, p.y);
        Triangle::new(m(t.vertex(0)), m(t.vertex(1)), m(t.vertex(2)))
    }));
    let params = AdsParams {
        views: ViewsKind::Cube,
        resolution: 32,
        buckets: 4,
        tile: 1,
        center: Some(Vec3::new(1.0, 1.0, 0.0)),
        axis: None,
    };
    (tris, params)
}

#[test]
fn views_no_triangle_reaches_are_left_out_with_their_memory() {
    let (tris, params) = lopsided();
    let all = Ads::build_all_views(&tris, &params).expect("build all");
    let ads = Ads::build(&tris, &params).expect("build");
    let reached: Vec<bool> = ads.views.views.iter().map(|v| v.has_content).collect();
    // +X (0) and +Y (2) see geometry; the others see none of it.
    assert_eq!(reached, [true, false, true, false, false, false]);
    assert!(
        all.views.slots() > ads.views.slots(),
        "the bounds reach more views"
    );
    // Memory is per stored view: the left-out ones cost nothing.
    let per_view = |a: &Ads| a.depth().len() / a.views.slots();
    assert_eq!(per_view(&ads), per_view(&all));
    assert_eq!(ads.depth().len(), 2 * per_view(&ads));
    assert!(ads.memory().total() < all.memory().total());
    // The same lists: every node of a left-out view would have been in an empty view.
    assert_eq!(ads.lists.ids.len(), all.lists.ids.len());
    // Slots are dense, in view order.
    let slots: Vec<u32> = ads.views.views.iter().map(|v| v.slot).collect();
    let none = dirt_math::view::NO_SLOT;
    assert_eq!(slots, [0, none, 1, none, none, none]);
}

#[test]
fn leaving_views_out_changes_no_hit() {
    let (tris, params) = lopsided();
    let rays = adversarial_rays(&tris, 400, 11);
    let truth = brute_force::trace(&tris, &rays);
    for params in [
        params,
        AdsParams { tile: 2, ..params },
        AdsParams {
            views: ViewsKind::Single,
            ..params
        },
    ] {
        let ads = Ads::build(&tris, &params).expect("build");
        let all = Ads::build_all_views(&tris, &params).expect("build all");
        for trav in [Traversal::Linear, Traversal::HiZ] {
            let (hits, _) = trace_with_stats(&ads, &tris, &rays, trav);
            let (hits_all, _) = trace_with_stats(&all, &tris, &rays, trav);
            for (i, ((h, a), g)) in hits.iter().zip(&hits_all).zip(&truth).enumerate() {
                assert_eq!(h.bits(), a.bits(), "ray {i} {params:?} {trav:?}");
                if params.views == ViewsKind::Cube {
                    assert_eq!(h.bits(), g.bits(), "ray {i} {params:?} {trav:?}");
                }
            }
        }
    }
}

#[test]
fn gpu_leaves_out_the_same_views_and_agrees_bit_for_bit() {
    let Some(gpu) = exact_gpu("gpu_leaves_out_the_same_views_and_agrees_bit_for_bit") else {
        return;
    };
    let (tris, params) = lopsided();
    let rays = adversarial_rays(&tris, 200, 12);
    let cpu = Ads::build(&tris, &params).expect("cpu build");
    let g = dirt_gpu::GpuAds::build(gpu, &tris, &params).expect("gpu build");
    assert_eq!(g.views.as_ref(), Some(&cpu.views));
    assert_eq!(g.read_hiz(gpu).expect("hiz"), cpu.hiz);
    let lists = g.read_lists(gpu).expect("lists");
    assert_eq!(lists.offsets, cpu.lists.offsets);
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let (hits, stats) = trace_with_stats(&cpu, &tris, &rays, trav);
        let (ghits, gstats) = dirt_gpu::trace::trace(gpu, &g, &rays, trav).expect("gpu trace");
        let bits = |h: &[dirt_math::Hit]| h.iter().map(|h| h.bits()).collect::<Vec<_>>();
        assert_eq!(bits(&ghits), bits(&hits), "{trav:?}");
        assert_eq!(gstats, stats, "{trav:?}");
    }
}

#[test]
fn an_empty_scene_stores_nothing_and_misses() {
    let params = AdsParams::default();
    let ads = Ads::build(&[], &params).expect("build");
    assert_eq!(ads.views.slots(), 0);
    assert!(ads.depth().is_empty());
    let rays = [dirt_math::Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)];
    let (hits, _) = trace_with_stats(&ads, &[], &rays, Traversal::HiZ);
    assert!(!hits[0].is_hit());
}

#[test]
fn left_out_views_say_why() {
    use dirt_core::{LeftOutReason, left_out_views};
    let (tris, params) = lopsided();
    let left = left_out_views(&tris, &params).expect("views");
    let names: Vec<&str> = left.iter().map(|l| l.name).collect();
    assert_eq!(names, ["-X", "-Y", "+Z", "-Z"]);
    assert!(
        left.iter()
            .all(|l| l.reason == LeftOutReason::NoTriangleReaches)
    );
    // A centre outside the bounds: the face looking away sees not even the bounds.
    let outside = AdsParams {
        center: Some(Vec3::new(-20.0, 1.0, 0.0)),
        ..params
    };
    let left = left_out_views(&tris, &outside).expect("views");
    let minus_x = left.iter().find(|l| l.name == "-X").expect("-X left out");
    assert_eq!(minus_x.reason, LeftOutReason::BoundsBehind);
    assert!(!left.iter().any(|l| l.name == "+X"), "+X sees everything");
}
