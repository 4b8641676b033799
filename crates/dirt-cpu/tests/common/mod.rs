//! Random scenes and rays shared by the integration tests of `dirt-cpu`.
#![allow(dead_code)]

use dirt_math::{Ray, Triangle, Vec3};

/// A deterministic stream (64-bit LCG, top 24 bits).
pub struct Rng(pub u64);

impl Rng {
    pub fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.f() * n as f32) as usize).min(n - 1)
    }
    pub fn v(&mut self, s: f32) -> Vec3 {
        Vec3::new(
            self.f() * 2.0 - 1.0,
            self.f() * 2.0 - 1.0,
            self.f() * 2.0 - 1.0,
        ) * s
    }
}

/// Small random triangles, a grid of shared edges (a floor) and a few
/// degenerate and large ones.
pub fn scene(n: usize, rng: &mut Rng) -> Vec<Triangle> {
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
pub fn rays(n: usize, tris: &[Triangle], rng: &mut Rng) -> Vec<Ray> {
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
