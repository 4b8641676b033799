//! The fast path behind `trace`, `trace_into`, `trace_with_stats` and
//! `trace_ray` against the plain stage (`trace::trace_ray_plain`, the loops
//! `trace.wgsl` mirrors): the same hit bits and the same per-ray statistics
//! (views, tiles, buckets, tests) on random scenes, rays and parameters.

use dirt_core::{AdsParams, RayStats, Traversal, ViewsKind};
use dirt_cpu::trace::{trace_ray, trace_ray_plain};
use dirt_cpu::{Ads, trace, trace_into, trace_with_stats};
use dirt_math::{Hit, Ray, Triangle, Vec3};
use proptest::prelude::*;

/// A deterministic stream (64-bit LCG, top 24 bits).
struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.f() * n as f32) as usize).min(n - 1)
    }
    fn v(&mut self, s: f32) -> Vec3 {
        Vec3::new(
            self.f() * 2.0 - 1.0,
            self.f() * 2.0 - 1.0,
            self.f() * 2.0 - 1.0,
        ) * s
    }
}

/// Small random triangles, a grid of shared edges (a floor) and a few
/// degenerate and large ones.
fn scene(n: usize, rng: &mut Rng) -> Vec<Triangle> {
    let mut tris = Vec::new();
    for _ in 0..n {
        let c = rng.v(1.0);
        let s = if rng.f() < 0.1 { 1.0 } else { 0.15 };
        tris.push(Triangle::new(c + rng.v(s), c + rng.v(s), c + rng.v(s)));
    }
    let g = 6;
    let p = |i: usize, j: usize| {
        Vec3::new(
            -1.0 + 2.0 * i as f32 / g as f32,
            -0.9,
            -1.0 + 2.0 * j as f32 / g as f32,
        )
    };
    for j in 0..g {
        for i in 0..g {
            tris.push(Triangle::new(p(i, j), p(i + 1, j), p(i + 1, j + 1)));
            tris.push(Triangle::new(p(i, j), p(i + 1, j + 1), p(i, j + 1)));
        }
    }
    let a = rng.v(1.0);
    tris.push(Triangle::new(a, a, a + Vec3::X));
    tris.push(Triangle::new(a, a + Vec3::Y, a + 2.0 * Vec3::Y));
    tris
}

/// Rays of every kind the tracer distinguishes: from inside and far outside,
/// aimed at vertices and edge midpoints, axis-aligned, grazing the floor,
/// short segments, and a few invalid ones.
fn rays(n: usize, tris: &[Triangle], rng: &mut Rng) -> Vec<Ray> {
    (0..n)
        .map(|k| {
            let o = rng.v(match k % 3 {
                0 => 0.9,
                1 => 3.0,
                _ => 40.0,
            });
            let t = tris[rng.below(tris.len())];
            let (tmin, tmax) = match k % 5 {
                0 => (0.0, rng.f() * 2.0),
                1 => (rng.f() * 0.5, f32::INFINITY),
                _ => (0.0, f32::INFINITY),
            };
            let dir = match k % 7 {
                0 => rng.v(1.0) - o,
                1 => t.vertex(k % 3) - o,
                2 => (t.vertex(0) + t.vertex(1)) * 0.5 - o,
                3 => [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z][rng.below(6)],
                4 => Vec3::new(rng.f() - 0.5, 0.0, rng.f() - 0.5),
                5 => rng.v(1.0),
                _ => Vec3::new(1.0, 1.0, rng.f() - 0.5),
            };
            match k % 97 {
                13 => Ray::new(o, Vec3::ZERO, 0.0, 1.0),
                29 => Ray::new(o, dir, f32::NAN, 1.0),
                41 => Ray::new(o * 1e30, dir, 0.0, f32::INFINITY),
                _ => Ray::new(o, dir, tmin, tmax),
            }
        })
        .collect()
}

fn plain(ads: &Ads, tris: &[Triangle], rays: &[Ray], trav: Traversal) -> (Vec<Hit>, Vec<RayStats>) {
    rays.iter()
        .map(|r| {
            let mut s = RayStats::default();
            let h = trace_ray_plain(ads, tris, r, trav, &mut s);
            (h, s)
        })
        .unzip()
}

fn check(ads: &Ads, tris: &[Triangle], rays: &[Ray], what: &str) -> Result<(), TestCaseError> {
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let (want, want_stats) = plain(ads, tris, rays, trav);
        let (hits, stats) = trace_with_stats(ads, tris, rays, trav);
        let only = trace(ads, tris, rays, trav);
        let mut into = vec![Hit::MISS; rays.len()];
        let mut into_stats = vec![
            RayStats {
                views: 9,
                tiles: 9,
                buckets: 9,
                tests: 9
            };
            rays.len()
        ];
        trace_into(ads, tris, rays, trav, &mut into, Some(&mut into_stats));
        for i in 0..rays.len() {
            let ctx = || format!("{what} {trav:?} ray {i} {:?}", rays[i]);
            prop_assert_eq!(hits[i].bits(), want[i].bits(), "hit: {}", ctx());
            prop_assert_eq!(only[i].bits(), want[i].bits(), "trace: {}", ctx());
            prop_assert_eq!(into[i].bits(), want[i].bits(), "trace_into: {}", ctx());
            prop_assert_eq!(stats[i], want_stats[i], "stats: {}", ctx());
            prop_assert_eq!(into_stats[i], want_stats[i], "trace_into stats: {}", ctx());
        }
        for i in (0..rays.len()).step_by(17) {
            let mut s = RayStats::default();
            let h = trace_ray(ads, tris, &rays[i], trav, &mut s);
            prop_assert_eq!(h.bits(), want[i].bits());
            prop_assert_eq!(s, want_stats[i]);
        }
    }
    Ok(())
}

fn params() -> impl Strategy<Value = (AdsParams, bool)> {
    (
        prop_oneof![Just(ViewsKind::Cube), Just(ViewsKind::Single)],
        prop_oneof![
            Just((1u32, 1u32)),
            Just((5, 1)),
            Just((16, 1)),
            Just((24, 2)),
            Just((37, 1)),
            Just((64, 4)),
            Just((96, 3)),
            Just((128, 1))
        ],
        prop_oneof![Just(1u32), Just(2), Just(3), Just(8), Just(16)],
        prop_oneof![
            Just(None),
            Just(Some(Vec3::new(0.3, -0.2, 0.1))),
            Just(Some(Vec3::new(2.5, 0.4, -0.3))),
            Just(Some(Vec3::new(0.0, -0.9, 0.0)))
        ],
        any::<bool>(),
    )
        .prop_map(|(views, (resolution, tile), buckets, center, all)| {
            (
                AdsParams {
                    views,
                    resolution,
                    buckets,
                    tile,
                    center,
                },
                all,
            )
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn fast_path_is_the_plain_stage(seed in any::<u64>(), n in 1usize..150, (p, all) in params()) {
        let mut rng = Rng(seed);
        let tris = scene(n, &mut rng);
        let rs = rays(500, &tris, &mut rng);
        let ads = if all { Ads::build_all_views(&tris, &p) } else { Ads::build(&tris, &p) };
        let ads = ads.expect("valid parameters");
        check(&ads, &tris, &rs, &format!("{p:?} all views {all}"))?;
    }
}

// Batches of at least `ORDER_MIN_RAYS` (4096) rays are traced in a coherent
// order; the results must still come back in input order, bit for bit.
#[test]
fn large_batches_in_coherent_order_are_the_plain_stage() {
    let mut rng = Rng(99);
    let tris = scene(300, &mut rng);
    let rs = rays(6000, &tris, &mut rng);
    for views in [ViewsKind::Cube, ViewsKind::Single] {
        let p = AdsParams {
            views,
            resolution: 48,
            buckets: 4,
            tile: 1,
            center: None,
        };
        let ads = Ads::build(&tris, &p).expect("valid parameters");
        if let Err(e) = check(&ads, &tris, &rs, &format!("{p:?}")) {
            panic!("{e}");
        }
    }
}
