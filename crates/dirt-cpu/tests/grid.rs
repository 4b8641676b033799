//! The compact uniform grid against brute force: the same hit bits on random
//! scenes and rays at several densities, on shared edges, grazing rays,
//! stacked full-size triangles, far origins (traced against every triangle)
//! and scenes of every scale; and its structure (two passes, ascending ids,
//! `ρ·N` cells) and errors.

use dirt_core::{CoreError, Tracer};
use dirt_cpu::brute_force;
use dirt_cpu::grid::{DEFAULT_DENSITY, Grid};
use dirt_math::{Hit, Ray, Triangle, Vec3};
use proptest::prelude::*;

mod common;

use common::{Rng, rays, scene};

fn check(tris: &[Triangle], rays: &[Ray], density: f32, what: &str) -> Result<(), TestCaseError> {
    let truth = brute_force::trace(tris, rays);
    let mut g = Grid::built(tris, density).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let hits = g
        .trace(rays)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    for (i, (h, t)) in hits.iter().zip(&truth).enumerate() {
        prop_assert_eq!(
            h.bits(),
            t.bits(),
            "{} ρ{} ray {} {:?}: grid {:?} brute {:?}",
            what,
            density,
            i,
            rays[i],
            h,
            t
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn the_grid_equals_brute_force(seed in any::<u64>(), n in 1usize..150, density in prop::sample::select(vec![0.25f32, 1.0, 4.0, 16.0])) {
        let mut rng = Rng(seed);
        let tris = scene(n, &mut rng);
        let rs = rays(400, &tris, &mut rng);
        check(&tris, &rs, density, "random")?;
        // The same scene scaled and moved far away.
        for (s, off) in [(1e-4f32, Vec3::new(3e-5, 0.0, -1e-5)), (1e4, Vec3::new(2e5, -1e5, 0.0))] {
            let moved: Vec<Triangle> = tris
                .iter()
                .map(|t| Triangle::new(t.vertex(0) * s + off, t.vertex(1) * s + off, t.vertex(2) * s + off))
                .collect();
            let rs: Vec<Ray> = rs
                .iter()
                .map(|r| Ray::new(r.origin() * s + off, r.dir(), r.tmin * s, r.tmax * s))
                .collect();
            check(&moved, &rs, density, "scaled")?;
        }
    }
}

#[test]
fn stacked_full_size_triangles_and_axis_rays() {
    // 64 parallel squares one behind the other, each in every cell of its slab.
    let mut tris = Vec::new();
    for k in 0..64 {
        let z = k as f32 * 0.1;
        let (a, b, c, d) = (
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        );
        tris.push(Triangle::new(a, b, c));
        tris.push(Triangle::new(a, c, d));
    }
    let mut rng = Rng(7);
    let mut rs = Vec::new();
    for _ in 0..500 {
        let o = Vec3::new(
            rng.f() * 2.4 - 1.2,
            rng.f() * 2.4 - 1.2,
            -3.0 + rng.f() * 10.0,
        );
        // Along +z, -z, and through the shared diagonal of each square.
        rs.push(Ray::new(o, Vec3::Z, 0.0, f32::INFINITY));
        rs.push(Ray::new(o, -Vec3::Z, 0.0, f32::INFINITY));
        let on_diag = Vec3::new(o.x, o.x, o.z);
        rs.push(Ray::new(
            on_diag,
            Vec3::new(0.0, 0.0, 1.0),
            0.0,
            f32::INFINITY,
        ));
        // Grazing: in the plane of a square.
        rs.push(Ray::new(
            Vec3::new(-2.0, o.y, 0.3),
            Vec3::X,
            0.0,
            f32::INFINITY,
        ));
    }
    for density in [1.0, DEFAULT_DENSITY, 32.0] {
        check(&tris, &rs, density, "stacked").expect("exact");
    }
}

#[test]
fn far_origins_are_traced_against_everything_and_stay_exact() {
    let mut rng = Rng(3);
    let tris = scene(40, &mut rng);
    let rs: Vec<Ray> = (0..200)
        .map(|_| {
            let target = tris[rng.below(tris.len())].vertex(0);
            let o = rng.v(1.0).normalize_or_zero() * 1e4;
            Ray::new(o, target - o, 0.0, f32::INFINITY)
        })
        .collect();
    check(&tris, &rs, DEFAULT_DENSITY, "far").expect("exact");
    let g = Grid::built(&tris, DEFAULT_DENSITY).expect("build");
    for r in &rs {
        g.trace_ray(r);
    }
    assert_eq!(
        g.fallbacks(),
        rs.len() as u64,
        "origins 1e4 away from a scene of size 1"
    );
    // Origins near the scene take the grid.
    let near = rays(100, &tris, &mut rng);
    let g = Grid::built(&tris, DEFAULT_DENSITY).expect("build");
    let valid = near
        .iter()
        .filter(|r| r.validate().is_ok() && r.origin().abs().max_element() < 50.0);
    for r in valid {
        g.trace_ray(r);
    }
    assert_eq!(g.fallbacks(), 0);
}

#[test]
fn the_structure_is_compact_and_ordered() {
    let mut rng = Rng(11);
    let tris = scene(500, &mut rng);
    let g = Grid::built(&tris, DEFAULT_DENSITY).expect("build");
    let cells: u64 = g.dims().iter().map(|&d| u64::from(d)).product();
    // ρ·N cells, give or take the rounding up of each axis.
    let n = tris.len() as f64 * f64::from(DEFAULT_DENSITY);
    assert!(
        cells as f64 >= 0.5 * n && (cells as f64) <= 3.0 * n,
        "{cells} cells for ρN = {n}"
    );
    assert_eq!(g.memory_bytes(), 4 * (cells + 1 + g.references() as u64));
    assert!(g.references() >= tris.len());
    // A rebuild of other triangles forgets the first.
    let mut g = g;
    let fewer = &tris[..10];
    g.build(fewer).expect("rebuild");
    let rs = rays(200, fewer, &mut rng);
    check(fewer, &rs, DEFAULT_DENSITY, "rebuilt").expect("exact");
    assert_eq!(
        g.trace(&rs)
            .expect("trace")
            .iter()
            .map(Hit::bits)
            .collect::<Vec<_>>(),
        brute_force::trace(fewer, &rs)
            .iter()
            .map(Hit::bits)
            .collect::<Vec<_>>()
    );
}

#[test]
fn bad_input_is_refused_and_empty_scenes_miss() {
    let r = Ray::new(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY);
    let mut unbuilt = Grid::new(1.0).expect("density 1");
    assert!(matches!(
        unbuilt.trace(&[r]),
        Err(CoreError::NotBuilt { .. })
    ));
    for d in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(
            matches!(Grid::new(d), Err(CoreError::InvalidParams(_))),
            "density {d}"
        );
    }
    let mut tris = vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 3];
    tris[2].v[1][0] = f32::NAN;
    assert!(matches!(
        Grid::built(&tris, 1.0),
        Err(CoreError::NonFiniteTriangle { index: 2 })
    ));
    let mut g = Grid::built(&[], 1.0).expect("empty");
    assert_eq!(g.trace(&[r]).expect("trace")[0].bits(), Hit::MISS.bits());
    // A density whose references would not fit is refused by name.
    let big: Vec<Triangle> = (0..5000)
        .map(|k| {
            let z = k as f32 * 1e-4;
            Triangle::new(
                Vec3::new(-1e3, -1e3, z),
                Vec3::new(1e3, -1e3, z),
                Vec3::new(0.0, 1e3, z),
            )
        })
        .collect();
    match Grid::built(&big, 1e6) {
        Err(e) => assert!(e.to_string().contains("cell references"), "{e}"),
        Ok(g) => panic!("built with {} references", g.references()),
    }
}
