//! GPU == CPU, bit for bit, on lavapipe: depth bounds, Hi-Z levels, id lists
//! (as sets per list), hits and per-ray statistics, on random scenes and rays.

use dirt_cpu::{Ads, AdsParams, Traversal, ViewsKind, trace_with_stats};
use dirt_gpu::GpuAds;
use dirt_math::{Ray, Triangle, Vec3};
use dirt_tests::{Rng, adversarial_rays, gpu};
use proptest::prelude::*;

fn random_scene(seed: u64, n: usize, scale: f32) -> Vec<Triangle> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let c = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * scale;
            let s = scale * rng.range(0.01, 0.5);
            Triangle::new(c + rng.dir() * s, c + rng.dir() * s, c + rng.dir() * s)
        })
        .collect()
}

/// Every list as a sorted set.
fn sorted_lists(l: &dirt_cpu::IdLists) -> Vec<Vec<u32>> {
    l.offsets
        .windows(2)
        .map(|w| {
            let mut v = l.ids[w[0] as usize..w[1] as usize].to_vec();
            v.sort_unstable();
            v
        })
        .collect()
}

fn compare(tris: &[Triangle], rays: &[Ray], params: &AdsParams) -> Result<(), TestCaseError> {
    let Some(g) = gpu() else { return Ok(()) };
    let cpu = Ads::build(tris, params).expect("cpu build");
    let ads = GpuAds::build(g, tris, params).expect("gpu build");
    let hiz = ads.read_hiz(g).expect("read hi-z");
    prop_assert_eq!(hiz.len(), cpu.hiz.len());
    for (l, (a, b)) in hiz.iter().zip(&cpu.hiz).enumerate() {
        let bad = a.iter().zip(b).position(|(x, y)| x != y);
        prop_assert!(
            bad.is_none(),
            "Hi-Z level {} differs at cell {:?}: gpu {:?} cpu {:?}",
            l,
            bad,
            bad.map(|i| a[i]),
            bad.map(|i| b[i])
        );
    }
    let lists = ads.read_lists(g).expect("read lists");
    prop_assert_eq!(&lists.offsets, &cpu.lists.offsets, "list offsets differ");
    prop_assert!(
        sorted_lists(&lists) == sorted_lists(&cpu.lists),
        "list contents differ"
    );
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let (gh, gs) = dirt_gpu::trace::trace(g, &ads, rays, trav).expect("gpu trace");
        let (ch, cs) = trace_with_stats(&cpu, tris, rays, trav);
        for i in 0..rays.len() {
            prop_assert_eq!(
                gh[i].bits(),
                ch[i].bits(),
                "{:?} ray {} {:?}: gpu {:?} cpu {:?}",
                trav,
                i,
                rays[i],
                gh[i],
                ch[i]
            );
            prop_assert_eq!(gs[i], cs[i], "{:?} ray {} statistics", trav, i);
        }
    }
    Ok(())
}

fn params_strategy() -> impl Strategy<Value = AdsParams> {
    (
        prop::bool::ANY,
        prop::sample::select(vec![8u32, 16, 24, 32]),
        prop::sample::select(vec![1u32, 2, 8, 32]),
        prop::sample::select(vec![1u32, 2, 4]),
    )
        .prop_map(|(cube, res, buckets, tile)| AdsParams {
            views: if cube {
                ViewsKind::Cube
            } else {
                ViewsKind::Single
            },
            resolution: res,
            buckets,
            tile: if res % tile == 0 { tile } else { 1 },
            center: None,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn gpu_equals_cpu_bit_for_bit(seed in any::<u64>(), n in 1usize..80, scale in prop::sample::select(vec![1.0f32, 1e-3, 300.0]), params in params_strategy()) {
        let tris = random_scene(seed, n, scale);
        let rays = adversarial_rays(&tris, 6, seed ^ 0x5eed);
        compare(&tris, &rays, &params)?;
    }
}

#[test]
fn builtin_scenes_gpu_equals_cpu() {
    for name in ["cornell", "layers"] {
        let scene = dirt_scene::builtin(name).expect("built-in");
        let rays = adversarial_rays(&scene.triangles, 40, 9);
        for views in [ViewsKind::Cube, ViewsKind::Single] {
            let params = AdsParams {
                views,
                resolution: 64,
                buckets: 8,
                tile: 2,
                center: None,
            };
            compare(&scene.triangles, &rays, &params).expect("gpu == cpu");
        }
    }
}

#[test]
fn empty_scene_builds_and_misses() {
    let Some(g) = gpu() else { return };
    let ads = GpuAds::build(g, &[], &AdsParams::default()).expect("empty scene builds");
    let rays = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)];
    let (h, _) = dirt_gpu::trace::trace(g, &ads, &rays, Traversal::Linear).expect("trace");
    assert!(!h[0].is_hit());
}
