//! Exactness of `trace` against `brute_force` on random triangle soups.

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, brute_force, trace_with_stats};
use dirt_math::{Ray, Triangle, Vec3};

mod common;

use common::Rng;

fn soup(n: usize, rng: &mut Rng) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let c = rng.v(1.0);
            Triangle::new(c + rng.v(0.2), c + rng.v(0.2), c + rng.v(0.2))
        })
        .collect()
}

fn rays(n: usize, tris: &[Triangle], rng: &mut Rng) -> Vec<Ray> {
    (0..n)
        .map(|k| {
            let o = rng.v(if k % 2 == 0 { 0.9 } else { 3.0 });
            let target = match k % 4 {
                0 => rng.v(1.0),
                1 => tris[k % tris.len()].vertex(k % 3),
                2 => {
                    let t = tris[k % tris.len()];
                    (t.vertex(0) + t.vertex(1)) * 0.5
                }
                _ => o + [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X][k % 4],
            };
            Ray::new(o, target - o, 0.0, f32::INFINITY)
        })
        .collect()
}

#[test]
fn random_soup_matches_brute_force() {
    let mut rng = Rng(7);
    let tris = soup(400, &mut rng);
    let rs = rays(4000, &tris, &mut rng);
    let truth = brute_force::trace(&tris, &rs);
    assert!(truth.iter().filter(|h| h.is_hit()).count() > 1000);
    for views in [ViewsKind::Cube, ViewsKind::Single] {
        for (res, tile) in [(32, 1), (64, 2), (64, 4)] {
            for buckets in [1, 8, 32] {
                let ads = Ads::build(
                    &tris,
                    &AdsParams {
                        views,
                        resolution: res,
                        buckets,
                        tile,
                        center: None,
                    },
                )
                .expect("build");
                for trav in [Traversal::Linear, Traversal::HiZ] {
                    let (hits, stats) = trace_with_stats(&ads, &tris, &rs, trav);
                    let bad: Vec<usize> = (0..rs.len())
                        .filter(|&i| hits[i].bits() != truth[i].bits())
                        .collect();
                    let tests: u64 = stats.iter().map(|s| s.tests as u64).sum();
                    assert!(
                        bad.is_empty(),
                        "{views:?} res {res} S {tile} B {buckets} {trav:?}: {} mismatches, first ray {:?}: {:?} vs {:?}",
                        bad.len(),
                        rs[bad[0]],
                        hits[bad[0]],
                        truth[bad[0]]
                    );
                    eprintln!(
                        "{views:?} res {res} S {tile} B {buckets} {trav:?}: {:.1} tests/ray",
                        tests as f64 / rs.len() as f64
                    );
                }
            }
        }
    }
}

// The library's default, DirtCpu::auto: the cost model's parameters, chosen
// at the first build and kept while the triangle count stays; exact like any
// fixed setting.
#[test]
fn auto_chooses_once_per_triangle_count_and_stays_exact() {
    use dirt_core::Tracer;
    use dirt_cpu::DirtCpu;
    use dirt_cpu::brute_force::Brute;
    let mut rng = Rng(11);
    let tris = soup(300, &mut rng);
    let rs = rays(2000, &tris, &mut rng);
    let mut t = DirtCpu::auto(Some(Traversal::HiZ), 50_000);
    let first = t.build(&tris).expect("build");
    assert_eq!(first.stages.first().map(|s| s.0), Some("choose"));
    let choice = t.choice().expect("a choice after the build");
    let chosen = choice.best.params;
    assert_eq!(t.params, chosen);
    assert_eq!(choice.ranked.len() + choice.skipped, 36);
    // The winner built while choosing is the structure kept: no second build.
    assert_eq!(first.stages.len(), 1, "{:?}", first.stages);
    assert!(choice.best_ads.is_none(), "handed over to the tracer");
    assert!(t.name().contains("the cost model's "), "{}", t.name());
    let want = Brute::new(&tris).trace(&rs).expect("brute");
    assert_eq!(t.trace(&rs).expect("trace"), want);
    // Same count (the soup moved): no new choice, same parameters.
    let moved: Vec<Triangle> = tris
        .iter()
        .map(|t| {
            Triangle::new(
                t.vertex(0) + Vec3::X * 0.01,
                t.vertex(1),
                t.vertex(2) - Vec3::Y * 0.01,
            )
        })
        .collect();
    let second = t.build(&moved).expect("build");
    assert!(second.stages.iter().all(|s| s.0 != "choose"));
    assert_eq!(t.params, chosen);
    assert_eq!(
        t.trace(&rs).expect("trace"),
        Brute::new(&moved).trace(&rs).expect("brute")
    );
    // Another count: chosen again.
    let third = t.build(&tris[..100]).expect("build");
    assert_eq!(third.stages.first().map(|s| s.0), Some("choose"));
    // An empty scene builds, and every ray misses.
    t.build(&[]).expect("an empty scene builds");
    assert!(t.trace(&rs).expect("trace").iter().all(|h| !h.is_hit()));
}

// DirtCpu::auto without a traversal: the faster one is timed at the choice
// and kept with it; exact either way.
#[test]
fn auto_without_a_traversal_times_both_and_stays_exact() {
    use dirt_core::Tracer;
    use dirt_cpu::DirtCpu;
    use dirt_cpu::brute_force::Brute;
    let mut rng = Rng(12);
    let tris = soup(300, &mut rng);
    let rs = rays(2000, &tris, &mut rng);
    let mut t = DirtCpu::auto(None, 50_000);
    assert!(t.traversal_choice().is_none(), "timed at the first build");
    let first = t.build(&tris).expect("build");
    assert_eq!(first.stages.first().map(|s| s.0), Some("choose"));
    let timed = *t.traversal_choice().expect("timed at the choice");
    assert_eq!(timed.rays, dirt_cpu::tracer::TRAVERSAL_SAMPLE);
    assert!(timed.linear > std::time::Duration::ZERO && timed.hiz > std::time::Duration::ZERO);
    assert_eq!(t.traversal, timed.traversal);
    assert!(
        t.name().contains(&timed.traversal.to_string()),
        "{}",
        t.name()
    );
    assert_eq!(
        t.trace(&rs).expect("trace"),
        Brute::new(&tris).trace(&rs).expect("brute")
    );
    // Same count: neither choice is made again.
    t.build(&tris).expect("build");
    assert_eq!(t.traversal_choice(), Some(&timed));
    // With a traversal given, nothing is timed.
    let mut fixed = DirtCpu::auto(Some(Traversal::Linear), 50_000);
    fixed.build(&tris).expect("build");
    assert!(fixed.traversal_choice().is_none());
    assert_eq!(fixed.traversal, Traversal::Linear);
}
