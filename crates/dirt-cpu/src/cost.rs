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
use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_math::{Ray, Triangle};

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
    /// spheres over resolution {64, 128, 256} × B {1, 4, 8, 16, 32} × S {1, 2}
    /// × {linear, Hi-Z} (240 traces, 120 builds), on a 2-core x86-64 machine
    /// that other builds were sharing. Median relative error of the fit on
    /// those measurements: 35 % for trace time per ray, 61 % for build time.
    /// That is good enough to rank candidates whose costs differ by factors,
    /// not to predict milliseconds.
    pub const CALIBRATED: CostModel = CostModel {
        ns_per_node: 188.0,
        ns_per_list: 0.0,
        ns_per_triangle_view: 734.4,
        ns_per_ray: 1217.0,
        ns_per_tile: 19.65,
        ns_per_bucket: 76.0,
        ns_per_test: 17.11,
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
}

/// The candidates the model ranks: face resolution {64, 128, 256} × B {4, 8, 16}
/// (S = 1; a tile of S pixels is the same structure as resolution / S), with
/// the views and centre of `base`; with `both_views` and no centre, for the
/// cube and for the single view too (placed outside the bounds, the single
/// view sees the whole scene, so it is exact for every ray as the cube is).
pub fn candidates(base: &AdsParams, both_views: bool) -> Vec<AdsParams> {
    let views = if both_views && base.center.is_none() {
        vec![ViewsKind::Cube, ViewsKind::Single]
    } else {
        vec![base.views]
    };
    let mut out = Vec::new();
    for views in views {
        for resolution in [64, 128, 256] {
            for buckets in [4, 8, 16] {
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
        let counts = Counts::measure(&ads, tris, sample, traversal);
        out.push(Candidate {
            params: *p,
            counts,
            build_ms: model.build_ms(&counts),
            ray_ns: model.ray_ns(&counts),
            frame_ms: model.frame_ms(&counts, rays_per_frame),
            bytes: ads.memory().total(),
        });
    }
    out.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(ranked.len(), 18);
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
}
