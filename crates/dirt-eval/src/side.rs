//! Side by side: DIRT at the headline's setting and each peer, measured in
//! alternated rounds, so that their ratio is read from measurements taken
//! moments apart.
//!
//! The headline tables measure every backend in turn, seconds to minutes
//! apart, and on a shared machine the speed of the cores drifts over that
//! time (a peer's trace has read 1.5 times faster in one run than in the
//! next, with nothing changed). Here each round builds DIRT and the peer,
//! then traces every ray type through one and then through the other (DIRT
//! with each traversal), their order swapped every round; a round gives one ratio of
//! each kind, and the report gives their median and their range over the
//! rounds. The hits of every round are compared with brute force's, as in
//! the headline.

use dirt_core::{AdsParams, CoreError, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_math::{Hit, Ray, Triangle};
use serde::Serialize;

use crate::measure::{self, StatsPass, median};
use crate::peers::Peer;
use crate::{EvalError, Match, compare};

/// One round of one scene against one peer. Times in ms: builds are the
/// medians of [`measure::build`], traces the sums over the ray types of the
/// medians of [`measure::trace`].
#[derive(Clone, Debug, Serialize)]
pub struct SideRow {
    pub scene: String,
    pub peer: String,
    /// DIRT's setting ([`measure::Setting::label`]).
    pub setting: String,
    /// The round, from 0.
    pub round: u32,
    /// Whether DIRT was measured before the peer in this round (builds and
    /// each ray type alike).
    pub dirt_first: bool,
    pub dirt_build_ms: f64,
    pub peer_build_ms: f64,
    /// DIRT's trace of every ray, linear traversal (`None`: not run).
    pub dirt_linear_ms: Option<f64>,
    /// The same with the Hi-Z traversal.
    pub dirt_hiz_ms: Option<f64>,
    pub peer_trace_ms: f64,
    pub rays: usize,
    /// Rays of the compared prefixes whose hit differs from brute force:
    /// DIRT any bit, over every traversal; the peer as the headline judges it.
    pub dirt_differ: usize,
    pub peer_differ: usize,
    /// Rays compared: DIRT's over its traversals, the peer's.
    pub dirt_compared: usize,
    pub peer_compared: usize,
}

impl SideRow {
    /// DIRT / peer build time.
    pub fn build_ratio(&self) -> f64 {
        self.dirt_build_ms / self.peer_build_ms
    }

    /// DIRT / peer trace time with `traversal`, where it was run.
    pub fn trace_ratio(&self, traversal: Traversal) -> Option<f64> {
        let dirt = match traversal {
            Traversal::Linear => self.dirt_linear_ms,
            Traversal::HiZ => self.dirt_hiz_ms,
        }?;
        Some(dirt / self.peer_trace_ms)
    }

    /// DIRT / peer trace time at DIRT's faster traversal in this round.
    pub fn faster_ratio(&self) -> Option<f64> {
        Traversal::ALL
            .into_iter()
            .filter_map(|t| self.trace_ratio(t))
            .min_by(f64::total_cmp)
    }
}

/// The median and the range of some ratios (`None` for none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<Spread> {
        let v: Vec<f64> = values.into_iter().collect();
        let min = v.iter().copied().min_by(f64::total_cmp)?;
        let max = v.iter().copied().max_by(f64::total_cmp)?;
        Some(Spread {
            median: median(v),
            min,
            max,
        })
    }
}

/// What one scene's rounds need, as the harness prepared it.
#[derive(Debug)]
pub struct Input<'a> {
    pub scene: &'a str,
    pub tris: &'a [Triangle],
    /// The rays of each type; the first `truth[k].len()` of type `k` are compared.
    pub rays: Vec<&'a [Ray]>,
    pub truth: Vec<&'a [Hit]>,
    /// DIRT's setting and its label.
    pub params: AdsParams,
    pub setting: String,
    pub traversals: &'a [Traversal],
    /// Runs of each measurement ([`measure::Runs::Steady`]).
    pub repeat: u32,
    pub rounds: u32,
}

/// Traces every ray type through `tracer`: (the sum of the median times,
/// rays whose hit differs, rays compared).
fn trace_all(
    tracer: &mut dyn Tracer,
    input: &Input<'_>,
    how: Match,
) -> Result<(f64, usize, usize), CoreError> {
    let (mut ms, mut differ, mut compared) = (0.0, 0, 0);
    for (rays, truth) in input.rays.iter().zip(&input.truth) {
        let m = measure::trace(tracer, rays, input.repeat, StatsPass::Prefix(0))?;
        let d = compare(&m.hits, truth, how);
        ms += m.trace_ms;
        differ += d.differ;
        compared += d.compared;
    }
    Ok((ms, differ, compared))
}

/// The rounds of one scene against `peer` (none, and a note, where the
/// peer cannot start).
pub fn run(
    input: &Input<'_>,
    peer: &Peer,
    threads: usize,
    notes: &mut Vec<String>,
) -> Result<Vec<SideRow>, EvalError> {
    let scene = || input.scene.to_string();
    let (build_err, trace_err) = (
        EvalError::build_of(input.scene),
        EvalError::trace_of(input.scene),
    );
    let mut other = match (peer.make)(threads) {
        Ok(t) => t,
        Err(e) if crate::peers::unavailable(&e) => {
            notes.push(format!("side by side, {}: {e}", input.scene));
            return Ok(Vec::new());
        }
        Err(e) => return Err(build_err(e)),
    };
    let mut dirt = DirtCpu::new(input.params, Traversal::Linear);
    let mut rows = Vec::new();
    for round in 0..input.rounds {
        let dirt_first = round % 2 == 0;
        // DIRT first (true) or the peer first, builds and traces alike.
        let order = [dirt_first, !dirt_first];
        let (mut d_build, mut p_build) = (0.0, 0.0);
        for dirt_turn in order {
            if dirt_turn {
                d_build = measure::build(&mut dirt, input.tris, input.repeat)
                    .map_err(build_err)?
                    .build_ms;
            } else {
                p_build = measure::build(other.as_mut(), input.tris, input.repeat)
                    .map_err(build_err)?
                    .build_ms;
            }
        }
        let mut dirt_ms = [None, None];
        let (mut dirt_differ, mut dirt_compared) = (0, 0);
        let (mut peer_ms, mut peer_differ, mut peer_compared) = (0.0, 0, 0);
        for dirt_turn in order {
            if dirt_turn {
                for &trav in input.traversals {
                    dirt.traversal = trav;
                    let (t, d, c) = trace_all(&mut dirt, input, Match::Bits).map_err(trace_err)?;
                    dirt_ms[usize::from(trav == Traversal::HiZ)] = Some(t);
                    dirt_differ += d;
                    dirt_compared += c;
                }
            } else {
                (peer_ms, peer_differ, peer_compared) =
                    trace_all(other.as_mut(), input, peer.how()).map_err(trace_err)?;
            }
        }
        rows.push(SideRow {
            scene: scene(),
            peer: peer.name.to_string(),
            setting: input.setting.clone(),
            round,
            dirt_first,
            dirt_build_ms: d_build,
            peer_build_ms: p_build,
            dirt_linear_ms: dirt_ms[0],
            dirt_hiz_ms: dirt_ms[1],
            peer_trace_ms: peer_ms,
            rays: input.rays.iter().map(|r| r.len()).sum(),
            dirt_differ,
            peer_differ,
            dirt_compared,
            peer_compared,
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spread_is_the_median_and_range_of_its_values() {
        assert_eq!(Spread::of([]), None);
        let s = Spread::of([3.0, 1.0, 2.0, 10.0]).expect("values");
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 10.0));
    }

    #[test]
    fn the_faster_ratio_is_the_faster_traversals() {
        let row = SideRow {
            scene: "s".into(),
            peer: "p".into(),
            setting: "x".into(),
            round: 0,
            dirt_first: true,
            dirt_build_ms: 2.0,
            peer_build_ms: 4.0,
            dirt_linear_ms: Some(6.0),
            dirt_hiz_ms: Some(3.0),
            peer_trace_ms: 2.0,
            rays: 10,
            dirt_differ: 0,
            peer_differ: 0,
            dirt_compared: 20,
            peer_compared: 10,
        };
        assert_eq!(row.build_ratio(), 0.5);
        assert_eq!(row.trace_ratio(Traversal::Linear), Some(3.0));
        assert_eq!(row.faster_ratio(), Some(1.5));
        let linear_only = SideRow {
            dirt_hiz_ms: None,
            ..row
        };
        assert_eq!(linear_only.faster_ratio(), Some(3.0));
    }
}
