//! dirt-eval: the evaluation harness behind `dirt eval`.
//!
//! Over a set of scenes and a grid of structure parameters it measures, in
//! one run on the same triangles and rays:
//!
//! * build time per stage, memory per structure next to the model of 001
//!   Table 3, trace speed per ray type of 001 Table 1 ([`rays::RayType`]) and
//!   traversal, and traversal statistics (tiles, buckets, tests per ray), for
//!   DIRT on the CPU and (on small scenes) on the GPU;
//! * the same build and trace figures for the peers ([`peers`]: obvhs and,
//!   with the `embree` feature, Embree 3);
//! * the error of every setting: rays whose hit differs from brute force's,
//!   split into another primitive, missed and false hits, with the relative
//!   error of `t` ([`Disagreement`]);
//! * the seeds' approximate tracers ([`approx`]: MMRT's A-buffer and one
//!   depth layer) with their knobs swept, so that error against time is a
//!   trade, and the compact grid's density swept;
//! * the per-frame cost (rebuild + trace) on a deforming scene ([`dynamic`]);
//! * the image error (RMSE, FLIP) of path-traced renders against a converged
//!   reference as samples accumulate, against wall time ([`renders`]);
//! * DIRT at the headline's setting beside each peer in alternated rounds,
//!   whose ratios come with their spread ([`side`]).
//!
//! Every figure is taken by [`measure`], one measuring path over
//! `&mut dyn dirt_core::Tracer` (DIRT on the CPU and GPU, brute force and the
//! peers are all tracers), which also makes the rows of the report. Adding a
//! tracer to the evaluation: implement `Tracer`, add its line to
//! [`peers::available`].
//!
//! [`report`] writes CSV, JSON, Markdown and plots ([`plot`]).
//!
//! Imports go one way: [`harness`] uses [`dynamic`], [`leave_out`],
//! [`renders`], [`side`] and [`peers`], which use [`measure`] (a leaf), never
//! the harness.
//!
//! Thread counts: DIRT's CPU stages, brute force and the peers' traces run on
//! rayon's global pool; Embree builds with the same number of threads; the
//! obvhs build is single-threaded.

pub mod approx;
pub mod dynamic;
pub mod harness;
pub mod leave_out;
pub mod measure;
pub mod peers;
pub mod plot;
pub mod rays;
pub mod renders;
pub mod report;
pub mod side;

pub use harness::{EvalConfig, EvalResults, run};

use dirt_math::Hit;

/// Errors of the harness.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error("cannot make rays: {0}")]
    Rays(String),
    #[error("scene {spec}: {source}")]
    Scene {
        spec: String,
        #[source]
        source: dirt_scene::SceneError,
    },
    #[error("scene {scene}: cannot build the structure: {source}")]
    Build {
        scene: String,
        #[source]
        source: dirt_core::CoreError,
    },
    /// A peer library's own error, in its words (the source of a
    /// `CoreError::Backend` naming the peer).
    #[error("{0}")]
    Peer(String),
    #[error("scene {scene}: cannot trace: {source}")]
    Trace {
        scene: String,
        #[source]
        source: dirt_core::CoreError,
    },
    #[error("cannot write {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {path}: {message}")]
    Output { path: String, message: String },
    #[error("render: {0}")]
    Render(String),
    #[error("invalid configuration: {0}")]
    Config(String),
}

impl EvalError {
    /// For `map_err`: a failed build of `scene`.
    pub fn build_of(scene: &str) -> impl Fn(dirt_core::CoreError) -> EvalError + Copy + '_ {
        move |source| EvalError::Build {
            scene: scene.to_string(),
            source,
        }
    }

    /// For `map_err`: a failed trace of `scene`.
    pub fn trace_of(scene: &str) -> impl Fn(dirt_core::CoreError) -> EvalError + Copy + '_ {
        move |source| EvalError::Trace {
            scene: scene.to_string(),
            source,
        }
    }
}

/// How many of the compared rays differ from the truth, and how.
///
/// Every ray whose primitive differs is exactly one of `other_prim` (both
/// hit, another primitive), `missed` (the truth hits, the tracer misses) and
/// `false_hits` (the truth misses, the tracer hits): their sum is
/// `differ_prim`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Disagreement {
    /// Rays compared (a prefix of the traced rays).
    pub compared: usize,
    /// Rays whose hit differs (see [`Match`]).
    pub differ: usize,
    /// Rays whose primitive (or hit/miss) differs.
    pub differ_prim: usize,
    /// Both hit, another primitive.
    pub other_prim: usize,
    /// The truth hits, the tracer misses.
    pub missed: usize,
    /// The truth misses, the tracer hits.
    pub false_hits: usize,
    /// Rays where both hit (any primitive): the ones `t` is compared on.
    pub both_hit: usize,
    /// Mean of `|t - t_true| / t_true` over the rays where both hit (0 when none).
    pub t_rel_mean: f64,
    /// Largest `|t - t_true| / t_true` over the rays where both hit.
    pub t_rel_max: f64,
}

impl Disagreement {
    /// `count` in % of the compared rays (0 when none were compared).
    pub fn pct(&self, count: usize) -> f64 {
        100.0 * count as f64 / self.compared.max(1) as f64
    }
}

/// What counts as the same hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Match {
    /// Every bit of `prim, t, u, v` (DIRT: same triangle test as brute force).
    Bits,
    /// The same `prim` and `t` within a relative tolerance: peers use their
    /// own triangle tests, whose `t` differs from brute force's in the last
    /// bits, and report no barycentrics here.
    Within { t_rel: f32 },
}

impl Match {
    /// The tolerance the peers are held to.
    pub const PEER: Match = Match::Within { t_rel: 1e-4 };
}

/// Compares `got` with `truth` over their common prefix.
pub fn compare(got: &[Hit], truth: &[Hit], how: Match) -> Disagreement {
    let n = got.len().min(truth.len());
    let mut d = Disagreement {
        compared: n,
        ..Disagreement::default()
    };
    let mut t_rel_sum = 0.0f64;
    for (g, t) in got[..n].iter().zip(&truth[..n]) {
        let same = match how {
            Match::Bits => g.bits() == t.bits(),
            Match::Within { t_rel } => {
                g.prim == t.prim
                    && (g.t.to_bits() == t.t.to_bits()
                        || (g.t - t.t).abs() <= t_rel * t.t.abs().max(f32::MIN_POSITIVE))
            }
        };
        d.differ += usize::from(!same);
        d.differ_prim += usize::from(g.prim != t.prim);
        match (g.is_hit(), t.is_hit()) {
            (true, true) => {
                d.other_prim += usize::from(g.prim != t.prim);
                d.both_hit += 1;
                let e = if g.t.to_bits() == t.t.to_bits() {
                    0.0
                } else {
                    f64::from((g.t - t.t).abs()) / f64::from(t.t.abs()).max(f64::MIN_POSITIVE)
                };
                t_rel_sum += e;
                d.t_rel_max = d.t_rel_max.max(e);
            }
            (false, true) => d.missed += 1,
            (true, false) => d.false_hits += 1,
            (false, false) => {}
        }
    }
    if d.both_hit > 0 {
        d.t_rel_mean = t_rel_sum / d.both_hit as f64;
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compare_counts_bits_and_prims() {
        let a = Hit {
            prim: 1,
            t: 2.0,
            u: 0.25,
            v: 0.5,
        };
        let b = Hit { u: 0.0, ..a };
        let c = Hit { prim: 2, ..a };
        let d = Hit {
            t: f32::from_bits(2.0f32.to_bits() + 1),
            ..a
        };
        let got = [a, b, c, d, Hit::MISS];
        let truth = [a, a, a, a, a];
        let ulp = f64::from(d.t - a.t) / 2.0;
        let expected = Disagreement {
            compared: 5,
            differ: 4,
            differ_prim: 2,
            other_prim: 1,
            missed: 1,
            false_hits: 0,
            both_hit: 4,
            t_rel_mean: ulp / 4.0,
            t_rel_max: ulp,
        };
        assert_eq!(compare(&got, &truth, Match::Bits), expected);
        // One ulp of t is within the peers' tolerance; another primitive is not.
        assert_eq!(
            compare(&got, &truth, Match::PEER),
            Disagreement {
                differ: 2,
                ..expected
            }
        );
        // A hit where the truth misses is a false hit.
        let f = compare(&[a, Hit::MISS], &[Hit::MISS, Hit::MISS], Match::Bits);
        assert_eq!(
            (f.false_hits, f.missed, f.both_hit, f.differ_prim),
            (1, 0, 0, 1)
        );
        assert_eq!((f.t_rel_mean, f.pct(f.false_hits)), (0.0, 50.0));
        let far = Hit { t: 2.1, ..a };
        assert_eq!(compare(&[far], &[a], Match::PEER).differ, 1);
        assert_eq!(compare(&got[..2], &truth, Match::Bits).compared, 2);
        // -0.0 == 0.0 as floats, but not as bits.
        let (z, nz) = (Hit { u: 0.0, ..a }, Hit { u: -0.0, ..a });
        assert_eq!(compare(&[z], &[nz], Match::Bits).differ, 1);
    }
}
