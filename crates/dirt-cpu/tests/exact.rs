//! Exactness of `trace` against `brute_force` on random triangle soups.

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, brute_force, trace_with_stats};
use dirt_math::view::Axis;
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
    for views in ViewsKind::ALL {
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
                        axis: None,
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
/// Orthographic views along every axis, one or split (at the centre, off
/// it, outside the bounds), through both traversals: brute force's hits.
#[test]
fn orthographic_views_along_every_axis_match_brute_force() {
    let mut rng = Rng(11);
    let tris = soup(300, &mut rng);
    let rs = rays(3000, &tris, &mut rng);
    let truth = brute_force::trace(&tris, &rs);
    let cuts = [None, Some(Vec3::splat(0.37)), Some(Vec3::splat(-40.0))];
    for axis in Axis::ALL {
        for (views, center) in [(ViewsKind::Ortho, None)]
            .into_iter()
            .chain(cuts.map(|c| (ViewsKind::OrthoSplit, c)))
        {
            let params = AdsParams {
                views,
                resolution: 32,
                buckets: 4,
                tile: 1,
                center,
                axis: Some(axis),
            };
            let ads = Ads::build(&tris, &params).expect("build");
            for trav in [Traversal::Linear, Traversal::HiZ] {
                let hits = dirt_cpu::trace(&ads, &tris, &rs, trav);
                let bad = (0..rs.len())
                    .filter(|&i| hits[i].bits() != truth[i].bits())
                    .count();
                assert_eq!(bad, 0, "{params:?} {trav:?}");
                let (counted, _) = trace_with_stats(&ads, &tris, &rs, trav);
                assert!(
                    counted
                        .iter()
                        .zip(&truth)
                        .all(|(a, b)| a.bits() == b.bits())
                );
                // The plain stage (the specification) on every tenth ray.
                for (r, t) in rs.iter().zip(&truth).step_by(10) {
                    let mut st = Default::default();
                    let h = dirt_cpu::trace::trace_ray_plain(&ads, &tris, r, trav, &mut st);
                    assert_eq!(h.bits(), t.bits(), "{params:?} {trav:?} {r:?}");
                }
            }
        }
    }
}

/// Not placed at a point the rays start from: no centre, or the split
/// orthographic views, whose centre is a point of their cut.
fn placed_as_by_default(p: &AdsParams) -> bool {
    p.center.is_none() || p.views == ViewsKind::OrthoSplit
}

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
    assert_eq!(
        choice.ranked.len() + choice.skipped,
        dirt_cpu::cost::candidates_all(&AdsParams::default(), &tris).len()
    );
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

/// Rays from `eye` towards random points of the soup's box.
fn rays_from(eye: Vec3, n: usize, rng: &mut Rng) -> Vec<Ray> {
    (0..n)
        .map(|_| {
            let target = rng.v(1.2);
            Ray::new(eye, target - eye, 0.0, f32::INFINITY)
        })
        .collect()
}

// Views placed where a frame's rays start (cost::candidates_at): the cube
// centred there, and the single view from there where it sees the whole
// scene, are exact for every ray, from anywhere. A single view from an eye
// that does not see all (inside the scene) is not offered, and would miss.
#[test]
fn views_placed_at_an_origin_are_exact_where_they_are_offered() {
    use dirt_cpu::cost::candidates_at;
    use dirt_math::Aabb;
    use dirt_math::view::single_sees_all;
    let mut rng = Rng(21);
    let tris = soup(300, &mut rng);
    let bounds = Aabb::of_triangles(&tris);
    let mut seen_all = 0;
    for eye in [
        Vec3::new(0.0, 0.5, 6.0),
        Vec3::new(-4.0, 3.0, 2.5),
        Vec3::new(2.2, 2.0, 2.0),
        Vec3::new(0.3, 0.2, 0.1),
    ] {
        let mut rs = rays(1500, &tris, &mut rng);
        rs.extend(rays_from(eye, 1500, &mut rng));
        let truth = brute_force::trace(&tris, &rs);
        let sees_all = single_sees_all(eye, &bounds);
        seen_all += usize::from(sees_all);
        let offered = candidates_at(eye, &bounds);
        let count = |v: ViewsKind| offered.iter().filter(|p| p.views == v).count();
        assert_eq!(count(ViewsKind::Cube), 30, "{eye}");
        assert_eq!(
            count(ViewsKind::Single),
            if sees_all { 30 } else { 0 },
            "{eye}"
        );
        assert!(offered.iter().all(|p| p.center == Some(eye)));
        for p in offered
            .iter()
            .filter(|p| [1, 8].contains(&p.buckets) && [16, 64].contains(&p.resolution))
        {
            let ads = Ads::build(&tris, p).expect("build");
            for trav in [Traversal::Linear, Traversal::HiZ] {
                let (hits, _) = trace_with_stats(&ads, &tris, &rs, trav);
                let bad = (0..rs.len())
                    .filter(|&i| hits[i].bits() != truth[i].bits())
                    .count();
                assert_eq!(bad, 0, "{:?} r{} at {eye} {trav:?}", p.views, p.resolution);
            }
        }
        if !sees_all {
            // What the check keeps out: the single view there loses hits.
            let p = AdsParams {
                views: ViewsKind::Single,
                resolution: 64,
                center: Some(eye),
                ..AdsParams::default()
            };
            let ads = Ads::build(&tris, &p).expect("build");
            let (hits, _) = trace_with_stats(&ads, &tris, &rs, Traversal::HiZ);
            let bad = (0..rs.len())
                .filter(|&i| hits[i].bits() != truth[i].bits())
                .count();
            assert!(bad > 0, "the single view at {eye} lost nothing");
        }
    }
    assert!(seen_all >= 2, "{seen_all} eyes see the whole soup");
    assert!(!single_sees_all(Vec3::NAN, &bounds));
}

// DirtCpu::auto told where the rays start: the views placed there are
// candidates too, a choice placed there follows the origin when it moves,
// and the hits stay exact; a non-finite origin is an error.
#[test]
fn auto_with_an_origin_weighs_views_there_and_follows_it() {
    use dirt_core::Tracer;
    use dirt_cpu::DirtCpu;
    use dirt_cpu::brute_force::Brute;
    let mut rng = Rng(22);
    let tris = soup(300, &mut rng);
    let eye = Vec3::new(0.0, 0.5, 6.0);
    let mut t = DirtCpu::auto(Some(Traversal::HiZ), 1_000_000).with_origin(eye);
    t.build(&tris).expect("build");
    let choice = t.choice().expect("a choice");
    // Only views at the eye are weighed: the cube and (it sees the whole soup) the single view.
    assert_eq!(choice.ranked.len() + choice.skipped, 60);
    assert!(choice.ranked.iter().all(|c| c.params.center == Some(eye)));
    assert_eq!(t.params.center, Some(eye));
    assert!(t.name().ends_with("at the rays' origin)"), "{}", t.name());
    let mut rs = rays_from(eye, 2000, &mut rng);
    rs.extend(rays(1000, &tris, &mut rng));
    let brute = Brute::new(&tris).trace(&rs).expect("brute");
    assert_eq!(t.trace(&rs).expect("trace"), brute);
    let chosen = t.params;
    // The camera moves: a choice placed at the eye moves with it, unchosen.
    let eye2 = Vec3::new(-1.0, 0.8, 5.5);
    t.set_origin(Some(eye2));
    let moved = t.build(&tris).expect("build");
    assert!(moved.stages.iter().all(|s| s.0 != "choose"));
    assert_eq!(t.params.center, Some(eye2));
    assert_eq!(
        (t.params.views, t.params.resolution),
        (chosen.views, chosen.resolution)
    );
    assert_eq!(t.trace(&rs).expect("trace"), brute);
    // Into the scene: a single view cannot see all from there; the cube still can.
    let inside = Vec3::new(0.1, 0.0, 0.2);
    t.set_origin(Some(inside));
    let again = t.build(&tris).expect("build");
    assert_eq!(t.params.center, Some(inside));
    if chosen.views == ViewsKind::Single {
        assert_eq!(again.stages.first().map(|s| s.0), Some("choose"));
    }
    assert_eq!(t.params.views, ViewsKind::Cube);
    assert_eq!(t.trace(&rs).expect("trace"), brute);
    // No origin any more: chosen again, placed as by default.
    t.set_origin(None);
    let plain = t.build(&tris).expect("build");
    assert_eq!(plain.stages.first().map(|s| s.0), Some("choose"));
    assert!(placed_as_by_default(&t.params), "{:?}", t.params);
    assert_eq!(t.trace(&rs).expect("trace"), brute);
    // And kept at the next build.
    let kept = t.build(&tris).expect("build");
    assert!(kept.stages.iter().all(|s| s.0 != "choose"));
    // A non-finite origin is refused, not traced.
    t.set_origin(Some(Vec3::new(f32::NAN, 0.0, 0.0)));
    let err = t.build(&tris).expect_err("a NaN origin");
    assert!(err.to_string().contains("not finite"), "{err}");
}

// DirtCpu::auto watches the rays it traces: once every ray of a frame starts
// at one point, the next build chooses among views placed there, and later
// builds move them with the point; rays from many points take it back to the
// default placement. Exact throughout.
#[test]
fn auto_places_its_views_where_the_traced_rays_start() {
    use dirt_core::Tracer;
    use dirt_cpu::DirtCpu;
    use dirt_cpu::brute_force::Brute;
    let mut rng = Rng(23);
    let tris = soup(300, &mut rng);
    let mut brute = Brute::new(&tris);
    let eye = Vec3::new(0.0, 0.5, 6.0);
    let mut t = DirtCpu::auto(Some(Traversal::HiZ), 1_000_000);
    let first = t.build(&tris).expect("build");
    assert_eq!(first.stages.first().map(|s| s.0), Some("choose"));
    assert!(placed_as_by_default(&t.params), "{:?}", t.params);
    let camera = rays_from(eye, 2000, &mut rng);
    assert_eq!(
        t.trace(&camera).expect("trace"),
        brute.trace(&camera).expect("brute")
    );
    // Frame 1: every ray of frame 0 started at the eye.
    let second = t.build(&tris).expect("build");
    assert_eq!(second.stages.first().map(|s| s.0), Some("choose"));
    assert_eq!(t.params.center, Some(eye));
    let counted = t.choice().expect("a choice");
    assert_eq!(counted.ranked.len() + counted.skipped, 60);
    // The camera moves; this frame's rays come in two batches: the next
    // build moves the views with it, unchosen.
    let eye2 = Vec3::new(-1.0, 0.8, 5.5);
    let moved = rays_from(eye2, 1000, &mut rng);
    for half in moved.chunks(500) {
        assert_eq!(
            t.trace(half).expect("trace"),
            brute.trace(half).expect("brute")
        );
    }
    let third = t.build(&tris).expect("build");
    assert!(
        third.stages.iter().all(|s| s.0 != "choose"),
        "{:?}",
        third.stages
    );
    assert_eq!(t.params.center, Some(eye2));
    assert_eq!(
        t.trace(&moved).expect("trace"),
        brute.trace(&moved).expect("brute")
    );
    // A batch from elsewhere among them: no common origin, chosen again as by default.
    let mixed = rays(1000, &tris, &mut rng);
    t.trace(&mixed).expect("trace");
    let fourth = t.build(&tris).expect("build");
    assert_eq!(fourth.stages.first().map(|s| s.0), Some("choose"));
    assert!(placed_as_by_default(&t.params), "{:?}", t.params);
    assert_eq!(
        t.trace(&mixed).expect("trace"),
        brute.trace(&mixed).expect("brute")
    );
    // Told where the rays start (anywhere), it stops watching.
    t.set_origin(None);
    t.trace(&camera).expect("trace");
    let fifth = t.build(&tris).expect("build");
    assert!(fifth.stages.iter().all(|s| s.0 != "choose"));
    assert!(placed_as_by_default(&t.params), "{:?}", t.params);
}
