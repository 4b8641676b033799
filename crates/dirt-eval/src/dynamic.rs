//! A fully dynamic scene: a displaced grid whose every vertex moves every
//! frame (a travelling wave), so every structure must be rebuilt each frame.
//! Per frame: rebuild + trace of the same camera rays, DIRT (CPU, default
//! setting, linear traversal) and each peer, with brute force on a prefix of
//! the rays as the truth. Every tracer is measured by [`crate::measure`].

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_math::{Ray, Triangle, Vec3};
use indicatif::ProgressBar;
use serde::Serialize;

use crate::measure::{self, StatsPass, median};
use crate::peers::{Peer, unavailable};
use crate::rays::{self, Camera, RayKind};
use crate::{EvalError, Match, compare};

/// Size of the deforming scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DynamicConfig {
    /// Quads per side: `2·grid²` triangles.
    pub grid: usize,
    pub frames: usize,
    /// Camera rays per frame.
    pub rays: usize,
}

/// One frame of one backend.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicRow {
    pub backend: String,
    pub frame: usize,
    pub triangles: usize,
    pub rays: usize,
    pub build_ms: f64,
    pub trace_ms: f64,
    pub frame_ms: f64,
    pub compared: usize,
    pub differ: usize,
    pub differ_prim: usize,
}

/// Rays compared with brute force per frame.
const TRUTH_RAYS: usize = 500;

/// The grid at time `t`: `[-1, 1]²` in x/z, heights a travelling wave plus
/// a moving bump, so neighbouring quads tilt differently every frame.
pub fn wave_grid(n: usize, t: f32) -> Vec<Triangle> {
    let n = n.max(1);
    let h = |i: usize, j: usize| {
        let x = -1.0 + 2.0 * i as f32 / n as f32;
        let z = -1.0 + 2.0 * j as f32 / n as f32;
        let (bx, bz) = (0.6 * t.cos(), 0.6 * t.sin());
        let bump = 0.4 * (-8.0 * ((x - bx).powi(2) + (z - bz).powi(2))).exp();
        let y = 0.15 * (6.0 * x + 3.0 * t).sin() * (5.0 * z - 2.0 * t).cos() + bump;
        Vec3::new(x, y, z)
    };
    let mut tris = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (h(i, j), h(i + 1, j), h(i + 1, j + 1), h(i, j + 1));
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    tris
}

/// The camera looking down at the grid at an angle.
fn camera() -> Option<Camera> {
    Camera::perspective(
        Vec3::new(0.0, 1.6, 2.4),
        Vec3::new(0.0, -1.5, -2.4),
        Vec3::Y,
        50f32.to_radians(),
        4.0 / 3.0,
    )
}

/// A tracer of the dynamic scene, with the name of its rows and how its hits are judged.
struct Entry {
    backend: &'static str,
    tracer: Box<dyn Tracer>,
    how: Match,
    /// A peer: skipped (and noted once) when its library cannot do the work.
    peer: bool,
    skipped: bool,
}

/// Runs the frames; peers that cannot start or build are noted and skipped.
pub fn run(
    cfg: &DynamicConfig,
    peers: &[Peer],
    threads: usize,
    seed: u64,
    pb: &ProgressBar,
    notes: &mut Vec<String>,
) -> Result<Vec<DynamicRow>, EvalError> {
    let mut entries = vec![Entry {
        backend: "dirt-cpu",
        tracer: Box::new(DirtCpu::new(AdsParams::default(), Traversal::Linear)),
        how: Match::Bits,
        peer: false,
        skipped: false,
    }];
    for peer in peers {
        match (peer.make)(threads) {
            Ok(tracer) => entries.push(Entry {
                backend: peer.name,
                tracer,
                how: Match::PEER,
                peer: true,
                skipped: false,
            }),
            Err(e) if unavailable(&e) => notes.push(format!("dynamic scene: {e}")),
            Err(source) => return Err(build_err(source)),
        }
    }
    let mut rows = Vec::new();
    for frame in 0..cfg.frames {
        let tris = wave_grid(cfg.grid, 0.35 * frame as f32);
        let rays: Vec<Ray> = rays::generate(&tris, camera(), RayKind::Camera, cfg.rays, seed)?;
        let n = TRUTH_RAYS.min(rays.len());
        let truth = dirt_cpu::brute_force::trace(&tris, &rays[..n]);
        for e in entries.iter_mut().filter(|e| !e.skipped) {
            let built = measure::build(e.tracer.as_mut(), &tris, 1);
            let built = match built {
                Ok(b) => b,
                Err(err) if e.peer && unavailable(&err) => {
                    notes.push(format!("dynamic scene: {err}"));
                    e.skipped = true;
                    continue;
                }
                Err(source) => return Err(build_err(source)),
            };
            let traced = measure::trace(e.tracer.as_mut(), &rays, 1, StatsPass::Prefix(0))
                .map_err(|source| EvalError::Trace {
                    scene: SCENE.into(),
                    source,
                })?;
            let d = compare(&traced.hits, &truth, e.how);
            rows.push(DynamicRow {
                backend: e.backend.to_string(),
                frame,
                triangles: tris.len(),
                rays: rays.len(),
                build_ms: built.build_ms,
                trace_ms: traced.trace_ms,
                frame_ms: built.build_ms + traced.trace_ms,
                compared: d.compared,
                differ: d.differ,
                differ_prim: d.differ_prim,
            });
        }
        pb.inc(1);
    }
    Ok(rows)
}

/// The name of the deforming scene in errors.
const SCENE: &str = "wave";

fn build_err(source: dirt_core::CoreError) -> EvalError {
    EvalError::Build {
        scene: SCENE.into(),
        source,
    }
}

/// Median per-frame figures of one backend: `(build, trace, frame)` in ms.
pub fn medians(rows: &[DynamicRow], backend: &str) -> Option<(f64, f64, f64)> {
    let of: Vec<&DynamicRow> = rows.iter().filter(|r| r.backend == backend).collect();
    if of.is_empty() {
        return None;
    }
    Some((
        median(of.iter().map(|r| r.build_ms).collect()),
        median(of.iter().map(|r| r.trace_ms).collect()),
        median(of.iter().map(|r| r.frame_ms).collect()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_moves_every_vertex_between_frames() {
        let a = wave_grid(8, 0.0);
        let b = wave_grid(8, 0.35);
        assert_eq!(a.len(), 128);
        assert_eq!(b.len(), 128);
        let moved = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| (0..3).any(|k| x.vertex(k) != y.vertex(k)))
            .count();
        assert_eq!(moved, 128);
        assert!(a.iter().all(Triangle::is_finite));
    }
}
