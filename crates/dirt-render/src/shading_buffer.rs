//! The shading buffer: per path the three path points G(k-1), G(k) and
//! G(k+1) of the current bounce, the direction sampled at G(k), and the
//! path's throughput and radiance.

use crate::fetch::SurfacePoint;
use dirt_math::Vec3;

/// The state a path carries between bounces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathState {
    /// Product of `f·cos/pdf` (and roulette) along the path so far.
    pub throughput: Vec3,
    /// Radiance gathered by this sample of the path's pixel.
    pub radiance: Vec3,
    pub alive: bool,
}

/// The direction sampled at G(k) towards G(k+1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    pub dir: Vec3,
    /// `f·cos/pdf` of the BSDF at G(k) between G(k-1) and G(k+1).
    pub weight: Vec3,
    /// Solid-angle pdf (0 for a delta lobe).
    pub pdf: f32,
    pub delta: bool,
}

/// One entry per path (per pixel of the image).
#[derive(Clone, Debug, Default)]
pub struct ShadingBuffer {
    /// G(k-1): the previous vertex (the eye for k = 1).
    pub prev: Vec<Vec3>,
    /// G(k): the current surface point (`None`: the path left the scene).
    pub cur: Vec<Option<SurfacePoint>>,
    /// G(k+1): what the ray sampled at G(k) hit.
    pub next: Vec<Option<SurfacePoint>>,
    /// The sampling record of the ray from G(k) (`None`: no ray left G(k)).
    pub scatter: Vec<Option<Scatter>>,
    pub paths: Vec<PathState>,
}

impl ShadingBuffer {
    /// Paths with G(1) = `primary`, seen from `eye`.
    pub fn new(eye: Vec<Vec3>, primary: Vec<Option<SurfacePoint>>) -> Self {
        let n = primary.len();
        Self {
            prev: eye,
            cur: primary,
            next: vec![None; n],
            scatter: vec![None; n],
            paths: vec![
                PathState {
                    throughput: Vec3::ONE,
                    radiance: Vec3::ZERO,
                    alive: true,
                };
                n
            ],
        }
    }

    pub fn len(&self) -> usize {
        self.paths.len()
    }

    pub fn is_empty(&self) -> bool {
        self.paths.is_empty()
    }
}
