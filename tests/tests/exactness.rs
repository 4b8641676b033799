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
