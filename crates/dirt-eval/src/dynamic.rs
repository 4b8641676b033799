//! A fully dynamic scene: a displaced grid whose every vertex moves every
//! frame (a travelling wave), so every structure must be rebuilt each frame.
//! Per frame: rebuild + trace of the same camera rays, DIRT on the CPU (the
//! library's default, [`DirtCpu::auto`]: the cost model's choice for the frame,
//! made at the first frame's build; and the fixed cube r128 B8 S1 beside it;
//! Hi-Z traversal) and each peer, with brute force on a prefix of the rays as
//! the truth. Every tracer is measured by [`crate::measure`]. It runs once per
//! ray count of [`DynamicConfig`].

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
    /// A second run with this many camera rays per frame (the figure for
    /// frames with many rays), if any.
    pub rays_large: Option<usize>,
}

impl DynamicConfig {
    /// The ray counts of the runs, in order.
    pub fn ray_counts(&self) -> Vec<usize> {
        std::iter::once(self.rays).chain(self.rays_large).collect()
    }
}

/// The dynamic rows' backend name of DIRT at the fixed default setting.
pub const FIXED: &str = "dirt-cpu cube r128 B8 S1";

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
    backend: String,
    tracer: Box<dyn Tracer>,
    how: Match,
    /// A peer: skipped (and noted once) when its library cannot do the work.
    peer: bool,
    skipped: bool,
}

/// Runs the frames for every ray count; peers that cannot start or build
/// are noted and skipped.
pub fn run(
    cfg: &DynamicConfig,
    peers: &[Peer],
    threads: usize,
    seed: u64,
    pb: &ProgressBar,
    notes: &mut Vec<String>,
) -> Result<Vec<DynamicRow>, EvalError> {
    let mut rows = Vec::new();
    for rays in cfg.ray_counts() {
        rows.extend(run_with(cfg, rays, peers, threads, seed, pb, notes)?);
    }
    Ok(rows)
}

fn run_with(
    cfg: &DynamicConfig,
    ray_count: usize,
    peers: &[Peer],
    threads: usize,
    seed: u64,
    pb: &ProgressBar,
    notes: &mut Vec<String>,
) -> Result<Vec<DynamicRow>, EvalError> {
    let dirt = |backend: &str, tracer: DirtCpu| Entry {
        backend: backend.into(),
        tracer: Box::new(tracer),
        how: Match::Bits,
        peer: false,
        skipped: false,
    };
    let mut entries = vec![
        dirt("dirt-cpu", DirtCpu::auto(Traversal::HiZ, ray_count as u64)),
        dirt(FIXED, DirtCpu::new(AdsParams::default(), Traversal::HiZ)),
    ];
    for peer in peers {
        match (peer.make)(threads) {
            Ok(tracer) => entries.push(Entry {
                backend: peer.name.into(),
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
        let rays: Vec<Ray> = rays::generate(&tris, camera(), RayKind::Camera, ray_count, seed)?;
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
            if let Some(ms) = built.stage("choose")
                && frame == 0
            {
                notes.push(format!(
                    "dynamic scene, {} rays per frame: {} is the cost model's choice, made in frame 0's build ({} ms of its {} ms; later frames keep it)",
                    rays.len(),
                    e.tracer.name(),
                    format_ms(ms),
                    format_ms(built.build_ms)
                ));
            }
            rows.push(DynamicRow {
                backend: e.backend.clone(),
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

/// Milliseconds with at most three decimals (trailing zeros dropped).
fn format_ms(ms: f64) -> String {
    format!("{ms:.3}")
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
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
