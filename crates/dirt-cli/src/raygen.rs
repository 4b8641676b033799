//! Test rays for a scene (`dirt rays`, `dirt bench`): the generator of
//! `dirt_eval::rays`, with the `--kind` names of the command line.

use clap::ValueEnum;
use dirt_math::{Ray, Triangle};

pub use dirt_eval::rays::Camera;

/// Which rays `dirt rays` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RayKind {
    /// All families below, interleaved (the default; use it for exactness checks).
    Mixed,
    /// Primary rays of a pinhole camera outside the scene looking at its centre.
    Camera,
    /// Origins inside and outside the bounds towards random points in them.
    Random,
    /// Origins inside the bounds and on surfaces, in random directions.
    Inside,
}

impl From<RayKind> for dirt_eval::rays::RayKind {
    fn from(k: RayKind) -> Self {
        match k {
            RayKind::Mixed => Self::Mixed,
            RayKind::Camera => Self::Camera,
            RayKind::Random => Self::Random,
            RayKind::Inside => Self::Inside,
        }
    }
}

/// `count` rays of `kind` for `tris`, deterministic for `seed`; see
/// [`dirt_eval::rays::generate`].
pub fn generate(
    tris: &[Triangle],
    camera: Option<Camera>,
    kind: RayKind,
    count: usize,
    seed: u64,
) -> Result<Vec<Ray>, String> {
    dirt_eval::rays::generate(tris, camera, kind.into(), count, seed).map_err(|e| e.to_string())
}
