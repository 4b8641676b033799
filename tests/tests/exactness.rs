//! DIRT's hits equal brute force's (same primitive, same `t`, `u`, `v` bits) on
//! adversarial rays, for every combination of views {cube, single}, traversal
//! {linear, hiz}, B ∈ {1, 8, 32} and S ∈ {1, 2, 4}.

use dirt_math::{Triangle, Vec3};
use dirt_tests::{adversarial_rays, assert_exact_over_matrix, grid, uv_sphere};

#[test]
fn closed_spheres_and_grid() {
    let mut tris: Vec<Triangle> = uv_sphere(Vec3::ZERO, 1.0, 12, 16);
    tris.extend(uv_sphere(Vec3::new(2.5, 0.3, -0.4), 0.7, 8, 12));
    tris.extend(grid(8, 8.0, -1.2));
    let rays = adversarial_rays(&tris, 150, 1);
    assert_exact_over_matrix("spheres+grid", &tris, &rays, 64);
}

#[test]
fn many_layers_under_one_pixel() {
    let mut tris = Vec::new();
    for k in 0..200 {
        tris.extend(grid(2, 1.0, k as f32 * 0.01));
    }
    let rays = adversarial_rays(&tris, 60, 2);
    assert_exact_over_matrix("layers", &tris, &rays, 32);
}

/// A single view placed inside the scene sees only its frustum. Defined
/// behaviour: a ray's hits outside the frustum are not found (the ray leaves
/// the view and its traversal ends there); every hit it does report is the
/// brute-force closest hit among the points the view sees.
#[test]
fn single_view_inside_the_scene_reports_what_it_sees() {
    use dirt_core::{AdsParams, Traversal, ViewsKind};
    use dirt_cpu::{Ads, brute_force, trace};
    use dirt_math::triangle::{RayShear, intersect};

    let mut tris: Vec<Triangle> = uv_sphere(Vec3::ZERO, 1.0, 12, 16);
    tris.extend(uv_sphere(Vec3::new(2.5, 0.3, -0.4), 0.7, 8, 12));
    tris.extend(grid(8, 8.0, -1.2));
    let rays = adversarial_rays(&tris, 100, 3);
    let truth = brute_force::trace(&tris, &rays);
    let eye = Vec3::new(1.5, 0.2, 2.0);
    let mut leaving = 0;
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let ads = Ads::build(
            &tris,
            &AdsParams {
                views: ViewsKind::Single,
                resolution: 64,
                buckets: 8,
                tile: 2,
                center: Some(eye),
                axis: None,
            },
        )
        .expect("build");
        let v = ads.views.views[0];
        // Inside the view's frustum, with a margin on the safe side.
        let sees = |p: Vec3, margin: f32| {
            let q = v.to_view(p);
            q[2] >= v.near * (1.0 + margin)
                && q[2] <= v.far * (1.0 - margin)
                && q[0].abs() <= q[2] * (1.0 - margin)
                && q[1].abs() <= q[2] * (1.0 - margin)
        };
        let hits = trace(&ads, &tris, &rays, trav);
        for (i, (h, g)) in hits.iter().zip(&truth).enumerate() {
            if h.bits() == g.bits() {
                continue;
            }
            // Brute force found something closer: it must lie where the view does not see.
            assert!(
                g.is_hit() && (!h.is_hit() || g.closer_than(h)),
                "ray {i}: dirt {h:?} is closer than brute {g:?}"
            );
            assert!(
                !sees(rays[i].at(g.t), 1e-3),
                "ray {i}: missed a hit inside the view: dirt {h:?} brute {g:?}"
            );
            leaving += 1;
            if h.is_hit() {
                // What it reports is a real hit of that triangle, bit for bit.
                let r = &rays[i];
                let (t, u, w) = intersect(r, &RayShear::new(r), &tris[h.prim as usize])
                    .expect("reported hit is a hit");
                assert_eq!(
                    [t.to_bits(), u.to_bits(), w.to_bits()],
                    [h.t.to_bits(), h.u.to_bits(), h.v.to_bits()]
                );
            }
        }
    }
    assert!(
        leaving > 0,
        "the test must include rays whose closest hit the view cannot see"
    );
}
