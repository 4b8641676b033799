//! The approximate screen-space tracers (MMRT and the single layer) against
//! brute force: their known losses reproduced on hand-built scenes with
//! hand-counted answers (a sliver between pixel centres, the thickness rule,
//! the single view's frustum and its one layer), simple rays close to the true
//! hit, error falling with resolution on a random scene, memory against 004
//! Table 2's formula, and bad input.
//!
//! The hand-built scenes share two walls (prims 0 and 1) whose bounds are
//! `[-3, 3]² × [-1, 1]`: the cube's centre is the origin, its near distance
//! `3/32`, so a point at world `z` lies at depth `z + 3/32` in the +Z view;
//! the diagonal is `√76 ≈ 8.72`, so a thickness of 0.01 is 0.0872 world units.

use dirt_core::{CoreError, Tracer};
use dirt_cpu::brute_force;
use dirt_cpu::screen_space::{
    DEFAULT_THICKNESS, Layers, Placement, ScreenSpace, ScreenSpaceParams,
};
use dirt_math::{Hit, INVALID_ID, Ray, Triangle, Vec3};

mod common;

use common::{Rng, rays, scene};

/// The cube's near distance for the walls' bounds.
const NEAR: f32 = 3.0 / 32.0;
// The origin of `rays_from_the_cube_centre_work` lies inside the near region.
const _: () = assert!(0.03 < NEAR);

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Prim 0: a wall at z = 1 covering `[-1, 1]²` (one triangle, so no diagonal
/// crosses the test points); prim 1: a wall at z = -1, likewise.
fn walls() -> Vec<Triangle> {
    vec![
        Triangle::new(v(-1.0, -1.0, 1.0), v(3.0, -1.0, 1.0), v(-1.0, 3.0, 1.0)),
        Triangle::new(v(1.0, 1.0, -1.0), v(-3.0, 1.0, -1.0), v(1.0, -3.0, -1.0)),
    ]
}

fn built(params: ScreenSpaceParams, tris: &[Triangle]) -> ScreenSpace {
    let mut s = ScreenSpace::new(params).expect("valid params");
    s.build(tris).expect("build");
    s
}

fn z_ray(x: f32, y: f32, z: f32) -> Ray {
    Ray::new(v(x, y, z), Vec3::Z, 0.0, f32::INFINITY)
}

/// Rays whose primitive differs from brute force's.
fn differing(hits: &[Hit], truth: &[Hit]) -> usize {
    hits.iter()
        .zip(truth)
        .filter(|(h, t)| h.prim != t.prim)
        .count()
}

/// A sliver 0.02 wide (prim 2, at z = 0.5, depth 0.59375 in the +Z view) in
/// front of the wall. At r8 pixel centres lie at slopes ±0.125, ±0.375, …,
/// i.e. x = ±0.074, … at its depth: it covers none and leaves no fragment, so
/// the five rays aimed at it report the wall behind (5 wrong by hand count;
/// the three aimed at the wall are right). At r64 the centre column of slope
/// 1/64 (x = 0.0093) crosses it wherever `0.01·(y + 0.5) <= 0.0093`, i.e.
/// `y <= 0.43`, which holds for every aimed ray: 0 wrong.
#[test]
fn sliver_between_pixel_centres_is_lost_at_low_resolution_only() {
    let mut tris = walls();
    tris.push(Triangle::new(
        v(0.0, -0.5, 0.5),
        v(0.02, -0.5, 0.5),
        v(0.01, 0.5, 0.5),
    ));
    let sliver_ys = [-0.4, -0.25, -0.1, 0.1, 0.25];
    let mut rays: Vec<Ray> = sliver_ys.iter().map(|&y| z_ray(0.01, y, 0.2)).collect();
    rays.extend([
        z_ray(0.6, 0.3, 0.2),
        z_ray(-0.5, -0.7, 0.2),
        z_ray(0.3, -0.2, 0.2),
    ]);
    let truth = brute_force::trace(&tris, &rays);
    let expected_truth: Vec<u32> = vec![2, 2, 2, 2, 2, 0, 0, 0];
    assert_eq!(
        truth.iter().map(|h| h.prim).collect::<Vec<_>>(),
        expected_truth
    );
    for (res, wrong) in [(8, 5), (64, 0)] {
        let mut s = built(ScreenSpaceParams::mmrt(res, 4, DEFAULT_THICKNESS), &tris);
        let hits = s.trace(&rays).expect("trace");
        let prims: Vec<u32> = hits.iter().map(|h| h.prim).collect();
        println!("mmrt r{res}: prims {prims:?}");
        assert_eq!(differing(&hits, &truth), wrong, "r{res}: {prims:?}");
        if res == 8 {
            // The lost sliver's rays land on the wall behind it.
            assert!(prims[..5].iter().all(|&p| p == 0), "{prims:?}");
        }
    }
}

/// A square (prims 2, 3) at z = 0.5, depth 0.59375; a ray segment running
/// along +x at z = 0.52 passes 0.02 behind it and never meets it (brute force
/// misses). With thickness 0.01 (0.0872 deep) the square's fragments count as
/// 0.0872 thick and the ray is reported on the square; with 0.001 (0.00872)
/// it passes behind them and misses.
#[test]
fn thickness_makes_a_ray_passing_behind_a_surface_hit_it() {
    let mut tris = walls();
    tris.push(Triangle::new(
        v(-0.2, -0.2, 0.5),
        v(0.2, -0.2, 0.5),
        v(0.2, 0.2, 0.5),
    ));
    tris.push(Triangle::new(
        v(-0.2, -0.2, 0.5),
        v(0.2, 0.2, 0.5),
        v(-0.2, 0.2, 0.5),
    ));
    // y = -0.17 < x all along the segment (x in [-0.1, 0.15]): only prim 2
    // (the half y <= x) lies in front of it, also at the nearby pixel centres.
    let ray = Ray::new(v(-0.1, -0.17, 0.52), Vec3::X, 0.0, 0.25);
    assert_eq!(brute_force::trace(&tris, &[ray])[0], Hit::MISS);
    let layers = [
        ScreenSpaceParams::mmrt(64, 4, 0.01),
        ScreenSpaceParams::single_layer(v(0.0, 0.0, -0.5), 64, 0.01),
    ];
    for p in layers {
        let mut thick = built(p, &tris);
        let h = thick.trace(&[ray]).expect("trace")[0];
        println!("{}: {h:?}", p.label());
        assert_eq!(h.prim, 2, "{}: {h:?}", p.label());
        assert!(h.t >= 0.0 && h.t <= 0.25, "{h:?}");
        let mut thin = built(
            ScreenSpaceParams {
                thickness: 0.001,
                ..p
            },
            &tris,
        );
        assert_eq!(thin.trace(&[ray]).expect("trace")[0], Hit::MISS);
    }
}

/// The single view from (0, 0, -0.5) looks along +z and sees `|x| <= depth`.
/// A ray from the origin along +x leaves that frustum at x = 0.5 and would
/// meet a triangle (prim 2) standing at x = 2.5: brute force and MMRT find it,
/// the single layer misses.
#[test]
fn single_layer_misses_outside_its_frustum() {
    let mut tris = walls();
    tris.push(Triangle::new(
        v(2.5, -0.5, -0.5),
        v(2.5, 0.5, -0.5),
        v(2.5, 0.0, 0.5),
    ));
    let ray = Ray::new(v(0.0, 0.1, 0.0), Vec3::X, 0.0, f32::INFINITY);
    let truth = brute_force::trace(&tris, &[ray])[0];
    assert_eq!(truth.prim, 2);
    let mut single = built(
        ScreenSpaceParams::single_layer(v(0.0, 0.0, -0.5), 64, DEFAULT_THICKNESS),
        &tris,
    );
    assert_eq!(single.trace(&[ray]).expect("trace")[0], Hit::MISS);
    let mut mmrt = built(ScreenSpaceParams::mmrt(64, 4, DEFAULT_THICKNESS), &tris);
    let h = mmrt.trace(&[ray]).expect("trace")[0];
    assert_eq!(h.prim, 2, "{h:?}");
    assert!((h.t - truth.t).abs() < 0.1, "{h:?} vs {truth:?}");
}

/// Two parallel triangles facing the camera at (0, 0, -0.5): A (prim 2) at
/// z = 0.1 and B (prim 3) at z = 0.5 behind it. A ray from z = 0.8 towards the
/// camera meets B first. The single layer keeps only A per pixel and reports
/// A; MMRT keeps both and reports B.
#[test]
fn single_layer_loses_occluded_surfaces_mmrt_keeps_them() {
    let mut tris = walls();
    tris.push(Triangle::new(
        v(-0.5, -0.5, 0.1),
        v(0.7, -0.5, 0.1),
        v(-0.5, 0.7, 0.1),
    ));
    tris.push(Triangle::new(
        v(-0.5, -0.5, 0.5),
        v(0.7, -0.5, 0.5),
        v(-0.5, 0.7, 0.5),
    ));
    let ray = Ray::new(v(0.05, 0.05, 0.8), -Vec3::Z, 0.0, f32::INFINITY);
    let truth = brute_force::trace(&tris, &[ray])[0];
    assert_eq!(truth.prim, 3);
    let eye = v(0.0, 0.0, -0.5);
    let mut single = built(
        ScreenSpaceParams::single_layer(eye, 64, DEFAULT_THICKNESS),
        &tris,
    );
    let h = single.trace(&[ray]).expect("trace")[0];
    assert_eq!(h.prim, 2, "single layer: {h:?}");
    let mut mmrt = built(ScreenSpaceParams::mmrt(64, 4, DEFAULT_THICKNESS), &tris);
    let h = mmrt.trace(&[ray]).expect("trace")[0];
    assert_eq!(h.prim, 3, "mmrt: {h:?}");
    // And the A-buffer of one camera view (all layers, camera placement) too.
    let mut camera_all = built(
        ScreenSpaceParams {
            layers: Layers::All,
            buckets: 4,
            ..ScreenSpaceParams::single_layer(eye, 64, DEFAULT_THICKNESS)
        },
        &tris,
    );
    assert_eq!(camera_all.trace(&[ray]).expect("trace")[0].prim, 3);
}

/// Rays at a tilted triangle (prim 2, z = 0.2 + 0.3·x, so the depth of a
/// fragment taken at a pixel centre is off by up to 0.3 × half a pixel) and at
/// the wall: the right prim, `t` within 0.02 of brute force's (at r128 a pixel
/// is about 0.011 wide at these depths) and `u`, `v` within 0.02.
#[test]
fn simple_rays_hit_the_right_prim_close_to_brute_force() {
    let mut tris = walls();
    let tilt = |x: f32, y: f32| v(x, y, 0.2 + 0.3 * x);
    tris.push(Triangle::new(
        tilt(-0.8, -0.8),
        tilt(0.8, -0.8),
        tilt(-0.8, 0.8),
    ));
    let mut rng = Rng(7);
    let mut rays = Vec::new();
    for k in 0..64 {
        // Points inside the tilted triangle (x + y < 0) or on the wall beyond it.
        let (x, y) = (rng.f() * 1.2 - 0.7, rng.f() * 1.2 - 0.7);
        let target = if k % 2 == 0 && x + y < -0.1 {
            tilt(x, y)
        } else {
            v(x * 0.3 + 0.6, y * 0.3 + 0.6, 1.0)
        };
        let o = v(rng.f() * 0.2 - 0.1, rng.f() * 0.2 - 0.1, -0.3);
        rays.push(Ray::new(o, target - o, 0.0, f32::INFINITY));
    }
    let truth = brute_force::trace(&tris, &rays);
    for p in [
        ScreenSpaceParams::mmrt(128, 8, DEFAULT_THICKNESS),
        // Far enough back that every target is inside the camera's frustum.
        ScreenSpaceParams::single_layer(v(0.0, 0.0, -0.9), 128, DEFAULT_THICKNESS),
    ] {
        let mut s = built(p, &tris);
        let hits = s.trace(&rays).expect("trace");
        let (mut dt, mut duv) = (0.0f32, 0.0f32);
        for (i, (h, t)) in hits.iter().zip(&truth).enumerate() {
            assert!(t.is_hit());
            assert_eq!(
                h.prim,
                t.prim,
                "{} ray {i} {:?}: {h:?} vs {t:?}",
                p.label(),
                rays[i]
            );
            dt = dt.max((h.t - t.t).abs());
            duv = duv.max((h.u - t.u).abs()).max((h.v - t.v).abs());
            assert!(h.u >= 0.0 && h.v >= 0.0 && h.u + h.v <= 1.0 + 1e-6, "{h:?}");
        }
        println!("{}: max |dt| {dt:.5}, max |du|,|dv| {duv:.5}", p.label());
        assert!(dt <= 0.02, "{}: max |dt| {dt}", p.label());
        assert!(duv <= 0.02, "{}: max |du|,|dv| {duv}", p.label());
    }
}

/// On a random scene: the share of rays whose primitive differs from brute
/// force's falls as the resolution rises (fewer triangles fall between pixel
/// centres); the buckets change nothing but speed (the same hits at B1 and
/// B16); a thinner thickness gives fewer hits in front of the true one, and
/// at a fixed thickness the single layer differs more than MMRT.
#[test]
fn random_scene_error_falls_with_resolution() {
    let mut rng = Rng(0x5eed);
    let tris = scene(400, &mut rng);
    let rays = rays(4000, &tris, &mut rng);
    let truth = brute_force::trace(&tris, &rays);
    let share = |hits: &[Hit]| differing(hits, &truth) as f64 / rays.len() as f64;
    // Hits in front of the true hit (or where there is none): the thickness' false hits.
    let early = |hits: &[Hit]| {
        hits.iter()
            .zip(&truth)
            .filter(|(h, t)| h.is_hit() && h.prim != t.prim && h.t < t.t)
            .count()
    };
    let mut shares = Vec::new();
    for res in [32, 256] {
        let mut s = built(ScreenSpaceParams::mmrt(res, 4, DEFAULT_THICKNESS), &tris);
        let hits = s.trace(&rays).expect("trace");
        println!(
            "mmrt r{res} B4 th0.01: {:.2}% differ, {} fragments, {} B (model {} B)",
            100.0 * share(&hits),
            s.fragments(),
            s.memory_bytes(),
            s.model_bytes()
        );
        shares.push(share(&hits));
    }
    assert!(
        shares[1] < shares[0],
        "share differing should fall with resolution: {shares:?}"
    );

    let hits_b1 = built(ScreenSpaceParams::mmrt(64, 1, DEFAULT_THICKNESS), &tris)
        .trace(&rays)
        .expect("trace");
    let hits_b16 = built(ScreenSpaceParams::mmrt(64, 16, DEFAULT_THICKNESS), &tris)
        .trace(&rays)
        .expect("trace");
    assert!(
        hits_b1
            .iter()
            .zip(&hits_b16)
            .all(|(a, b)| a.bits() == b.bits()),
        "buckets must not change the hits"
    );

    let mut earlies = Vec::new();
    for th in [0.05, 0.01, 0.002] {
        let hits = built(ScreenSpaceParams::mmrt(128, 4, th), &tris)
            .trace(&rays)
            .expect("trace");
        let misses = hits
            .iter()
            .zip(&truth)
            .filter(|(h, t)| !h.is_hit() && t.is_hit())
            .count();
        println!(
            "mmrt r128 th{th}: {:.2}% differ, {} hits in front of the true one, {} false misses",
            100.0 * share(&hits),
            early(&hits),
            misses
        );
        earlies.push(early(&hits));
    }
    assert!(
        earlies[0] > earlies[1] && earlies[1] > earlies[2],
        "hits in front of the true one should fall as the thickness tightens: {earlies:?}"
    );

    let eye = v(0.0, 0.2, -2.5);
    let single = built(
        ScreenSpaceParams::single_layer(eye, 128, DEFAULT_THICKNESS),
        &tris,
    )
    .trace(&rays)
    .expect("trace");
    let mmrt = built(ScreenSpaceParams::mmrt(128, 4, DEFAULT_THICKNESS), &tris)
        .trace(&rays)
        .expect("trace");
    println!(
        "r128 th0.01: 1-layer {:.2}% differ, mmrt {:.2}% differ",
        100.0 * share(&single),
        100.0 * share(&mmrt)
    );
    assert!(share(&single) > share(&mmrt));
}

/// A bounded march stops early: with one pixel per view a ray from far away
/// finds nothing; unbounded it finds the wall.
#[test]
fn max_steps_bounds_the_march() {
    let tris = walls();
    let ray = z_ray(0.3, 0.2, -0.9);
    let p = ScreenSpaceParams::mmrt(64, 4, DEFAULT_THICKNESS);
    assert_eq!(built(p, &tris).trace(&[ray]).expect("trace")[0].prim, 0);
    let bounded = ScreenSpaceParams { max_steps: 1, ..p };
    assert_eq!(bounded.label(), "mmrt r64 B4 th1e-2 steps1");
    assert_eq!(
        built(bounded, &tris).trace(&[ray]).expect("trace")[0],
        Hit::MISS
    );
}

/// Memory: what is stored (8 B per pixel of depth bounds, 4 B per pixel and
/// bucket plus one of heads, 8 B per fragment), and 004 Table 2's DLLB
/// formula `V·r²·(8 + 8B) + F·(12 + 4)`; the single layer's depth and id
/// buffers `r²·8`. The walls at r16 are seen by all six cube views.
#[test]
fn memory_matches_what_is_stored_and_table_2() {
    let tris = walls();
    let mut s = ScreenSpace::new(ScreenSpaceParams::mmrt(16, 4, DEFAULT_THICKNESS)).expect("new");
    let report = s.build(&tris).expect("build");
    let names: Vec<&str> = report.stages.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["fragments", "reorder"]);
    assert_eq!(s.name(), "mmrt");
    assert_eq!(s.views(), 6);
    let (px, f) = (6 * 16 * 16u64, s.fragments() as u64);
    assert!(f > 0);
    assert_eq!(report.memory, Some(s.memory_bytes()));
    assert_eq!(s.memory_bytes(), 8 * px + 4 * (px * 4 + 6) + 8 * f);
    assert_eq!(s.model_bytes(), px * (8 + 8 * 4) + 16 * f);

    let mut one = ScreenSpace::new(ScreenSpaceParams::single_layer(
        v(0.0, 0.0, -0.5),
        16,
        DEFAULT_THICKNESS,
    ))
    .expect("new");
    let report = one.build(&tris).expect("build");
    assert_eq!(one.name(), "1-layer");
    // Plus its Hi-Z above the pixels: 8² + 4² + 2² + 1 cells of 8 B; 004's
    // model has no pyramid.
    assert_eq!(report.memory, Some(16 * 16 * 8 + (64 + 16 + 4 + 1) * 8));
    assert_eq!(one.model_bytes(), 16 * 16 * 8);
    let linear = built(
        ScreenSpaceParams {
            hiz: false,
            ..*one.params()
        },
        &tris,
    );
    assert_eq!(linear.memory_bytes(), 16 * 16 * 8);
    assert_eq!(linear.model_bytes(), 16 * 16 * 8);
    // MMRT with a pyramid: the same, over the cube's six views.
    let mmrt_hiz = built(
        ScreenSpaceParams {
            hiz: true,
            ..ScreenSpaceParams::mmrt(16, 4, DEFAULT_THICKNESS)
        },
        &tris,
    );
    assert_eq!(
        mmrt_hiz.memory_bytes(),
        s.memory_bytes() + 6 * (64 + 16 + 4 + 1) * 8
    );
    assert_eq!(mmrt_hiz.model_bytes(), s.model_bytes());
    // The wall at z = 1 (depth 1.5, where the view spans [-1.5, 1.5]²) covers
    // x >= -1, y >= -1, x + y <= 2. Pixel centres lie at -1.5 + 0.1875·(i + 0.5):
    // columns and rows 3..=15 have x, y >= -1 (169 pixels), of which the 15
    // with i + j >= 26 have x + y > 2: 154 fragments; the wall at z = -1 is
    // behind the eye.
    assert_eq!(one.fragments(), 154);
}

#[test]
fn labels_and_params() {
    let m = ScreenSpaceParams::mmrt(128, 8, 0.01);
    assert_eq!(m.label(), "mmrt r128 B8 th1e-2");
    assert_eq!(m.placement, Placement::Cube);
    assert_eq!(m.max_steps, 0);
    let s = ScreenSpaceParams::single_layer(Vec3::ONE, 128, 0.01);
    assert_eq!(s.label(), "1-layer r128 th1e-2");
    assert_eq!(s.layers, Layers::Nearest);
    assert_eq!(s.buckets, 1);
    assert!(s.hiz && !m.hiz);
    let s_linear = ScreenSpaceParams { hiz: false, ..s };
    assert_eq!(s_linear.label(), "1-layer r128 th1e-2 linear");
    let m_hiz = ScreenSpaceParams { hiz: true, ..m };
    assert_eq!(m_hiz.label(), "mmrt r128 B8 th1e-2 hiz");
    assert!(s_linear.validate().is_ok() && m_hiz.validate().is_ok());
    assert!(m.validate().is_ok() && s.validate().is_ok());
}

#[test]
fn bad_params_are_refused_with_readable_messages() {
    let ok = ScreenSpaceParams::mmrt(64, 4, 0.01);
    let cases = [
        (
            ScreenSpaceParams {
                resolution: 0,
                ..ok
            },
            "resolution",
        ),
        (
            ScreenSpaceParams {
                resolution: 5000,
                ..ok
            },
            "resolution",
        ),
        (ScreenSpaceParams { buckets: 0, ..ok }, "buckets"),
        (ScreenSpaceParams { buckets: 65, ..ok }, "buckets"),
        (
            ScreenSpaceParams {
                thickness: f32::NAN,
                ..ok
            },
            "thickness",
        ),
        (
            ScreenSpaceParams {
                thickness: -0.1,
                ..ok
            },
            "thickness",
        ),
        (
            ScreenSpaceParams {
                thickness: f32::INFINITY,
                ..ok
            },
            "thickness",
        ),
        (
            ScreenSpaceParams::single_layer(v(f32::NAN, 0.0, 0.0), 64, 0.01),
            "eye",
        ),
    ];
    for (p, word) in cases {
        let e = ScreenSpace::new(p).expect_err("must be refused");
        assert!(matches!(e, CoreError::InvalidParams(_)), "{e:?}");
        let msg = e.to_string();
        assert!(msg.contains(word), "{msg}");
        assert_eq!(p.validate().map_err(|e| e.to_string()), Err(msg));
    }
    // Too big a structure is refused before anything is allocated.
    let mut huge = ScreenSpace::new(ScreenSpaceParams::mmrt(4096, 64, 0.01)).expect("valid");
    let e = huge.build(&walls()).expect_err("too many heads");
    assert!(e.to_string().contains("lower the resolution"), "{e}");
    // A failed build leaves the tracer unbuilt.
    assert!(matches!(
        huge.trace(&[z_ray(0.0, 0.0, 0.0)]),
        Err(CoreError::NotBuilt { .. })
    ));
}

#[test]
fn bad_rays_and_triangles_do_not_panic() {
    let mut s = ScreenSpace::new(ScreenSpaceParams::mmrt(32, 4, 0.01)).expect("new");
    let e = s.trace(&[z_ray(0.0, 0.0, 0.0)]).expect_err("not built");
    assert!(matches!(e, CoreError::NotBuilt { .. }), "{e:?}");
    assert!(e.to_string().contains("mmrt"), "{e}");

    // NaN, degenerate, zero-area, huge and tiny triangles beside the walls.
    let mut tris = walls();
    let nan = f32::NAN;
    tris.push(Triangle::new(v(nan, 0.0, 0.0), v(0.0, 1.0, 0.0), Vec3::ONE));
    tris.push(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
    tris.push(Triangle::new(
        v(0.0, 0.0, 0.3),
        v(0.5, 0.5, 0.3),
        v(1.0, 1.0, 0.3),
    ));
    tris.push(Triangle::new(
        v(0.0, 0.0, 0.5),
        v(1e-30, 0.0, 0.5),
        v(0.0, 1e-30, 0.5),
    ));
    tris.push(Triangle::new(v(f32::INFINITY, 0.0, 0.0), Vec3::X, Vec3::Y));
    for p in [
        ScreenSpaceParams::mmrt(32, 4, 0.01),
        ScreenSpaceParams::single_layer(v(0.0, 0.0, -0.5), 32, 0.01),
    ] {
        let mut s = built(p, &tris);
        let bad = [
            Ray::new(v(nan, 0.0, 0.0), Vec3::Z, 0.0, 1.0),
            Ray::new(Vec3::ZERO, v(0.0, nan, 1.0), 0.0, 1.0),
            Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0, 1.0),
            Ray::new(Vec3::ZERO, Vec3::Z, nan, 1.0),
            Ray::new(Vec3::ZERO, Vec3::Z, 2.0, 1.0),
        ];
        let hits = s.trace(&bad).expect("trace");
        assert!(hits.iter().all(|h| *h == Hit::MISS), "{hits:?}");
        // The good triangles are still found.
        let h = s.trace(&[z_ray(0.4, -0.6, 0.0)]).expect("trace")[0];
        assert_eq!(h.prim, 0, "{}: {h:?}", p.label());
        // Wrong buffer lengths are an error, not a panic.
        let mut short = [Hit::MISS; 1];
        assert!(matches!(
            s.trace_into(&bad, &mut short, None),
            Err(CoreError::BufferLength { .. })
        ));
    }

    // Huge coordinates: builds, traces, no panic.
    let far = vec![Triangle::new(
        v(-1e30, -1e30, 1e30),
        v(1e30, -1e30, 1e30),
        v(0.0, 1e30, 1e30),
    )];
    let mut s = built(ScreenSpaceParams::mmrt(16, 4, 0.01), &far);
    let _ = s.trace(&[z_ray(0.0, 0.0, 0.0)]).expect("trace");

    // No triangles (or none usable): builds, every ray misses.
    for tris in [
        Vec::new(),
        vec![Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE)],
    ] {
        let mut s = ScreenSpace::new(ScreenSpaceParams::mmrt(16, 4, 0.01)).expect("new");
        let r = s.build(&tris).expect("build");
        assert_eq!(s.fragments(), 0);
        assert_eq!(r.memory, Some(s.memory_bytes()));
        let hits = s.trace(&[z_ray(0.0, 0.0, 0.0)]).expect("trace");
        assert_eq!(hits[0], Hit::MISS);
        assert_eq!(hits[0].prim, INVALID_ID);
    }
}

/// Rays starting in the near region around the cube's centre (between the
/// six near planes) still find the walls.
#[test]
fn rays_from_the_cube_centre_work() {
    let tris = walls();
    let mut s = built(ScreenSpaceParams::mmrt(64, 4, DEFAULT_THICKNESS), &tris);
    for (d, prim) in [(Vec3::Z, 0), (-Vec3::Z, 1), (v(0.3, 0.2, 1.0), 0)] {
        let ray = Ray::new(v(0.01, -0.02, 0.03), d, 0.0, f32::INFINITY);
        let truth = brute_force::trace(&tris, &[ray])[0];
        let h = s.trace(&[ray]).expect("trace")[0];
        assert_eq!(h.prim, prim, "{h:?}");
        assert_eq!(truth.prim, prim);
        assert!((h.t - truth.t).abs() < 0.01, "{h:?} vs {truth:?}");
    }
}

/// Hits of the Hi-Z march and of the linear march (the same params with
/// `hiz` off), compared bit for bit; returns how many rays hit.
fn hiz_equals_linear(p: ScreenSpaceParams, tris: &[Triangle], rays: &[Ray]) -> usize {
    let mut fast = built(ScreenSpaceParams { hiz: true, ..p }, tris);
    let mut slow = built(ScreenSpaceParams { hiz: false, ..p }, tris);
    assert_eq!(fast.fragments(), slow.fragments());
    let a = fast.trace(rays).expect("trace");
    let b = slow.trace(rays).expect("trace");
    for (k, (h, l)) in a.iter().zip(&b).enumerate() {
        assert_eq!(
            h.bits(),
            l.bits(),
            "{}: ray {k} {:?}: hiz {h:?} vs linear {l:?}",
            p.label(),
            rays[k]
        );
    }
    a.iter().filter(|h| h.is_hit()).count()
}

/// The Hi-Z single layer's hits are the linear march's, bit for bit: random
/// scenes and rays (from inside and far outside, grazing, short segments,
/// invalid ones), several seeds, resolutions (1, odd, non-powers of two),
/// thicknesses and eyes (inside and outside the scene's bounds); and the same
/// for the pyramid over the cube's views (several views: the bound of an
/// earlier view's hit matters) and over MMRT's A-buffer.
#[test]
fn hiz_hits_equal_the_linear_march_bit_for_bit() {
    let eyes = [
        v(0.0, 0.2, -2.5),
        v(0.1, -0.2, 0.3),
        v(3.0, 2.0, 1.0),
        v(-0.6, 0.5, -0.7),
    ];
    let mut rays_total = 0;
    let mut hits_total = 0;
    for seed in [1u64, 2, 3] {
        let mut rng = Rng(0xd1e7 + seed);
        let tris = scene(300, &mut rng);
        let rays = rays(2000, &tris, &mut rng);
        for (n, &eye) in eyes.iter().enumerate() {
            let res = [100, 64, 37, 128][(n + seed as usize) % 4];
            let th = [0.01, 0.0, 0.002, 0.05][(n + 2 * seed as usize) % 4];
            let p = ScreenSpaceParams::single_layer(eye, res, th);
            hits_total += hiz_equals_linear(p, &tris, &rays);
            rays_total += rays.len();
        }
        let r = rays.len() / 4;
        for res in [1, 2, 3, 5, 100] {
            let p = ScreenSpaceParams::single_layer(eyes[seed as usize], res, DEFAULT_THICKNESS);
            hits_total += hiz_equals_linear(p, &tris, &rays[..r]);
            rays_total += r;
        }
        // One layer over the cube's views, and MMRT's A-buffer.
        let cube = ScreenSpaceParams {
            placement: Placement::Cube,
            ..ScreenSpaceParams::single_layer(Vec3::ZERO, 100, DEFAULT_THICKNESS)
        };
        hits_total += hiz_equals_linear(cube, &tris, &rays);
        rays_total += rays.len();
        let mmrt = ScreenSpaceParams::mmrt(100, 4, 0.005);
        hits_total += hiz_equals_linear(mmrt, &tris, &rays[..r]);
        rays_total += r;
        // A bounded march is linear either way.
        let bounded = ScreenSpaceParams {
            max_steps: 5,
            ..ScreenSpaceParams::single_layer(eyes[0], 64, DEFAULT_THICKNESS)
        };
        hits_total += hiz_equals_linear(bounded, &tris, &rays[..r]);
        rays_total += r;
    }
    println!("{hits_total} hits of {rays_total} rays, the same bits");
    assert!(rays_total >= 2000);
    // Enough hits that the comparison says something.
    assert!(hits_total > rays_total / 10, "{hits_total} of {rays_total}");
}

/// Many short segments and rays aimed at triangles from near the camera
/// (reflection-like rays: most hit something after a few pixels), on a
/// denser scene.
#[test]
fn hiz_equals_linear_on_rays_aimed_at_the_scene() {
    let mut rng = Rng(0xabc);
    let tris = scene(1500, &mut rng);
    let eye = v(0.0, 0.3, -2.2);
    let mut rays = Vec::new();
    for k in 0..3000 {
        let o = if k % 2 == 0 {
            eye + rng.v(0.3)
        } else {
            rng.v(0.9)
        };
        let t = tris[rng.below(tris.len())];
        let target = t.vertex(0) * 0.4 + t.vertex(1) * 0.3 + t.vertex(2) * 0.3;
        let tmax = if k % 3 == 0 {
            rng.f() * 3.0
        } else {
            f32::INFINITY
        };
        rays.push(Ray::new(o, target - o + rng.v(0.05), 0.0, tmax));
    }
    let mut hits = 0;
    for (res, th) in [(100, 0.01), (256, 0.003), (61, 0.02)] {
        hits += hiz_equals_linear(ScreenSpaceParams::single_layer(eye, res, th), &tris, &rays);
    }
    assert!(hits > rays.len(), "{hits}");
}
