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
//! * the error of every setting: rays whose hit differs from brute force's;
//! * the per-frame cost (rebuild + trace) on a deforming scene ([`dynamic`]);
//! * the image error (RMSE, FLIP) of path-traced renders against a converged
//!   reference as samples accumulate, against wall time ([`renders`]).
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
//! [`renders`] and [`peers`], which use [`measure`] (a leaf), never the harness.
//!
//! Thread counts: DIRT's CPU stages, brute force and the peers' traces run on
//! rayon's global pool; Embree builds with the same number of threads; the
//! obvhs build is single-threaded.

pub mod dynamic;
pub mod harness;
pub mod leave_out;
pub mod measure;
pub mod peers;
pub mod plot;
pub mod rays;
pub mod renders;
pub mod report;

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

/// How many of the compared rays differ from the truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Disagreement {
    /// Rays compared (a prefix of the traced rays).
    pub compared: usize,
    /// Rays whose hit differs (see [`Match`]).
    pub differ: usize,
    /// Rays whose primitive (or hit/miss) differs.
    pub differ_prim: usize,
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
        assert_eq!(
            compare(&got, &truth, Match::Bits),
            Disagreement {
                compared: 5,
                differ: 4,
                differ_prim: 2
            }
        );
        // One ulp of t is within the peers' tolerance; another primitive is not.
        assert_eq!(
            compare(&got, &truth, Match::PEER),
            Disagreement {
                compared: 5,
                differ: 2,
                differ_prim: 2
            }
        );
        let far = Hit { t: 2.1, ..a };
        assert_eq!(compare(&[far], &[a], Match::PEER).differ, 1);
        assert_eq!(compare(&got[..2], &truth, Match::Bits).compared, 2);
        // -0.0 == 0.0 as floats, but not as bits.
        let (z, nz) = (Hit { u: 0.0, ..a }, Hit { u: -0.0, ..a });
        assert_eq!(compare(&[z], &[nz], Match::Bits).differ, 1);
    }
}
