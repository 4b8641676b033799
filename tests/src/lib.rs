//! Shared helpers of the cross-crate tests: adversarial ray sets and the
//! exactness check against brute force.

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, brute_force, trace};
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

/// `n` random triangles of sizes 1–50 % of `scale` in a box of half-size `scale`.
pub fn random_scene(seed: u64, n: usize, scale: f32) -> Vec<Triangle> {
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
                    axis: None,
                });
            }
        }
    }
    out.extend(ortho_params(resolution, [(1, 1), (8, 2), (32, 4)]));
    out
}

/// The orthographic sets (one view, then two split) at `resolution`, on
/// each `(B, S)` pair, looking along the bounds' thinnest axis.
pub fn ortho_params(resolution: u32, pairs: [(u32, u32); 3]) -> Vec<AdsParams> {
    [ViewsKind::Ortho, ViewsKind::OrthoSplit]
        .into_iter()
        .flat_map(|views| {
            pairs.map(|(buckets, tile)| AdsParams {
                views,
                resolution,
                buckets,
                tile,
                ..AdsParams::default()
            })
        })
        .collect()
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

/// Where the compact uniform grid (`dirt_cpu::grid`, the exact baseline) at
/// densities 1, 4 and 16 differs from `truth` in any bit.
pub fn grid_mismatches(tris: &[Triangle], rays: &[Ray], truth: &[Hit]) -> Vec<String> {
    let mut out = Vec::new();
    for density in [1.0, dirt_cpu::grid::DEFAULT_DENSITY, 16.0] {
        let g = match dirt_cpu::grid::Grid::built(tris, density) {
            Ok(g) => g,
            Err(e) => {
                out.push(format!("grid ρ{density}: build failed: {e}"));
                continue;
            }
        };
        for (i, (r, t)) in rays.iter().zip(truth).enumerate() {
            let h = g.trace_ray(r);
            if h.bits() != t.bits() {
                out.push(format!(
                    "grid ρ{density} ray {i} {r:?}: grid {h:?} brute {t:?}"
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
    all.extend(grid_mismatches(tris, rays, &truth));
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

/// The reduced matrix of the robustness cases: views {cube, single} × three
/// (B, S) pairs, then {ortho, ortho2} × three; `trace` is then run with both traversals. `center` is used for
/// the cube only (a single view with a centre sees only its frustum).
pub fn robust_matrix(resolution: u32, center: Option<Vec3>) -> Vec<AdsParams> {
    let mut out = Vec::new();
    for views in [ViewsKind::Cube, ViewsKind::Single] {
        for (buckets, tile) in [(8, 1), (1, 2), (32, 4)] {
            out.push(AdsParams {
                views,
                resolution,
                buckets,
                tile,
                center: if views == ViewsKind::Cube {
                    center
                } else {
                    None
                },
                axis: None,
            });
        }
    }
    out.extend(ortho_params(resolution, [(8, 1), (1, 2), (32, 4)]));
    out
}

/// Asserts that CPU DIRT equals brute force bit for bit on every ray for
/// every parameter set, and returns brute force's hits.
pub fn assert_exact(name: &str, tris: &[Triangle], rays: &[Ray], params: &[AdsParams]) -> Vec<Hit> {
    let truth = brute_force::trace(tris, rays);
    let mut all = Vec::new();
    for p in params {
        all.extend(mismatches(tris, rays, &truth, p));
    }
    all.extend(grid_mismatches(tris, rays, &truth));
    assert!(
        all.is_empty(),
        "{name}: {} mismatches, first: {}",
        all.len(),
        all.iter().take(5).cloned().collect::<Vec<_>>().join("\n")
    );
    truth
}

/// Rays from a closed mesh's triangles that leave its surface or start on it:
/// the number of brute-force hits among `hits` (for "the test proves something" checks).
pub fn hit_count(hits: &[Hit]) -> usize {
    hits.iter().filter(|h| h.is_hit()).count()
}

/// How GPU DIRT differs from CPU DIRT on one scene, rays and parameters.
#[derive(Clone, Debug, Default)]
pub struct GpuDiff {
    /// Hi-Z levels and id lists (compared as sets).
    pub structure: Vec<String>,
    /// Rays whose hit differs in any bit (either traversal).
    pub hits: Vec<String>,
    /// Rays whose hit is the same but whose statistics differ.
    pub stats: Vec<String>,
}

impl GpuDiff {
    pub fn is_empty(&self) -> bool {
        self.structure.is_empty() && self.hits.is_empty() && self.stats.is_empty()
    }
    pub fn summary(&self) -> String {
        let first: Vec<&String> = self
            .structure
            .iter()
            .chain(&self.hits)
            .chain(&self.stats)
            .take(3)
            .collect();
        format!(
            "{} structure, {} hit and {} statistics differences; first: {first:?}",
            self.structure.len(),
            self.hits.len(),
            self.stats.len()
        )
    }
}

/// Compares GPU DIRT with CPU DIRT: Hi-Z levels, id lists as sets, and hits
/// and statistics with both traversals. `None` when the running test is
/// skipped: a bit comparison needs [`dirt_gpu::testing::exact_gpu`].
pub fn gpu_differences(tris: &[Triangle], rays: &[Ray], params: &AdsParams) -> Option<GpuDiff> {
    let g = dirt_gpu::testing::exact_gpu(&dirt_gpu::testing::current_test_name())?;
    let ads = dirt_gpu::GpuAds::build(g, tris, params).expect("gpu build");
    Some(gpu_differences_of(g, &ads, tris, rays))
}

/// [`gpu_differences`] of a structure `ads` already built on `g` (an exact
/// context: the caller checks), by either build path.
pub fn gpu_differences_of(
    g: &dirt_gpu::Gpu,
    ads: &dirt_gpu::GpuAds,
    tris: &[Triangle],
    rays: &[Ray],
) -> GpuDiff {
    let params = &ads.params;
    let cpu = Ads::build(tris, params).expect("cpu build");
    let mut out = GpuDiff::default();
    let hiz = ads.read_hiz(g).expect("read hi-z");
    for (l, (a, b)) in hiz.iter().zip(&cpu.hiz).enumerate() {
        let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
        if differ > 0 || a.len() != b.len() {
            out.structure
                .push(format!("{params:?} Hi-Z level {l}: {differ} cells differ"));
        }
    }
    let lists = ads.read_lists(g).expect("read lists");
    let sorted = |l: &dirt_core::IdLists| -> Vec<Vec<u32>> {
        l.offsets
            .windows(2)
            .map(|w| {
                let mut v = l.ids[w[0] as usize..w[1] as usize].to_vec();
                v.sort_unstable();
                v
            })
            .collect()
    };
    if lists.offsets != cpu.lists.offsets || sorted(&lists) != sorted(&cpu.lists) {
        out.structure.push(format!("{params:?}: id lists differ"));
    }
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let traced = dirt_gpu::trace::trace_report(g, ads, rays, trav).expect("gpu trace");
        let (ch, cs) = dirt_cpu::trace_with_stats(&cpu, tris, rays, trav);
        for i in 0..rays.len() {
            let line = || {
                format!(
                    "{params:?} {trav:?} ray {i} {:?}: gpu {:?} {:?} cpu {:?} {:?}",
                    rays[i], traced.hits[i], traced.stats[i], ch[i], cs[i]
                )
            };
            if traced.hits[i].bits() != ch[i].bits() {
                out.hits.push(line());
            } else if traced.stats[i] != cs[i] {
                out.stats.push(line());
            }
        }
    }
    out
}

/// Asserts GPU == CPU in everything [`gpu_differences`] compares; skipped (and
/// said) off the exact path.
pub fn assert_gpu_equals_cpu(name: &str, tris: &[Triangle], rays: &[Ray], params: &AdsParams) {
    if let Some(d) = gpu_differences(tris, rays, params) {
        assert!(
            d.is_empty(),
            "{name}: GPU differs from CPU: {}",
            d.summary()
        );
    }
}

/// An indexed triangle mesh: shared vertices are the same `f32` values.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn triangles(&self) -> Vec<Triangle> {
        self.faces
            .iter()
            .map(|f| {
                Triangle::new(
                    self.vertices[f[0] as usize],
                    self.vertices[f[1] as usize],
                    self.vertices[f[2] as usize],
                )
            })
            .collect()
    }

    /// Every undirected edge once.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut e: Vec<[u32; 2]> = self
            .faces
            .iter()
            .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[2], f[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    /// True when every edge is shared by exactly two faces (a closed surface).
    pub fn is_closed(&self) -> bool {
        let mut e: Vec<[u32; 2]> = self
            .faces
            .iter()
            .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[2], f[0]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        e.sort_unstable();
        e.chunk_by(|a, b| a == b).all(|g| g.len() == 2)
    }

    /// The mesh moved by `p' = s·p + offset`.
    pub fn transformed(&self, s: f32, offset: Vec3) -> Mesh {
        Mesh {
            vertices: self.vertices.iter().map(|&p| p * s + offset).collect(),
            faces: self.faces.clone(),
        }
    }
}

/// A geodesic sphere: an icosahedron subdivided `levels` times, each new
/// vertex made once and shared.
pub fn icosphere(center: Vec3, r: f32, levels: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut vertices: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&[x, y, z]| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(faces.len() * 4);
        for f in &faces {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                m[k] = *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    vertices
                        .push(((vertices[a as usize] + vertices[b as usize]) * 0.5).normalize());
                    (vertices.len() - 1) as u32
                });
            }
            next.extend([
                [f[0], m[0], m[2]],
                [f[1], m[1], m[0]],
                [f[2], m[2], m[1]],
                [m[0], m[1], m[2]],
            ]);
        }
        faces = next;
    }
    Mesh {
        vertices: vertices.into_iter().map(|p| center + p * r).collect(),
        faces,
    }
}

/// A closed axis-aligned box with each face split into `n`×`n` quads (two
/// triangles each); vertices on shared edges are the same values.
pub fn box_mesh(min: Vec3, max: Vec3, n: u32) -> Mesh {
    let mut m = Mesh::default();
    let mut index = std::collections::HashMap::new();
    let mut vid = |m: &mut Mesh, g: [u32; 3]| -> u32 {
        *index.entry(g).or_insert_with(|| {
            let f = |k: usize| {
                let s = g[k] as f32 / n as f32;
                min[k] + (max[k] - min[k]) * s
            };
            m.vertices.push(Vec3::new(f(0), f(1), f(2)));
            (m.vertices.len() - 1) as u32
        })
    };
    // Each face: the fixed axis, its side, and two running axes.
    for axis in 0..3 {
        for side in [0, n] {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            for j in 0..n {
                for i in 0..n {
                    let g = |di: u32, dj: u32| {
                        let mut g = [0u32; 3];
                        g[axis] = side;
                        g[a] = i + di;
                        g[b] = j + dj;
                        g
                    };
                    let q = [
                        vid(&mut m, g(0, 0)),
                        vid(&mut m, g(1, 0)),
                        vid(&mut m, g(1, 1)),
                        vid(&mut m, g(0, 1)),
                    ];
                    m.faces.push([q[0], q[1], q[2]]);
                    m.faces.push([q[0], q[2], q[3]]);
                }
            }
        }
    }
    m
}

/// A buffer's bytes as an application reads them: its own staging buffer,
/// copy, submit, map, wait. `buf` needs `COPY_SRC`.
pub fn read_buffer(device: &wgpu::Device, queue: &wgpu::Queue, buf: &wgpu::Buffer) -> Vec<u8> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: buf.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buf, 0, &staging, 0, buf.size());
    queue.submit([enc.finish()]);
    staging.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    staging.get_mapped_range(..).expect("mapped").to_vec()
}
