//! dirt-cpu: the CPU reference of every DIRT stage (API skeleton; bodies land with the stages).

use dirt_math::{Hit, Ray, Triangle, Vec3};

/// Which set of views covers the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ViewsKind {
    /// Six 90° perspective views around the centre (004 §3.2).
    #[default]
    Cube,
    /// One perspective view placed outside the scene, fitted to its bounds.
    Single,
}

/// How `trace` walks the tiles a ray crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Traversal {
    /// Conservative 2D DDA over the finest tiles.
    #[default]
    Linear,
    /// Hierarchical stepping over the Hi-Z pyramid.
    HiZ,
}

/// Build parameters of the acceleration structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdsParams {
    pub views: ViewsKind,
    /// Face resolution in pixels (square faces).
    pub resolution: u32,
    /// Depth buckets per tile (B).
    pub buckets: u32,
    /// Tile size in pixels (S).
    pub tile: u32,
    /// View centre; `None` = centre of the scene bounds.
    pub center: Option<Vec3>,
}

impl Default for AdsParams {
    fn default() -> Self {
        Self { views: ViewsKind::Cube, resolution: 128, buckets: 8, tile: 1, center: None }
    }
}

/// Errors of the CPU backend.
#[derive(Debug, thiserror::Error)]
pub enum CpuError {
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
}

/// Per-ray traversal statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayStats {
    pub tiles: u32,
    pub buckets: u32,
    pub tests: u32,
}

/// Structure statistics (printed by `dirt info`).
#[derive(Clone, Debug, Default)]
pub struct AdsStats {}

impl std::fmt::Display for AdsStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "(statistics pending)")
    }
}

/// Memory per structure next to the 001 Table 3 model (printed by `dirt info`).
#[derive(Clone, Debug, Default)]
pub struct MemoryReport {}

impl std::fmt::Display for MemoryReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "(memory pending)")
    }
}

/// The acceleration structure.
#[derive(Debug)]
pub struct Ads {}

impl Ads {
    pub fn build(_tris: &[Triangle], _params: &AdsParams) -> Result<Ads, CpuError> {
        Err(CpuError::InvalidParams("not built yet".into()))
    }
    pub fn stats(&self) -> AdsStats {
        AdsStats::default()
    }
    pub fn memory(&self) -> MemoryReport {
        MemoryReport::default()
    }
}

/// Ground truth: every ray against every triangle with the same triangle test.
pub mod brute_force {
    use dirt_math::{Hit, Ray, Triangle};
    pub fn trace(_tris: &[Triangle], rays: &[Ray]) -> Vec<Hit> {
        vec![Hit::MISS; rays.len()]
    }
}

/// Closest hits of `rays` through the structure.
pub fn trace(_ads: &Ads, _tris: &[Triangle], rays: &[Ray], _traversal: Traversal) -> Vec<Hit> {
    vec![Hit::MISS; rays.len()]
}
