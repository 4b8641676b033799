//! A cost model of one frame (build + trace) and the choice of build
//! parameters it makes.
//!
//! The model is linear in counts the structure and the traversal report
//! exactly (so its predictions are deterministic):
//!
//! * build: `ns_per_node · nodes + ns_per_list · lists + ns_per_triangle_view · triangles · views`,
//!   where `nodes` are the list entries, `lists` the (slot, tile, bucket)
//!   lists (offsets, scan) and the last term the per-view clipping of every triangle;
//! * trace, per ray: `ns_per_ray + ns_per_tile · tiles + ns_per_bucket · buckets + ns_per_test · tests`
//!   with the per-ray statistics of `trace_with_stats`.
//!
//! The weights are fitted by least squares ([`CostModel::fit`]) to measured
//! build and trace times; [`CostModel::CALIBRATED`] holds the weights fitted on
//! the measurements of `crates/dirt-cpu/examples/calibrate.rs` (2-core x86-64,
//! release build; refit on other machines; its fit error is stated there).
//! Only the *ranking* of candidates matters for [`choose`]; every candidate
//! gives the same hits.

use crate::{Ads, CpuError, trace_with_stats};
use dirt_core::{AdsParams, BindingLimits, SplitArray, Traversal, ViewsKind};
use dirt_math::view::{Axis, single_sees_all};
use dirt_math::{Aabb, Ray, Triangle, Vec3};

/// Weights of the frame-cost model, in nanoseconds per unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    pub ns_per_node: f64,
    pub ns_per_list: f64,
    pub ns_per_triangle_view: f64,
    pub ns_per_ray: f64,
    pub ns_per_tile: f64,
    pub ns_per_bucket: f64,
    pub ns_per_test: f64,
}

/// Counts of one build and the mean per-ray statistics of a ray sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub nodes: f64,
    pub lists: f64,
    pub triangle_views: f64,
    pub tiles_per_ray: f64,
    pub buckets_per_ray: f64,
    pub tests_per_ray: f64,
}

impl Counts {
    /// The counts of `ads` and of tracing `sample` through it (mean per ray).
    pub fn measure(ads: &Ads, tris: &[Triangle], sample: &[Ray], traversal: Traversal) -> Counts {
        let (_, stats) = trace_with_stats(ads, tris, sample, traversal);
        let n = sample.len().max(1) as f64;
        let sum =
            |f: fn(&dirt_math::RayStats) -> u32| stats.iter().map(|s| f(s) as f64).sum::<f64>() / n;
        Counts {
            nodes: ads.lists.ids.len() as f64,
            lists: ads.lists.offsets.len() as f64,
            triangle_views: (tris.len() * ads.views.slots()) as f64,
            tiles_per_ray: sum(|s| s.tiles),
            buckets_per_ray: sum(|s| s.buckets),
            tests_per_ray: sum(|s| s.tests),
        }
    }
}

impl CostModel {
    /// Fitted by `examples/calibrate.rs` on cornell, foliage, layers and
    /// spheres over {cube, single} × resolution {32, 64, 128, 256} ×
    /// B {1, 4, 8, 16, 32} × {linear, Hi-Z} (320 traces, 160 builds), on a
    /// 2-core x86-64 machine, after the build stopped clipping a triangle to
    /// its tiles more than once and the single view looks along the thinnest
    /// axis. Median relative error of the fit on those measurements: 22 % for
    /// trace time per ray, 36 % for build time. Spearman's rank correlation
    /// between predicted and measured cost: 0.84 (trace per ray), 0.96
    /// (build), and for whole frames 0.95 (5 000 rays), 0.91 (100 000), 0.87
    /// (1 000 000). Ranking is what [`auto`] and [`choose`] need; the
    /// milliseconds are rough. The candidates at resolution 8 and 16 are
    /// ranked with these constants too: a fit that included them (480
    /// traces) ranked no better (0.87 / 0.95 / 0.94, 0.91, 0.88) and chose a
    /// slower structure for the deforming grid's frames of 100 000 rays.
    ///
    /// Measured again after the trace's speed work, with the orthographic
    /// kinds added to the sweep ({cube, single, ortho, ortho2}: 640 traces,
    /// 320 builds): these constants rank the measurements with 0.87 (trace
    /// per ray), 0.86 (build), and for whole frames 0.85 (5 000 rays), 0.88
    /// (100 000), 0.88 (1 000 000); a fit to that sweep ranks them no better
    /// (0.87, 0.85; 0.87, 0.88, 0.87), so these stay.
    ///
    /// Measured again after the build's coverage took eight triangles at a
    /// time (the same 640 traces and 320 builds): these constants rank the
    /// measurements with 0.84 (trace per ray), 0.90 (build), and 0.88, 0.90,
    /// 0.86 for whole frames; a fit ranks them with 0.85, 0.89; 0.90, 0.89,
    /// 0.86, no better, so these stay. The fit's weights are lower (per node
    /// 13.0 ns, per triangle and view 57.9, per ray 224, per tile 12.0, per
    /// bucket 8.8, per test 2.9, per list 2.5): the milliseconds these
    /// constants predict are 1.3× to 1.9× today's, the ranking the same.
    ///
    /// Measured again after the trace left out listed triangles whose
    /// view-space box misses the ray's segment (the same sweep): these
    /// constants rank the measurements with 0.78 (trace per ray), 0.87
    /// (build), and 0.84, 0.83, 0.80 for whole frames; a fit ranks them with
    /// 0.85, 0.87; 0.88, 0.87, 0.85 (per test 0.72 ns, per tile 7.3, per
    /// bucket 11.7, per ray 196, per node 6.9, per triangle and view 56.3,
    /// per list 2.4). Its choices were slower where it matters: the
    /// deforming grid's frames (r64 B8 for 5 000 rays, 4.21 ms a frame
    /// against 2.98 at r128 B2; r128 B1 for 100 000, 12.8 against 10.1 at
    /// r256 B1) and foliage's 25 000 rays (single r64 B8, whose trace is 20%
    /// slower than that of ortho2 r32 B8, for 1 ms less build). These stay.
    ///
    /// Tried and not kept: counting the fast path's work instead of the plain
    /// stage's statistics (triangles tested after the apex look, the boxes
    /// and the mailbox; Hi-Z cells expanded counted as tiles; each for a
    /// batch of the frame's size). A fit to it ranked the same sweep better
    /// (0.926 trace per ray; 0.912, 0.924, 0.921 for frames), but chose
    /// slower structures for the deforming grid: r128 B4 and r256 B2 for
    /// frames of 5,000 and 100,000 rays, 6% and 11-13% slower than the
    /// r128 B2 and r256 B1 chosen now (alternated runs). With the grid's
    /// camera rays in the sweep, a test weighed 3.0 ns instead of 11.4, and
    /// the search chose single r32 B1 for foliage's headline rays, whose
    /// trace is 2.3x slower than that of ortho2 r32 B8.
    pub const CALIBRATED: CostModel = CostModel {
        ns_per_node: 24.53,
        ns_per_list: 2.418,
        ns_per_triangle_view: 85.41,
        ns_per_ray: 291.9,
        ns_per_tile: 10.99,
        ns_per_bucket: 7.777,
        ns_per_test: 4.204,
    };

    /// Predicted build time in milliseconds.
    pub fn build_ms(&self, c: &Counts) -> f64 {
        (self.ns_per_node * c.nodes
            + self.ns_per_list * c.lists
            + self.ns_per_triangle_view * c.triangle_views)
            * 1e-6
    }

    /// Predicted trace time per ray in nanoseconds.
    pub fn ray_ns(&self, c: &Counts) -> f64 {
        self.ns_per_ray
            + self.ns_per_tile * c.tiles_per_ray
            + self.ns_per_bucket * c.buckets_per_ray
            + self.ns_per_test * c.tests_per_ray
    }

    /// Predicted frame time (build + `rays` rays) in milliseconds.
    pub fn frame_ms(&self, c: &Counts, rays: u64) -> f64 {
        self.build_ms(c) + self.ray_ns(c) * rays as f64 * 1e-6
    }

    /// Median relative error of the model's trace and build predictions on
    /// measurements shaped as for [`CostModel::fit`]: `(trace, build)`.
    pub fn median_relative_error(
        &self,
        builds: &[(Counts, f64)],
        traces: &[(Counts, f64)],
    ) -> (f64, f64) {
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
        };
        (
            median(
                traces
                    .iter()
                    .map(|(c, ns)| ((self.ray_ns(c) - ns) / ns).abs())
                    .collect(),
            ),
            median(
                builds
                    .iter()
                    .map(|(c, ms)| ((self.build_ms(c) - ms) / ms).abs())
                    .collect(),
            ),
        )
    }

    /// Least-squares fit (of relative errors) of the weights to measurements: `builds` pairs the
    /// counts of a build with its measured milliseconds, `traces` the counts
    /// of a traced sample with its measured nanoseconds per ray. Negative
    /// weights are clamped to zero (a count never makes work cheaper).
    /// `None` when the measurements do not determine the weights.
    pub fn fit(builds: &[(Counts, f64)], traces: &[(Counts, f64)]) -> Option<CostModel> {
        let b = least_squares(
            &builds
                .iter()
                .map(|(c, ms)| (vec![c.nodes, c.lists, c.triangle_views], ms * 1e6))
                .collect::<Vec<_>>(),
        )?;
        let t = least_squares(
            &traces
                .iter()
                .map(|(c, ns)| {
                    (
                        vec![1.0, c.tiles_per_ray, c.buckets_per_ray, c.tests_per_ray],
                        *ns,
                    )
                })
                .collect::<Vec<_>>(),
        )?;
        let p = |x: f64| x.max(0.0);
        Some(CostModel {
            ns_per_node: p(b[0]),
            ns_per_list: p(b[1]),
            ns_per_triangle_view: p(b[2]),
            ns_per_ray: p(t[0]),
            ns_per_tile: p(t[1]),
            ns_per_bucket: p(t[2]),
            ns_per_test: p(t[3]),
        })
    }
}

/// Least squares of the *relative* error of `rows` (features, target): each
/// row is divided by its target, so small scenes weigh as much as large ones
/// (ranking candidates needs relative accuracy). Rows with a target that is
/// not positive are skipped. Normal equations, Gaussian elimination with
/// partial pivoting; `None` if singular.
fn least_squares(rows: &[(Vec<f64>, f64)]) -> Option<Vec<f64>> {
    let n = rows.first()?.0.len();
    let mut a = vec![vec![0.0; n + 1]; n];
    for (x, y) in rows {
        if !(*y > 0.0) {
            continue;
        }
        let w = 1.0 / y;
        for i in 0..n {
            for j in 0..n {
                a[i][j] += x[i] * w * x[j] * w;
            }
            a[i][n] += x[i] * w;
        }
    }
    for col in 0..n {
        let piv = (col..n).max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))?;
        if !(a[piv][col].abs() > 1e-12 * (1.0 + a[col][col].abs())) {
            return None;
        }
        a.swap(col, piv);
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                for (x, p) in row.iter_mut().zip(&pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    Some((0..n).map(|i| a[i][n] / a[i][i]).collect())
}

/// One candidate of [`choose`] with its counts and predicted costs.
#[derive(Clone, Copy, Debug)]
pub struct Candidate {
    pub params: AdsParams,
    pub counts: Counts,
    pub build_ms: f64,
    pub ray_ns: f64,
    pub frame_ms: f64,
    /// Bytes of the structure.
    pub bytes: u64,
    /// Triangles.
    pub tris: u64,
    /// List entries (ids).
    pub ids: u64,
    /// Cells of the Hi-Z pyramid, depth bounds included.
    pub hiz_cells: u64,
    /// List offsets (one per list, and the total).
    pub offsets: u64,
}

impl Candidate {
    /// Whether a device of `limits` can hold its structure: each array
    /// within its bindings ([`BindingLimits::capacity`]).
    pub fn fits(&self, limits: &BindingLimits) -> bool {
        limits.fits([
            (SplitArray::Tris, self.tris),
            (SplitArray::Ids, self.ids),
            (SplitArray::Hiz, self.hiz_cells),
            (SplitArray::Offsets, self.offsets),
        ])
    }
}

impl Candidate {
    /// The counts of `ads` (built over `tris`) and of tracing `sample`
    /// through it, with the model's predictions for `rays_per_frame` rays.
    fn of(
        ads: &Ads,
        tris: &[Triangle],
        sample: &[Ray],
        traversal: Traversal,
        model: &CostModel,
        rays_per_frame: u64,
    ) -> Candidate {
        let counts = Counts::measure(ads, tris, sample, traversal);
        Candidate {
            params: ads.params,
            counts,
            build_ms: model.build_ms(&counts),
            ray_ns: model.ray_ns(&counts),
            frame_ms: model.frame_ms(&counts, rays_per_frame),
            bytes: ads.memory().total(),
            tris: tris.len() as u64,
            ids: ads.lists.ids.len() as u64,
            hiz_cells: ads.hiz.iter().map(|l| l.len() as u64).sum(),
            offsets: ads.lists.offsets.len() as u64,
        }
    }
}

/// The candidates the model ranks: face resolution {8, 16, …, 256} ×
/// B {1, 2, 4, 8, 16} (S = 1; a tile of S pixels is the same structure as
/// resolution / S), with the views and centre of `base`; with `both_views`
/// and no centre, for the cube and for the single view too (placed outside
/// the bounds, the single view sees the whole scene, so it is exact for
/// every ray as the cube is).
pub fn candidates(base: &AdsParams, both_views: bool) -> Vec<AdsParams> {
    let views = if both_views && base.center.is_none() {
        vec![ViewsKind::Cube, ViewsKind::Single]
    } else {
        vec![base.views]
    };
    let mut out = Vec::new();
    for views in views {
        for resolution in [8, 16, 32, 64, 128, 256] {
            for buckets in [1, 2, 4, 8, 16] {
                out.push(AdsParams {
                    views,
                    resolution,
                    buckets,
                    tile: 1,
                    ..*base
                });
            }
        }
    }
    out
}

/// [`candidates`] with both perspective kinds, and with no centre given the
/// orthographic sets too, looking along `base.axis` or the bounds' thinnest
/// axis (000 §5.3): one view, and two split at each of [`ortho_cuts`]. Every
/// kind both backends build, each exact for every ray.
pub fn candidates_all(base: &AdsParams, tris: &[Triangle]) -> Vec<AdsParams> {
    let mut out = candidates(
        &AdsParams {
            axis: None,
            ..*base
        },
        true,
    );
    if base.center.is_some() {
        return out;
    }
    let bounds = dirt_core::bounds_of(tris);
    let axis = base.ortho_axis(&bounds);
    let ortho = |views, center| AdsParams {
        views,
        center,
        axis: base.axis,
        ..*base
    };
    out.extend(candidates(&ortho(ViewsKind::Ortho, None), false));
    for (k, cut) in ortho_cuts(tris, &bounds, axis).into_iter().enumerate() {
        // The first cut is the bounds' centre, the split's default.
        let center = (k > 0).then(|| {
            let mut c = bounds.center();
            c[axis.index()] = cut;
            c
        });
        out.extend(candidates(&ortho(ViewsKind::OrthoSplit, center), false));
    }
    out
}

/// Where [`candidates_all`] cuts the split orthographic views along `axis`:
/// the spatial median (the centre of `bounds`), then, where they differ from
/// it, the object median (the median of the triangles' centroids) and the
/// point halfway between. MacDonald and Booth showed that the best cut lies
/// between the two medians (000 §6.3); the cost model picks among these.
/// Nothing but the spatial median for an empty scene.
pub fn ortho_cuts(tris: &[Triangle], bounds: &Aabb, axis: Axis) -> Vec<f32> {
    let a = axis.index();
    let spatial = bounds.center()[a];
    let mut out = vec![spatial];
    let mut c: Vec<f32> = tris
        .iter()
        .map(|t| (t.vertex(0)[a] + t.vertex(1)[a] + t.vertex(2)[a]) / 3.0)
        .filter(|x| x.is_finite())
        .collect();
    if c.is_empty() || !spatial.is_finite() {
        return out;
    }
    let mid = c.len() / 2;
    let object = *c.select_nth_unstable_by(mid, f32::total_cmp).1;
    for cut in [object, 0.5 * (object + spatial)] {
        if !out.contains(&cut) {
            out.push(cut);
        }
    }
    out
}

/// The candidates placed at `origin`, where a frame's rays start (a camera's
/// eye): the cube centred there, which is exact wherever it stands, and the
/// single view from there when it sees all of `bounds`
/// ([`single_sees_all`]), each over the resolutions and B of [`candidates`].
/// A ray that starts at a view's apex projects to one point of it, so the
/// walk of such a ray stays near one pixel (0.4 tiles a ray, against 44 for
/// the single view outside the scene, on the eval's deforming grid).
pub fn candidates_at(origin: Vec3, bounds: &Aabb) -> Vec<AdsParams> {
    let mut out = Vec::new();
    for views in [ViewsKind::Cube, ViewsKind::Single] {
        if views == ViewsKind::Single && !single_sees_all(origin, bounds) {
            continue;
        }
        let base = AdsParams {
            views,
            center: Some(origin),
            ..AdsParams::default()
        };
        out.extend(candidates(&base, false));
    }
    out
}

/// Builds every candidate, traces `sample` through it for its counts, and
/// ranks the candidates by predicted frame time for `rays_per_frame` rays
/// (cheapest first). Every candidate gives the same hits: only time and
/// memory differ.
pub fn choose(
    tris: &[Triangle],
    sample: &[Ray],
    rays_per_frame: u64,
    traversal: Traversal,
    model: &CostModel,
    candidates: &[AdsParams],
) -> Result<Vec<Candidate>, CpuError> {
    let mut out = Vec::with_capacity(candidates.len());
    for p in candidates {
        let ads = Ads::build(tris, p)?;
        out.push(Candidate::of(
            &ads,
            tris,
            sample,
            traversal,
            model,
            rays_per_frame,
        ));
    }
    out.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    Ok(out)
}

/// Which traversal traced a sample of rays faster through one structure,
/// and how long each took (the shortest of [`TRAVERSAL_RUNS`] runs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraversalChoice {
    pub traversal: Traversal,
    pub linear: std::time::Duration,
    pub hiz: std::time::Duration,
    pub rays: usize,
}

/// Runs of each traversal [`faster_traversal`] times, alternated.
pub const TRAVERSAL_RUNS: usize = 3;

/// Times the trace of `sample` through `ads` (built over `tris`) with each
/// traversal — [`TRAVERSAL_RUNS`] runs each, alternated, the shortest kept —
/// and picks the faster (linear on a tie). Unlike the counts of the cost
/// model this is a measurement: where the two are close the pick may differ
/// from run to run. It changes only time: both traversals give the same
/// hits, bit for bit.
pub fn faster_traversal(ads: &Ads, tris: &[Triangle], sample: &[Ray]) -> TraversalChoice {
    let mut best = [std::time::Duration::MAX; 2];
    for _ in 0..TRAVERSAL_RUNS {
        for (k, t) in Traversal::ALL.into_iter().enumerate() {
            let start = web_time::Instant::now();
            std::hint::black_box(crate::trace(ads, tris, sample, t));
            best[k] = best[k].min(start.elapsed());
        }
    }
    let [linear, hiz] = best;
    TraversalChoice {
        traversal: if hiz < linear {
            Traversal::HiZ
        } else {
            Traversal::Linear
        },
        linear,
        hiz,
        rays: sample.len(),
    }
}

/// Spearman's rank correlation of two equally long series (ties get their
/// mean rank); `None` for fewer than two pairs or a constant series.
pub fn rank_correlation(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 2 {
        return None;
    }
    let ranks = |x: &[f64]| {
        let mut idx: Vec<usize> = (0..x.len()).collect();
        idx.sort_by(|&p, &q| x[p].total_cmp(&x[q]));
        let mut r = vec![0.0; x.len()];
        let mut k = 0;
        while k < idx.len() {
            let mut e = k;
            while e + 1 < idx.len() && x[idx[e + 1]] == x[idx[k]] {
                e += 1;
            }
            let mean = (k + e) as f64 / 2.0;
            for &i in &idx[k..=e] {
                r[i] = mean;
            }
            k = e + 1;
        }
        r
    };
    let (ra, rb) = (ranks(a), ranks(b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    (saa > 0.0 && sbb > 0.0).then(|| sab / (saa * sbb).sqrt())
}

/// At most about `n` of the caller's `rays`, evenly strided (every k-th), as
/// the sample the model measures candidates with.
pub fn stride_sample(rays: &[Ray], n: usize) -> Vec<Ray> {
    let stride = rays.len().div_ceil(n.max(1)).max(1);
    rays.iter().step_by(stride).copied().collect()
}

/// A deterministic sample of `n` rays for the model when the caller has none:
/// origins on the triangles (a random point of a random triangle), directions
/// uniform on the sphere, from a fixed seed. Secondary rays start on
/// surfaces, so this resembles a path tracer's bounces more than a camera's.
pub fn sample_rays(tris: &[Triangle], n: usize, seed: u64) -> Vec<Ray> {
    if tris.is_empty() {
        return Vec::new();
    }
    let mut s = seed;
    let mut next = move || {
        // splitmix64
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut unit = move || {
        let z = next();
        (z >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let k = ((unit() as f64 * tris.len() as f64) as usize).min(tris.len() - 1);
            let t = &tris[k];
            let (mut a, mut b) = (unit(), unit());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let o = t.vertex(0) + (t.vertex(1) - t.vertex(0)) * a + (t.vertex(2) - t.vertex(0)) * b;
            let d = loop {
                let d = dirt_math::Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
                let l = d.length();
                if l > 0.05 && l <= 1.0 {
                    break d / l;
                }
            };
            Ray::new(o, d, 1e-4, f32::INFINITY)
        })
        .collect()
}

/// The point every ray of `rays` starts at, when they all start at one
/// (bit for bit, and finite): a camera's primary rays. `None` for no rays.
pub fn common_origin(rays: &[Ray]) -> Option<Vec3> {
    let first = rays.first()?.origin;
    let bits = first.map(f32::to_bits);
    (rays.iter().all(|r| r.origin.map(f32::to_bits) == bits) && first.iter().all(|c| c.is_finite()))
        .then(|| Vec3::from(first))
}

/// A deterministic sample of `n` rays from `origin` (a camera's eye) towards
/// random points of random triangles, for the model when a frame's rays
/// start there: every ray of the sample reaches the scene.
pub fn sample_rays_from(origin: Vec3, tris: &[Triangle], n: usize, seed: u64) -> Vec<Ray> {
    sample_rays(tris, n, seed)
        .iter()
        .map(|r| Ray::new(origin, r.origin() - origin, 0.0, f32::INFINITY))
        .collect()
}

/// What [`auto`] chose and what it cost to choose.
#[derive(Debug)]
pub struct AutoChoice {
    /// The cheapest candidate built.
    pub best: Candidate,
    /// Every candidate built, cheapest first.
    pub ranked: Vec<Candidate>,
    /// Candidates left unbuilt: not next to the path the search took, pruned
    /// by an estimate of their frame, or past the budget.
    pub skipped: usize,
    /// Candidates built but too large for the device ([`auto_within`]).
    pub too_large: usize,
    /// Predicted milliseconds of the candidate builds and sample traces the
    /// choice made: the price of choosing, which [`auto`] keeps near a share of the frame.
    pub spent_ms: f64,
    /// The structure of `best`, built while choosing (so the caller need not build it again).
    pub best_ads: Option<Ads>,
}

/// Share of the best predicted frame that [`auto`] may spend building
/// candidates (in predicted milliseconds, so the choice is deterministic).
pub const AUTO_BUDGET: f64 = 0.25;

/// [`AUTO_BUDGET`] of a choice that is kept for later frames and traces
/// ([`auto_budgeted`], as `DirtCpu::auto` chooses): four frames' worth. On
/// the deforming grid at the camera (32k triangles) the quarter frame built
/// only the first guess, single r128 B8. Two frames walked on to r128 B4 (a
/// frame of 5,000 rays 4.12 -> 3.80 ms, of 100,000 rays 19.0 -> 16.9 ms);
/// with B 1 and 2 among the candidates they reach r256 B1 for 100,000 rays
/// (17.1 -> 14.6 ms), and four frames reach r128 B2 for 5,000 (3.46-3.52 ->
/// 3.39-3.42 ms), for a few builds once.
pub const KEPT_BUDGET: f64 = 4.0;

/// The first resolution [`auto`] tries for a perspective view kind: the
/// power of two nearest `sqrt(triangles / views)` among the candidates'
/// resolutions, so that a triangle covers about one tile.
fn first_guess(tris: usize, views: ViewsKind, resolutions: &[u32]) -> u32 {
    let per_view = tris as f64 / views.view_count() as f64;
    let want = per_view.max(1.0).sqrt().log2();
    resolutions
        .iter()
        .copied()
        .min_by(|a, b| {
            let d = |r: u32| (f64::from(r).log2() - want).abs();
            d(*a).total_cmp(&d(*b)).then(a.cmp(b))
        })
        .unwrap_or(AdsParams::default().resolution)
}

/// The mean products of a triangle's extents along two world axes: the
/// size of its bounding rectangle in an orthographic view
/// ([`Extents::area`]), known without a build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Extents {
    /// Mean product of the extents along the two axes other than x, y and z:
    /// `[y·z, x·z, x·y]`.
    pub cross: [f64; 3],
}

impl Extents {
    /// Of `tris`, skipping triangles with a coordinate that is not finite;
    /// `None` where none is left. Sums are made per chunk and added in
    /// order, so the result does not depend on the threads.
    pub fn of(tris: &[Triangle]) -> Option<Extents> {
        use rayon::prelude::*;
        let part = |chunk: &[Triangle]| {
            let (mut sum, mut n) = ([0.0f64; 3], 0usize);
            for t in chunk {
                // min and max pass NaN over: test the coordinates themselves.
                if t.v.iter().flatten().all(|x| x.is_finite()) {
                    let [a, b, c] = [t.vertex(0), t.vertex(1), t.vertex(2)];
                    let e = (a.max(b).max(c) - a.min(b).min(c))
                        .to_array()
                        .map(f64::from);
                    let terms = [e[1] * e[2], e[0] * e[2], e[0] * e[1]];
                    for (s, x) in sum.iter_mut().zip(terms) {
                        *s += x;
                    }
                    n += 1;
                }
            }
            (sum, n)
        };
        let parts: Vec<([f64; 3], usize)> = tris.par_chunks(4096).map(part).collect();
        let (mut sum, mut n) = ([0.0f64; 3], 0usize);
        for (s, k) in parts {
            for (a, b) in sum.iter_mut().zip(s) {
                *a += b;
            }
            n += k;
        }
        (n > 0).then(|| {
            let m = |k: usize| sum[k] / n as f64;
            Extents {
                cross: [m(0), m(1), m(2)],
            }
        })
    }

    /// The mean area of a triangle's bounding rectangle in an orthographic
    /// view looking along `axis` whose image is `2·half` wide, as a share
    /// of the image's.
    pub fn area(&self, axis: Axis, half: f32) -> f64 {
        self.cross[axis.index()] / (2.0 * f64::from(half)).powi(2)
    }
}

/// The resolutions [`auto`] tries first for the placement `place` over
/// `bounds`. For an orthographic one, the two of `resolutions` around the
/// resolution at which the mean triangle's bounding rectangle is about a
/// tile (`area · r² = 1`) or, for triangles much smaller than the image's
/// share of each, about a triangle a tile (`r² = triangles / views`, as
/// [`first_guess`]): `r = 1 / sqrt(area + views / triangles)`. A ray walks
/// more tiles as they grow finer and meets more triangles in each as they
/// grow coarser; past a tile's size a triangle is listed in more tiles,
/// and a ray meets no fewer of them. The coarser first: it builds faster,
/// and a large scene's budget builds one candidate. Over every candidate
/// of the eval's static scenes and its five ray types (2 threads,
/// `dirt-eval`'s `sweep` example), the one-view orthographic set traced
/// fastest at r8 on cornell (`r` 15.3; r16 8% slower), r16 on foliage
/// (15.6) and bunny (30; r32 1% slower), r64 on layers (22.6; r32 5-8%
/// slower), r128 on spheres (99; r64 2% slower, building in 0.6x the
/// time) and on 2CylinderEngine (141).
/// For a perspective placement, whose tiles grow with the depth,
/// [`first_guess`] alone.
fn first_guesses_at(
    sizes: Option<&(Aabb, Extents)>,
    tris: usize,
    place: &AdsParams,
    resolutions: &[u32],
) -> Vec<u32> {
    let perspective = || vec![first_guess(tris, place.views, resolutions)];
    let Some((bounds, e)) =
        sizes.filter(|(b, _)| place.views.is_ortho() && !b.is_empty() && tris > 0)
    else {
        return perspective();
    };
    let views = dirt_core::views_over(place, bounds);
    let axis = place.ortho_axis(bounds);
    let half = views.views.first().map_or(0.0, |v| v.tan);
    let share = place.views.view_count() as f64 / tris as f64;
    let want = 1.0 / (e.area(axis, half) + share).sqrt();
    let mut sorted = resolutions.to_vec();
    sorted.sort_unstable();
    let below = sorted.iter().copied().rfind(|&r| f64::from(r) <= want);
    let above = sorted.iter().copied().find(|&r| f64::from(r) > want);
    let mut out: Vec<u32> = [below, above].into_iter().flatten().collect();
    out.dedup();
    if out.is_empty() {
        // Only where `want` is not a number.
        return perspective();
    }
    out
}

/// The cost model's choice of parameters for `rays_per_frame` rays, made
/// cheaply enough to be a default: a local search over `candidates` instead of
/// building them all ([`choose`]).
///
/// 1. Per placement (view kind and centre), a first guess with the B nearest
///    8: for an orthographic placement two, at the resolutions around the
///    one where its mean triangle is about a tile ([`Extents`], known
///    without a build), the coarser first; for a perspective one, the
///    resolution of [`first_guess`]. Placements are tried in the order of
///    their estimated frames (one view costs less to build than six), the
///    orthographic first of two alike.
/// 2. From the best candidate so far, its neighbours (resolution halved or
///    doubled, B halved or doubled, same placement) are tried, cheapest estimate
///    first; the search moves to a neighbour that beats it and stops when none does.
///
/// A candidate is built only when an estimate of its frame can beat the best
/// so far — the nodes of a built candidate of the same placement that it
/// dominates (nodes grow with resolution and B), `triangles × views` with the
/// kind's view count, and the per-ray constant for every ray — and when the
/// predicted cost of the candidates built, plus its own estimated build, stays
/// under [`AUTO_BUDGET`] of the best predicted frame. The first candidate is
/// always built. Every candidate gives the same hits.
pub fn auto(
    tris: &[Triangle],
    sample: &[Ray],
    rays_per_frame: u64,
    traversal: Traversal,
    model: &CostModel,
    candidates: &[AdsParams],
) -> Result<AutoChoice, CpuError> {
    auto_within(
        tris,
        sample,
        rays_per_frame,
        traversal,
        model,
        candidates,
        None,
    )
}

/// [`auto`] for a device of binding limits `limits` (a GPU's
/// [`BindingLimits`]): a candidate that does not fit them
/// ([`Candidate::fits`]: a buffer bound whole beyond one binding, or
/// triangles or list ids beyond their bindings) is built and measured but never chosen, and
/// when the first guesses all exceed them the smaller candidates are tried,
/// smallest first. An error when none fits.
pub fn auto_within(
    tris: &[Triangle],
    sample: &[Ray],
    rays_per_frame: u64,
    traversal: Traversal,
    model: &CostModel,
    candidates: &[AdsParams],
    limits: Option<BindingLimits>,
) -> Result<AutoChoice, CpuError> {
    auto_budgeted(
        tris,
        sample,
        rays_per_frame,
        traversal,
        model,
        candidates,
        limits,
        AUTO_BUDGET,
    )
}

/// [`auto_within`] spending at most `budget` of the best predicted frame on
/// candidate builds: [`AUTO_BUDGET`] for a one-off choice, [`KEPT_BUDGET`]
/// for one kept for later frames and traces (what `DirtCpu::auto` makes).
pub fn auto_budgeted(
    tris: &[Triangle],
    sample: &[Ray],
    rays_per_frame: u64,
    traversal: Traversal,
    model: &CostModel,
    candidates: &[AdsParams],
    limits: Option<BindingLimits>,
    budget: f64,
) -> Result<AutoChoice, CpuError> {
    let fits = |c: &Candidate| limits.is_none_or(|l| c.fits(&l));
    let mut too_large: usize = 0;
    let mut ranked: Vec<Candidate> = Vec::new();
    let mut best_ads: Option<Ads> = None;
    let mut tried = vec![false; candidates.len()];
    let mut spent_ms = 0.0;
    let per_ray_floor = model.ns_per_ray * rays_per_frame as f64 * 1e-6;
    // Candidates of one placement (views and centre) are neighbours.
    let same_place = |p: &AdsParams, q: &AdsParams| {
        p.views == q.views && p.center == q.center && p.axis == q.axis
    };
    let view_count = |p: &AdsParams| p.views.view_count() as f64;
    let res = |p: &AdsParams| p.resolution / p.tile.max(1);
    // Estimated frame of an unbuilt candidate, from what was built.
    let estimate = |p: &AdsParams, ranked: &[Candidate]| {
        let nodes = ranked
            .iter()
            .filter(|c| {
                same_place(&c.params, p)
                    && res(&c.params) <= res(p)
                    && c.params.buckets <= p.buckets
            })
            .map(|c| c.counts.nodes)
            .fold(0.0, f64::max);
        let c = Counts {
            nodes,
            triangle_views: tris.len() as f64 * view_count(p),
            ..Counts::default()
        };
        model.build_ms(&c) + per_ray_floor
    };
    // Builds candidate k when it may win and the budget allows; true if it became the best.
    let attempt = |k: usize,
                   tried: &mut [bool],
                   ranked: &mut Vec<Candidate>,
                   best_ads: &mut Option<Ads>,
                   spent_ms: &mut f64,
                   too_large: &mut usize|
     -> Result<bool, CpuError> {
        tried[k] = true;
        let p = &candidates[k];
        let best = ranked.first().map_or(f64::INFINITY, |c| c.frame_ms);
        // Its estimated build must fit in what is left of the budget, and its
        // estimated frame must beat the best.
        let frame = estimate(p, ranked);
        if !ranked.is_empty()
            && (*spent_ms + (frame - per_ray_floor) > budget * best || frame >= best)
        {
            return Ok(false);
        }
        let ads = Ads::build(tris, p)?;
        let c = Candidate::of(&ads, tris, sample, traversal, model, rays_per_frame);
        *spent_ms += c.build_ms + c.ray_ns * sample.len() as f64 * 1e-6;
        if !fits(&c) {
            *too_large += 1;
            return Ok(false);
        }
        let wins = c.frame_ms < best;
        if wins {
            *best_ads = Some(ads);
        }
        ranked.push(c);
        ranked.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
        Ok(wins)
    };
    // 1. The first guesses per placement, the one with the cheaper estimate first.
    let resolutions: Vec<u32> = {
        let mut r: Vec<u32> = candidates.iter().map(|p| p.resolution).collect();
        r.sort_unstable();
        r.dedup();
        r
    };
    let mut places: Vec<AdsParams> = Vec::new();
    for p in candidates {
        if !places.iter().any(|q| same_place(p, q)) {
            places.push(*p);
        }
    }
    let mut guesses: Vec<usize> = Vec::new();
    // What the orthographic guesses look at, where there are some.
    let sizes = places
        .iter()
        .any(|p| p.views.is_ortho())
        .then(|| Some((dirt_core::bounds_of(tris), Extents::of(tris)?)))
        .flatten();
    for place in &places {
        for r0 in first_guesses_at(sizes.as_ref(), tris.len(), place, &resolutions) {
            let guess = (0..candidates.len())
                .filter(|&k| same_place(&candidates[k], place))
                .min_by_key(|&k| {
                    let p = &candidates[k];
                    (p.resolution.abs_diff(r0), p.buckets.abs_diff(8), p.buckets)
                });
            guesses.extend(guess.filter(|k| !guesses.contains(k)));
        }
    }
    // Of two placements alike in views, the orthographic first (over every
    // candidate of the eval's six static scenes, the one-view orthographic
    // set traced within 2% of the fastest candidate, the single view 14-88%
    // behind it: `dirt-eval`'s `sweep` example), and of one placement's
    // guesses the coarser: a large scene's budget builds one guess. The
    // sort is stable.
    guesses.sort_by(|&a, &b| {
        let (p, q) = (&candidates[a], &candidates[b]);
        estimate(p, &[])
            .total_cmp(&estimate(q, &[]))
            .then(q.views.is_ortho().cmp(&p.views.is_ortho()))
    });
    for &k in &guesses {
        attempt(
            k,
            &mut tried,
            &mut ranked,
            &mut best_ads,
            &mut spent_ms,
            &mut too_large,
        )?;
    }
    // Every guess too large for the device: the smaller candidates, smallest first, until one fits.
    if ranked.is_empty() {
        let mut order: Vec<usize> = (0..candidates.len()).filter(|&k| !tried[k]).collect();
        order.sort_by_key(|&k| {
            let p = &candidates[k];
            (res(p) as u64 * res(p) as u64 * p.buckets as u64, p.buckets)
        });
        for k in order {
            if attempt(
                k,
                &mut tried,
                &mut ranked,
                &mut best_ads,
                &mut spent_ms,
                &mut too_large,
            )? {
                break;
            }
        }
    }
    // 2. Walk downhill through the neighbours of the best.
    while let Some(at) = ranked.first().map(|c| c.params) {
        let mut next: Vec<usize> = (0..candidates.len())
            .filter(|&k| !tried[k])
            .filter(|&k| {
                let p = &candidates[k];
                let (r, b) = (res(p), p.buckets);
                let (r0, b0) = (res(&at), at.buckets);
                same_place(p, &at)
                    && ((b == b0 && (r == r0 * 2 || r * 2 == r0))
                        || (r == r0 && (b == b0 * 2 || b * 2 == b0)))
            })
            .collect();
        next.sort_by(|&a, &b| {
            estimate(&candidates[a], &ranked).total_cmp(&estimate(&candidates[b], &ranked))
        });
        let mut moved = false;
        for k in next {
            moved |= attempt(
                k,
                &mut tried,
                &mut ranked,
                &mut best_ads,
                &mut spent_ms,
                &mut too_large,
            )?;
        }
        if !moved {
            break;
        }
    }
    let best = *ranked.first().ok_or_else(|| {
        CpuError::Core(dirt_core::CoreError::InvalidParams(match limits {
            Some(l) if too_large > 0 => format!(
                "none of the {too_large} candidates built fits the device ({l}); the CPU backend traces this scene"
            ),
            _ => "the cost model was given no candidates".into(),
        }))
    })?;
    Ok(AutoChoice {
        best,
        too_large,
        skipped: candidates.len() - ranked.len() - too_large,
        ranked,
        spent_ms,
        best_ads,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ortho_cuts_are_the_medians_and_between() {
        // Centroids along x at 0, 1, 2, 3, 10: spatial median 5 (bounds 0..10
        // with the triangles' extents), object median 2, between 3.5.
        let tri = |x: f32| {
            Triangle::new(
                Vec3::new(x - 0.5, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            )
        };
        let tris: Vec<Triangle> = [0.0, 1.0, 2.0, 3.0, 10.0].map(tri).to_vec();
        let b = Aabb::of_triangles(&tris);
        assert_eq!(ortho_cuts(&tris, &b, Axis::X), vec![5.0, 2.0, 3.5]);
        // Flat along z: the medians agree, one cut.
        assert_eq!(ortho_cuts(&tris, &b, Axis::Z), vec![0.0]);
        assert_eq!(ortho_cuts(&[], &b, Axis::Y), vec![b.center().y]);
        // Offered without a centre, every split at its own cut; none with
        // one. (Along x: the thinnest axis, z, has one cut.)
        let along_x = AdsParams {
            axis: Some(Axis::X),
            ..AdsParams::default()
        };
        let all = candidates_all(&along_x, &tris);
        let split: Vec<Option<Vec3>> = all
            .iter()
            .filter(|p| p.views == ViewsKind::OrthoSplit && p.resolution == 8 && p.buckets == 4)
            .map(|p| p.center)
            .collect();
        let at = |x: f32| Some(Vec3::new(x, b.center().y, b.center().z));
        assert_eq!(split, vec![None, at(2.0), at(3.5)]);
        assert!(all.iter().any(|p| p.views == ViewsKind::Ortho));
        assert_eq!(
            candidates_all(&AdsParams::default(), &tris).len(),
            all.len() - 2 * 30
        );
        assert!(all.iter().all(|p| p.validate().is_ok()));
        let placed = AdsParams {
            center: Some(Vec3::ONE),
            ..AdsParams::default()
        };
        assert!(
            candidates_all(&placed, &tris)
                .iter()
                .all(|p| !p.views.is_ortho())
        );
    }

    #[test]
    fn fit_recovers_known_weights() {
        let truth = CostModel {
            ns_per_node: 40.0,
            ns_per_list: 2.0,
            ns_per_triangle_view: 90.0,
            ns_per_ray: 500.0,
            ns_per_tile: 10.0,
            ns_per_bucket: 5.0,
            ns_per_test: 30.0,
        };
        let mut builds = Vec::new();
        let mut traces = Vec::new();
        for k in 0..12 {
            let k = k as f64;
            let c = Counts {
                nodes: 1000.0 + 370.0 * k * k,
                lists: 5000.0 + 900.0 * k,
                triangle_views: 300.0 + 50.0 * (k % 3.0),
                tiles_per_ray: 3.0 + k,
                buckets_per_ray: 2.0 + (k * 1.7) % 5.0,
                tests_per_ray: 10.0 + (k * k) % 7.0,
            };
            builds.push((c, truth.build_ms(&c)));
            traces.push((c, truth.ray_ns(&c)));
        }
        let fit = CostModel::fit(&builds, &traces).expect("determined");
        for (a, b) in [
            (fit.ns_per_node, truth.ns_per_node),
            (fit.ns_per_list, truth.ns_per_list),
            (fit.ns_per_triangle_view, truth.ns_per_triangle_view),
            (fit.ns_per_ray, truth.ns_per_ray),
            (fit.ns_per_tile, truth.ns_per_tile),
            (fit.ns_per_bucket, truth.ns_per_bucket),
            (fit.ns_per_test, truth.ns_per_test),
        ] {
            assert!((a - b).abs() < 1e-6 * b.max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn the_faster_traversal_is_the_one_measured_faster() {
        let tris: Vec<Triangle> = (0..64)
            .map(|k| {
                let z = k as f32 * 0.05;
                Triangle::new(
                    dirt_math::Vec3::new(-1.0, -1.0, z),
                    dirt_math::Vec3::new(1.0, -1.0, z + 0.3),
                    dirt_math::Vec3::new(0.0, 1.0, z),
                )
            })
            .collect();
        let sample = sample_rays(&tris, 300, 7);
        let ads = Ads::build(&tris, &AdsParams::default()).expect("build");
        let c = faster_traversal(&ads, &tris, &sample);
        assert_eq!(c.rays, sample.len());
        assert!(c.linear > std::time::Duration::ZERO && c.hiz > std::time::Duration::ZERO);
        let want = if c.hiz < c.linear {
            Traversal::HiZ
        } else {
            Traversal::Linear
        };
        assert_eq!(c.traversal, want);
        // Whichever it picks traces the same hits.
        let bits = |t| -> Vec<[u32; 4]> {
            crate::trace(&ads, &tris, &sample, t)
                .iter()
                .map(|h| h.bits())
                .collect()
        };
        assert_eq!(bits(Traversal::Linear), bits(Traversal::HiZ));
    }

    #[test]
    fn underdetermined_fit_is_none() {
        let c = Counts::default();
        assert!(CostModel::fit(&[(c, 1.0)], &[(c, 1.0)]).is_none());
    }

    #[test]
    fn choose_ranks_by_predicted_frame_time_and_builds_nothing_wrong() {
        let scene = dirt_math::Vec3::ZERO;
        let tris: Vec<Triangle> = (0..40)
            .map(|k| {
                let z = k as f32 * 0.1;
                Triangle::new(
                    scene + dirt_math::Vec3::new(-1.0, -1.0, z),
                    dirt_math::Vec3::new(1.0, -1.0, z),
                    dirt_math::Vec3::new(0.0, 1.0, z),
                )
            })
            .collect();
        let sample: Vec<Ray> = (0..50)
            .map(|k| {
                let x = k as f32 / 50.0 - 0.5;
                Ray::new(
                    dirt_math::Vec3::new(x, 0.0, -1.0),
                    dirt_math::Vec3::Z,
                    0.0,
                    f32::INFINITY,
                )
            })
            .collect();
        let ranked = choose(
            &tris,
            &sample,
            1_000_000,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &candidates(&AdsParams::default(), true),
        )
        .expect("choose");
        assert_eq!(ranked.len(), 60);
        assert!(ranked.windows(2).all(|w| w[0].frame_ms <= w[1].frame_ms));
        // Counts are exact: more buckets never put fewer nodes in the lists.
        let nodes = |r: u32, b: u32| {
            ranked
                .iter()
                .find(|c| {
                    c.params.resolution == r
                        && c.params.buckets == b
                        && c.params.views == ViewsKind::Cube
                })
                .map(|c| c.counts.nodes)
                .expect("candidate")
        };
        assert!(nodes(64, 16) >= nodes(64, 4));
    }

    #[test]
    fn extents_are_the_triangles_mean_sizes() {
        // Extents (1, 2, 0) and (3, 0, 4); one with a NaN is left out.
        let a = Triangle::new(
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        );
        let b = Triangle::new(
            Vec3::ZERO,
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 4.0),
        );
        let nan = Triangle::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO, Vec3::ONE);
        let e = Extents::of(&[a, nan, b]).expect("two finite triangles");
        // y·z: (2·0 + 0·4) / 2; x·z: (1·0 + 3·4) / 2; x·y: (1·2 + 3·0) / 2.
        assert_eq!(e.cross, [0.0, 6.0, 1.0]);
        // Looking along z at an image 4 wide: x·y over 16.
        assert_eq!(e.area(Axis::Z, 2.0), 1.0 / 16.0);
        assert!(Extents::of(&[nan]).is_none());
        assert!(Extents::of(&[]).is_none());
        // Sums per chunk, added in order: the same bits on any number of threads.
        let many: Vec<Triangle> = sample_rays(&stack(8), 20_000, 3)
            .iter()
            .map(|r| {
                let o = Vec3::from(r.origin);
                Triangle::new(o, o + Vec3::from(r.dir) * 0.1, o + Vec3::X * 0.01)
            })
            .collect();
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| Extents::of(&many))
        };
        assert_eq!(on(1), on(3));
    }

    /// `n × n` small squares' triangles (`size` a side) over the unit
    /// square of the xy plane: the bounds' thinnest axis is z.
    fn tiles_of(n: usize, size: f32) -> Vec<Triangle> {
        let mut out = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let p = Vec3::new(i as f32 / n as f32, j as f32 / n as f32, 0.0);
                out.push(Triangle::new(p, p + Vec3::X * size, p + Vec3::Y * size));
            }
        }
        out
    }

    #[test]
    fn an_orthographic_guess_is_about_a_tile_a_triangle() {
        let res = [8, 16, 32, 64, 128, 256];
        let ortho = AdsParams {
            views: ViewsKind::Ortho,
            ..AdsParams::default()
        };
        let guesses = |tris: &[Triangle], place: &AdsParams| {
            let sizes = Extents::of(tris).map(|e| (Aabb::of_triangles(tris), e));
            first_guesses_at(sizes.as_ref(), tris.len(), place, &res)
        };
        // 2,025 specks: about a triangle a tile at sqrt(2025) = 45, between r32 and r64.
        let specks = tiles_of(45, 1e-4);
        assert_eq!(specks.len(), 2025);
        assert_eq!(guesses(&specks, &ortho), vec![32, 64]);
        // 64 triangles, each about a quarter of the image wide: a tile each
        // near r4, below every candidate, so the coarsest alone.
        let large = tiles_of(8, 0.25);
        assert_eq!(guesses(&large, &ortho), vec![8]);
        // A perspective placement keeps sqrt(triangles / views).
        let single = AdsParams {
            views: ViewsKind::Single,
            ..AdsParams::default()
        };
        assert_eq!(
            guesses(&specks, &single),
            vec![first_guess(2025, ViewsKind::Single, &res)]
        );
        // The search builds the orthographic guess first: with one frame's
        // budget for a few rays, the coarser one is built.
        let sample = sample_rays(&specks, 200, 5);
        let a = auto(
            &specks,
            &sample,
            10,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &candidates_all(&AdsParams::default(), &specks),
        )
        .expect("auto");
        assert!(
            a.ranked.iter().any(|c| c.params.views == ViewsKind::Ortho
                && c.params.resolution == 32
                && c.params.buckets == 8),
            "{:?}",
            a.ranked.iter().map(|c| c.params).collect::<Vec<_>>()
        );
    }

    fn stack(n: usize) -> Vec<Triangle> {
        (0..n)
            .map(|k| {
                let z = k as f32 * 0.1;
                Triangle::new(
                    dirt_math::Vec3::new(-1.0, -1.0, z),
                    dirt_math::Vec3::new(1.0, -1.0, z),
                    dirt_math::Vec3::new(0.0, 1.0, z),
                )
            })
            .collect()
    }

    #[test]
    fn rank_correlation_of_known_series() {
        let a = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(rank_correlation(&a, &[10.0, 20.0, 30.0, 40.0]), Some(1.0));
        assert_eq!(rank_correlation(&a, &[4.0, 3.0, 2.0, 1.0]), Some(-1.0));
        // Ranks (1, 2, 3, 4) against (2, 1, 4, 3): 1 - 6·4 / (4·15) = 0.6.
        let r = rank_correlation(&a, &[2.0, 1.0, 4.0, 3.0]).expect("defined");
        assert!((r - 0.6).abs() < 1e-12, "{r}");
        // Ties share their mean rank; a constant series has no correlation.
        assert!(rank_correlation(&a, &[1.0, 1.0, 1.0, 1.0]).is_none());
        assert!(rank_correlation(&[1.0], &[1.0]).is_none());
    }

    #[test]
    fn sample_rays_start_on_the_triangles_and_are_deterministic() {
        let tris = stack(5);
        let a = sample_rays(&tris, 300, 9);
        assert_eq!(a.len(), 300);
        assert_eq!(a, sample_rays(&tris, 300, 9));
        assert_ne!(a, sample_rays(&tris, 300, 10));
        for r in &a {
            assert!(r.validate().is_ok(), "{r:?}");
            // Origins lie in the stack's planes z = 0.0, 0.1, …, 0.4.
            let z = r.origin[2] * 10.0;
            assert!(
                (z - z.round()).abs() < 1e-3 && (-1e-3..=4.001).contains(&z),
                "{r:?}"
            );
        }
        assert!(sample_rays(&[], 10, 1).is_empty());
        // A stride of the caller's rays: every third of 300 for 100, all of a short list.
        let s = stride_sample(&a, 100);
        assert_eq!(s.len(), 100);
        assert_eq!((s[0], s[1], s[99]), (a[0], a[3], a[297]));
        assert_eq!(stride_sample(&a[..7], 100), a[..7].to_vec());
        assert!(stride_sample(&[], 100).is_empty());
    }

    #[test]
    fn a_kept_choice_searches_further() {
        let tris = stack(40);
        let sample = sample_rays(&tris, 200, 1);
        let cands = candidates(&AdsParams::default(), true);
        let run = |budget: f64| {
            auto_budgeted(
                &tris,
                &sample,
                1_000,
                Traversal::HiZ,
                &CostModel::CALIBRATED,
                &cands,
                None,
                budget,
            )
            .expect("auto")
        };
        let (once, kept) = (run(AUTO_BUDGET), run(KEPT_BUDGET));
        assert!(
            kept.ranked.len() > once.ranked.len(),
            "{} vs {}",
            kept.ranked.len(),
            once.ranked.len()
        );
        assert!(kept.best.frame_ms <= once.best.frame_ms);
        assert!(kept.spent_ms > once.spent_ms);
    }

    #[test]
    fn auto_prunes_candidates_and_its_best_is_the_best_it_built() {
        let tris = stack(40);
        let sample = sample_rays(&tris, 200, 1);
        let cands = candidates(&AdsParams::default(), true);
        let full = choose(
            &tris,
            &sample,
            1_000,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &cands,
        )
        .expect("choose");
        let a = auto(
            &tris,
            &sample,
            1_000,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &cands,
        )
        .expect("auto");
        // Few rays: the builds dominate, so most candidates are never built.
        assert!(a.skipped > 0, "{a:?}");
        assert_eq!(a.ranked.len() + a.skipped, cands.len());
        assert!(a.ranked.windows(2).all(|w| w[0].frame_ms <= w[1].frame_ms));
        assert_eq!(a.best.params, a.ranked[0].params);
        // Pruning skips only candidates the exhaustive ranking also puts after the choice.
        let pos = |p: &AdsParams| full.iter().position(|c| c.params == *p).expect("candidate");
        for c in &a.ranked {
            assert_eq!(
                full[pos(&c.params)].frame_ms,
                c.frame_ms,
                "counts are exact"
            );
        }
        let at_best = pos(&a.best.params);
        assert!(
            full[at_best].frame_ms <= 1.5 * full[0].frame_ms,
            "{:?} vs {:?}",
            a.best,
            full[0]
        );
        assert!(a.spent_ms > 0.0);
        // The winner's structure comes with the choice.
        assert_eq!(
            a.best_ads.as_ref().map(|ads| ads.params),
            Some(a.best.params)
        );
        // A frame of many rays is worth a longer search, and it lands near the exhaustive best.
        let many = auto(
            &tris,
            &sample,
            1_000_000_000,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &cands,
        )
        .expect("auto");
        assert!(
            many.ranked.len() > a.ranked.len(),
            "{} vs {}",
            many.ranked.len(),
            a.ranked.len()
        );
        let full_many = choose(
            &tris,
            &sample,
            1_000_000_000,
            Traversal::HiZ,
            &CostModel::CALIBRATED,
            &cands,
        )
        .expect("choose");
        assert!(many.best.frame_ms <= 1.5 * full_many[0].frame_ms);
        assert!(
            auto(
                &tris,
                &sample,
                1,
                Traversal::HiZ,
                &CostModel::CALIBRATED,
                &[]
            )
            .is_err()
        );
    }
}
