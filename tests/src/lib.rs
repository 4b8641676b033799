//! Shared helpers of the cross-crate tests: adversarial ray sets and the
//! exactness check against brute force.

use dirt_cpu::{Ads, AdsParams, Traversal, ViewsKind, brute_force, trace};
use dirt_math::{Aabb, Hit, Ray, Triangle, Vec3};

/// A small deterministic generator (PCG-style LCG), so every test is reproducible.
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    pub fn u32(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f32 {
        (self.u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.u32() as usize) % n.max(1)
    }
    pub fn in_box(&mut self, b: &Aabb) -> Vec3 {
        Vec3::new(
            self.range(b.min.x, b.max.x),
            self.range(b.min.y, b.max.y),
            self.range(b.min.z, b.max.z),
        )
    }
    pub fn dir(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.05 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// The kinds of rays every exactness test uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From a random point inside the bounds, random direction.
    Inside,
    /// From far outside the bounds towards a random point inside.
    Outside,
    /// Along ±X, ±Y, ±Z (zero direction components).
    AxisAligned,
    /// Aimed exactly at a vertex.
    ThroughVertex,
    /// Aimed at a point of an edge (shared edges of closed meshes).
    ThroughEdge,
    /// Lying in the plane of a triangle (edge-on, grazing).
    Grazing,
    /// From the cube centre, along seams and through corners of the cube faces.
    FromCenter,
    /// Segments ending before the geometry (occlusion rays, tmax-limited).
    Segment,
    /// Starting on a surface, with tmin > 0 against self-intersection.
    OnSurface,
}

pub const ALL_KINDS: [RayKind; 9] = [
    RayKind::Inside,
    RayKind::Outside,
    RayKind::AxisAligned,
    RayKind::ThroughVertex,
    RayKind::ThroughEdge,
    RayKind::Grazing,
    RayKind::FromCenter,
    RayKind::Segment,
    RayKind::OnSurface,
];

/// `n` rays of each kind for a scene.
pub fn adversarial_rays(tris: &[Triangle], n: usize, seed: u64) -> Vec<Ray> {
    let mut out = Vec::new();
    for k in ALL_KINDS {
        out.extend(rays_of_kind(
            tris,
            k,
            n,
            seed ^ (k as u64).wrapping_mul(0x9e37_79b9),
        ));
    }
    out
}

pub fn rays_of_kind(tris: &[Triangle], kind: RayKind, n: usize, seed: u64) -> Vec<Ray> {
    let b = Aabb::of_triangles(tris);
    let c = b.center();
    let ext = b.extent().max_element().max(1e-30);
    let mut rng = Rng(seed);
    let mut out = Vec::with_capacity(n);
    let axes = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    while out.len() < n {
        let t = tris[rng.below(tris.len())];
        let r = match kind {
            RayKind::Inside => Ray::new(rng.in_box(&b), rng.dir(), 0.0, f32::INFINITY),
            RayKind::Outside => {
                let o = c + rng.dir() * ext * rng.range(1.5, 4.0);
                Ray::new(o, rng.in_box(&b) - o, 0.0, f32::INFINITY)
            }
            RayKind::AxisAligned => {
                let o = if rng.f() < 0.5 {
                    rng.in_box(&b)
                } else {
                    t.vertex(rng.below(3))
                };
                Ray::new(
                    o - axes[rng.below(6)] * ext * rng.range(0.0, 2.0),
                    axes[rng.below(6)],
                    0.0,
                    f32::INFINITY,
                )
            }
            RayKind::ThroughVertex => {
                let o = if rng.f() < 0.5 {
                    rng.in_box(&b)
                } else {
                    c + rng.dir() * ext * 2.0
                };
                Ray::new(o, t.vertex(rng.below(3)) - o, 0.0, f32::INFINITY)
            }
            RayKind::ThroughEdge => {
                let o = if rng.f() < 0.5 {
                    rng.in_box(&b)
                } else {
                    c + rng.dir() * ext * 2.0
                };
                let e = rng.below(3);
                let (p, q) = (t.vertex(e), t.vertex((e + 1) % 3));
                let target = if rng.f() < 0.5 {
                    (p + q) * 0.5
                } else {
                    p + (q - p) * rng.f()
                };
                Ray::new(o, target - o, 0.0, f32::INFINITY)
            }
            RayKind::Grazing => {
                let e = rng.below(3);
                let d = t.vertex((e + 1) % 3) - t.vertex(e);
                let centroid = (t.vertex(0) + t.vertex(1) + t.vertex(2)) / 3.0;
                Ray::new(centroid - d * rng.range(0.5, 3.0), d, 0.0, f32::INFINITY)
            }
            RayKind::FromCenter => {
                let s = [-1.0f32, 0.0, 1.0];
                let mut d = Vec3::new(s[rng.below(3)], s[rng.below(3)], s[rng.below(3)]);
                if d == Vec3::ZERO {
                    d = rng.dir();
                } else if rng.f() < 0.3 {
                    d += rng.dir() * 1e-6;
                }
                Ray::new(c, d, 0.0, f32::INFINITY)
            }
            RayKind::Segment => {
                let o = rng.in_box(&b);
                let target = rng.in_box(&b);
                Ray::new(o, target - o, 0.0, rng.range(0.0, 1.0))
            }
            RayKind::OnSurface => {
                let (u, v) = (rng.f(), rng.f());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                let p =
                    t.vertex(0) + (t.vertex(1) - t.vertex(0)) * u + (t.vertex(2) - t.vertex(0)) * v;
                Ray::new(p, rng.dir(), ext * 1e-5, f32::INFINITY)
            }
        };
        if r.validate().is_ok() {
            out.push(r);
        }
    }
    out
}

/// The full parameter matrix of the exactness requirement.
pub fn param_matrix(resolution: u32) -> Vec<AdsParams> {
    let mut out = Vec::new();
    for views in [ViewsKind::Cube, ViewsKind::Single] {
        for buckets in [1, 8, 32] {
            for tile in [1, 2, 4] {
                out.push(AdsParams {
                    views,
                    resolution,
                    buckets,
                    tile,
                    center: None,
                });
            }
        }
    }
    out
}

/// Builds with `params`, traces with both traversals and returns a description
/// of every ray whose hit differs from `truth` in any bit.
pub fn mismatches(
    tris: &[Triangle],
    rays: &[Ray],
    truth: &[Hit],
    params: &AdsParams,
) -> Vec<String> {
    let ads = match Ads::build(tris, params) {
        Ok(a) => a,
        Err(e) => return vec![format!("{params:?}: build failed: {e}")],
    };
    let mut out = Vec::new();
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let hits = trace(&ads, tris, rays, trav);
        for (i, (h, g)) in hits.iter().zip(truth).enumerate() {
            if h.bits() != g.bits() {
                out.push(format!(
                    "{params:?} {trav:?} ray {i} {:?}: dirt {h:?} brute {g:?}",
                    rays[i]
                ));
            }
        }
    }
    out
}

/// Asserts exactness over the whole parameter matrix.
pub fn assert_exact_over_matrix(name: &str, tris: &[Triangle], rays: &[Ray], resolution: u32) {
    let truth = brute_force::trace(tris, rays);
    let hits = truth.iter().filter(|h| h.is_hit()).count();
    assert!(
        hits * 10 >= rays.len(),
        "{name}: only {hits} of {} rays hit; the test would prove little",
        rays.len()
    );
    let mut all = Vec::new();
    for p in param_matrix(resolution) {
        all.extend(mismatches(tris, rays, &truth, &p));
    }
    assert!(
        all.is_empty(),
        "{name}: {} mismatches, first: {}",
        all.len(),
        all.iter().take(5).cloned().collect::<Vec<_>>().join("\n")
    );
}

/// A closed UV sphere (shared edges and vertices everywhere).
pub fn uv_sphere(center: Vec3, r: f32, rings: u32, segs: u32) -> Vec<Triangle> {
    let p = |i: u32, j: u32| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = std::f32::consts::TAU * (j % segs) as f32 / segs as f32;
        center + Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..segs {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i != 0 {
                out.push(Triangle::new(a, b, d));
            }
            if i + 1 != rings {
                out.push(Triangle::new(b, c, d));
            }
        }
    }
    out
}

/// A grid of `n`×`n` quads (two triangles each) in the plane `z = z0`.
pub fn grid(n: u32, size: f32, z0: f32) -> Vec<Triangle> {
    let mut out = Vec::new();
    let s = size / n as f32;
    for j in 0..n {
        for i in 0..n {
            let p = |a: u32, b: u32| {
                Vec3::new(a as f32 * s - size * 0.5, b as f32 * s - size * 0.5, z0)
            };
            out.push(Triangle::new(p(i, j), p(i + 1, j), p(i + 1, j + 1)));
            out.push(Triangle::new(p(i, j), p(i + 1, j + 1), p(i, j + 1)));
        }
    }
    out
}

/// The shared GPU of the GPU tests, or `None` (said loudly) when no adapter
/// exists. With `DIRT_REQUIRE_GPU=1` (set by `.ci/run`) a missing adapter, or
/// one that is not lavapipe, fails instead.
pub fn gpu() -> Option<&'static dirt_gpu::Gpu> {
    use std::sync::OnceLock;
    static GPU: OnceLock<Option<dirt_gpu::Gpu>> = OnceLock::new();
    let required = std::env::var("DIRT_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let g = GPU.get_or_init(|| match dirt_gpu::Gpu::new() {
        Ok(g) => Some(g),
        Err(e) => {
            assert!(!required, "DIRT_REQUIRE_GPU=1 but: {e}");
            eprintln!("\n*** SKIPPING GPU TEST: {e} ***\n");
            None
        }
    });
    if let Some(g) = g {
        // Bits are only promised on the CI device.
        if !g.is_llvmpipe() || !g.exact {
            assert!(
                !required,
                "DIRT_REQUIRE_GPU=1 but the adapter is {} (NoContraction path: {}), not llvmpipe with it",
                g.describe(),
                g.exact
            );
            eprintln!(
                "\n*** SKIPPING BIT-EXACT GPU TEST: adapter {} is not llvmpipe with the NoContraction path ***\n",
                g.describe()
            );
            return None;
        }
    }
    g.as_ref()
}
