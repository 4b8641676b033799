//! Criterion benches of the hot CPU stages on a fixed procedural scene:
//! `fill_depth`, `mip_depth`, `fill_primitives`, and `trace` (linear and
//! Hi-Z). `cargo bench -p dirt-cpu`; `dirt eval` reports the same stages
//! over scenes and parameters.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dirt_core::{AdsParams, Traversal};
use dirt_cpu::Ads;
use dirt_math::{Ray, Triangle, Vec3};
use std::hint::black_box;

/// A deterministic stream (64-bit LCG, top 24 bits) so the scene never changes.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    fn point(&mut self) -> Vec3 {
        Vec3::new(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        )
    }
}

/// A wavy floor of 2·n² triangles plus `n²/4` small random triangles above it:
/// a floor seen from inside and clutter in depth.
fn scene(n: usize) -> Vec<Triangle> {
    let mut rng = Lcg(7);
    let h = |i: usize, j: usize| {
        let x = -1.0 + 2.0 * i as f32 / n as f32;
        let z = -1.0 + 2.0 * j as f32 / n as f32;
        Vec3::new(x, -0.8 + 0.1 * (5.0 * x).sin() * (4.0 * z).cos(), z)
    };
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            tris.push(Triangle::new(h(i, j), h(i + 1, j), h(i + 1, j + 1)));
            tris.push(Triangle::new(h(i, j), h(i + 1, j + 1), h(i, j + 1)));
        }
    }
    for _ in 0..n * n / 4 {
        let c = rng.point();
        let s = 0.05;
        let v = |r: &mut Lcg| c + Vec3::new(r.range(-s, s), r.range(-s, s), r.range(-s, s));
        tris.push(Triangle::new(v(&mut rng), v(&mut rng), v(&mut rng)));
    }
    tris
}

fn rays(count: usize) -> Vec<Ray> {
    let mut rng = Lcg(11);
    (0..count)
        .map(|_| {
            let o = rng.point() * 0.9;
            let d = rng.point();
            Ray::new(o, d, 0.0, f32::INFINITY)
        })
        .filter(|r| r.validate().is_ok())
        .collect()
}

fn stages(c: &mut Criterion) {
    let tris = scene(48);
    let params = AdsParams::default();
    let views = dirt_core::views_for(&tris, &params).expect("valid parameters");
    let depth = dirt_cpu::fill_depth::fill_depth(&views, &tris);
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("fill_depth", |b| {
        b.iter(|| dirt_cpu::fill_depth::fill_depth(black_box(&views), black_box(&tris)))
    });
    g.bench_function("mip_depth", |b| {
        b.iter(|| dirt_cpu::mip_depth::mip_depth(black_box(&views), black_box(&depth)))
    });
    g.bench_function("fill_primitives", |b| {
        b.iter(|| {
            dirt_cpu::fill_primitives::fill_primitives(
                black_box(&views),
                black_box(&depth),
                params.buckets,
                black_box(&tris),
            )
        })
    });
    g.finish();

    let ads = Ads::build(&tris, &params).expect("valid parameters");
    let rays = rays(4096);
    let mut g = c.benchmark_group("trace");
    g.sample_size(10);
    g.throughput(Throughput::Elements(rays.len() as u64));
    for (name, t) in [("linear", Traversal::Linear), ("hiz", Traversal::HiZ)] {
        g.bench_with_input(BenchmarkId::from_parameter(name), &t, |b, &t| {
            b.iter(|| dirt_cpu::trace(black_box(&ads), black_box(&tris), black_box(&rays), t))
        });
    }
    g.finish();
}

criterion_group!(benches, stages);
criterion_main!(benches);
