//! dirt-cpu: the CPU reference of every DIRT stage, one module per GPU pass
//! with the same name, inputs and outputs:
//!
//! | stage | module | in | out |
//! |---|---|---|---|
//! | `fill_depth` | [`fill_depth`] | views, triangles | per view and tile `[zmin, zmax]` (encoded) |
//! | `mip_depth` | [`mip_depth`] | depth bounds | Hi-Z pyramid |
//! | `fill_primitives` | [`fill_primitives`] | views, depth bounds, triangles | per (view, tile, bucket) id lists |
//! | `trace` | [`trace`] | structure, triangles, rays | closest hits |
//!
//! and [`brute_force`], the ground truth the tests compare `trace` with, and
//! [`cache`], which rebuilds the structure only when geometry or parameters change.

pub mod brute_force;
pub mod cache;
pub mod cost;
pub mod fill_depth;
pub mod fill_primitives;
pub mod mip_depth;
pub mod trace;

pub use cache::{BuildCache, Geometry, Reuse};
pub use dirt_math::ViewsKind;
pub use dirt_math::types::RayStats;
pub use fill_primitives::IdLists;
pub use trace::{trace, trace_with_stats};

use dirt_math::clip::{clip_triangle_to_view, polygon_tile_range};
use dirt_math::dda::hiz_width;
use dirt_math::encode::ordered_to_f32;
use dirt_math::{Aabb, Triangle, Vec3, ViewSet};
use std::fmt;
use std::time::{Duration, Instant};

/// How `trace` walks the tiles a ray crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Traversal {
    /// Conservative 2D DDA over the finest tiles.
    #[default]
    Linear,
    /// Hierarchical stepping through the Hi-Z pyramid.
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
    /// Tile size in pixels (S); must divide `resolution`.
    pub tile: u32,
    /// Cube: the centre of the views. Single: the eye. `None`: the centre of
    /// the scene bounds for the cube; outside the bounds, seeing all of them, for the single view.
    pub center: Option<Vec3>,
}

impl Default for AdsParams {
    fn default() -> Self {
        Self {
            views: ViewsKind::Cube,
            resolution: 128,
            buckets: 8,
            tile: 1,
            center: None,
        }
    }
}

impl AdsParams {
    /// Tiles per side of each view.
    pub fn tiles(&self) -> u32 {
        self.resolution / self.tile.max(1)
    }

    /// Checks the parameters before any work is done.
    pub fn validate(&self) -> Result<(), CpuError> {
        let bad = |m: String| Err(CpuError::InvalidParams(m));
        if self.resolution == 0 || self.resolution > 16384 {
            return bad(format!(
                "resolution must be in 1..=16384, got {}",
                self.resolution
            ));
        }
        if self.tile == 0 || !self.resolution.is_multiple_of(self.tile) {
            return bad(format!(
                "tile size {} must be >= 1 and divide the resolution {}",
                self.tile, self.resolution
            ));
        }
        if self.buckets == 0 || self.buckets > 4096 {
            return bad(format!("buckets must be in 1..=4096, got {}", self.buckets));
        }
        if let Some(c) = self.center
            && !c.is_finite()
        {
            return bad(format!("center must be finite, got {c}"));
        }
        let lists = 6u64 * (self.tiles() as u64).pow(2) * self.buckets as u64;
        if lists >= u32::MAX as u64 {
            return bad(format!(
                "{lists} lists (views × tiles² × buckets) is more than the structure can index"
            ));
        }
        Ok(())
    }
}

/// Errors of the CPU backend.
#[derive(Debug, thiserror::Error)]
pub enum CpuError {
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    #[error("triangle {index} has a non-finite vertex coordinate")]
    NonFiniteTriangle { index: usize },
    #[error(
        "the structure would hold {nodes} list nodes, more than 2^32-1; use fewer buckets or a lower resolution"
    )]
    TooManyNodes { nodes: u64 },
}

/// Wall time of each build stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimings {
    pub fill_depth: Duration,
    pub mip_depth: Duration,
    pub fill_primitives: Duration,
}

impl BuildTimings {
    pub fn total(&self) -> Duration {
        self.fill_depth + self.mip_depth + self.fill_primitives
    }
}

/// Checks `params` and `tris` and makes the view set both backends build over.
///
/// Views that no triangle reaches (see [`views_reached`]) are left out: they
/// get no build passes and no memory, and rays skip them. That changes no hit.
pub fn views_for(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CpuError> {
    let mut views = views_for_all(tris, params)?;
    let keep = views_reached(&views, tris);
    views.leave_out(&keep);
    Ok(views)
}

/// Which views at least one triangle reaches: the triangle, clipped to the
/// view's (dilated) frustum, is not empty and has a tile range. This is the
/// gate `fill_depth` and `fill_primitives` pass before their per-tile tests,
/// so a view that fails it for every triangle has no covered tile, and no
/// hit can lie in it.
pub fn views_reached(views: &ViewSet, tris: &[Triangle]) -> Vec<bool> {
    use rayon::prelude::*;
    views
        .views
        .iter()
        .map(|v| {
            v.has_content
                && tris.par_iter().any(|t| {
                    let tv = [
                        v.to_view(t.vertex(0)),
                        v.to_view(t.vertex(1)),
                        v.to_view(t.vertex(2)),
                    ];
                    clip_triangle_to_view(v, tv)
                        .and_then(|p| polygon_tile_range(v, &p))
                        .is_some()
                })
        })
        .collect()
}

/// Why a view was left out of the structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeftOutReason {
    /// No part of the scene bounds is in front of its near plane.
    BoundsBehind,
    /// The bounds reach it, but no triangle reaches any of its tiles.
    NoTriangleReaches,
}

/// A view [`views_for`] leaves out: no passes, no memory, skipped by rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeftOutView {
    /// Index in the view set.
    pub view: usize,
    /// `+X`, `-X`, `+Y`, `-Y`, `+Z`, `-Z` for a cube face; `single` for the single view.
    pub name: &'static str,
    pub reason: LeftOutReason,
}

/// The views [`views_for`] leaves out for `tris` and `params`, with the reason.
pub fn left_out_views(tris: &[Triangle], params: &AdsParams) -> Result<Vec<LeftOutView>, CpuError> {
    let all = views_for_all(tris, params)?;
    let reached = views_reached(&all, tris);
    const FACES: [&str; 6] = ["+X", "-X", "+Y", "-Y", "+Z", "-Z"];
    Ok(all
        .views
        .iter()
        .enumerate()
        .filter(|&(k, _)| !reached[k])
        .map(|(k, v)| LeftOutView {
            view: k,
            name: match all.kind {
                ViewsKind::Cube => FACES.get(k).copied().unwrap_or("?"),
                ViewsKind::Single => "single",
            },
            reason: if v.has_content {
                LeftOutReason::NoTriangleReaches
            } else {
                LeftOutReason::BoundsBehind
            },
        })
        .collect())
}

/// [`views_for`] without leaving out the views no triangle reaches: every
/// view whose frustum meets the scene bounds is built (the papers'
/// configuration; the baseline that leaving out is measured against).
pub fn views_for_all(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CpuError> {
    params.validate()?;
    if let Some(index) = tris.iter().position(|t| !t.is_finite()) {
        return Err(CpuError::NonFiniteTriangle { index });
    }
    let mut bounds = Aabb::of_triangles(tris);
    if bounds.is_empty() {
        bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
    }
    let tiles = params.tiles();
    Ok(match params.views {
        ViewsKind::Cube => ViewSet::cube(params.center.unwrap_or(bounds.center()), &bounds, tiles),
        ViewsKind::Single => ViewSet::single(params.center, &bounds, tiles),
    })
}

/// The acceleration structure: views, depth bounds with their Hi-Z pyramid,
/// and per-bucket primitive lists.
#[derive(Debug)]
pub struct Ads {
    pub params: AdsParams,
    pub views: ViewSet,
    /// Hi-Z pyramid; level 0 is the depth bounds of `fill_depth`.
    pub hiz: Vec<Vec<[u32; 2]>>,
    pub lists: IdLists,
    pub timings: BuildTimings,
    pub triangles: usize,
}

impl Ads {
    /// Builds the structure: `fill_depth`, `mip_depth`, `fill_primitives`,
    /// over the views of [`views_for`] (views no triangle reaches left out).
    pub fn build(tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        Self::build_over(views_for(tris, params)?, tris, params)
    }

    /// [`Ads::build`] over every view of [`views_for_all`]: nothing left out.
    pub fn build_all_views(tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        Self::build_over(views_for_all(tris, params)?, tris, params)
    }

    fn build_over(views: ViewSet, tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        let t0 = Instant::now();
        let depth = fill_depth::fill_depth(&views, tris);
        let t1 = Instant::now();
        let hiz = mip_depth::mip_depth(&views, &depth);
        let t2 = Instant::now();
        let lists = fill_primitives::fill_primitives(&views, &depth, params.buckets, tris)?;
        let t3 = Instant::now();
        let timings = BuildTimings {
            fill_depth: t1 - t0,
            mip_depth: t2 - t1,
            fill_primitives: t3 - t2,
        };
        Ok(Ads {
            params: *params,
            views,
            hiz,
            lists,
            timings,
            triangles: tris.len(),
        })
    }

    /// Depth bounds per view and tile (Hi-Z level 0).
    pub fn depth(&self) -> &[[u32; 2]] {
        &self.hiz[0]
    }

    /// Cells per side of Hi-Z level `level`.
    pub fn hiz_width(&self, level: u32) -> usize {
        hiz_width(self.params.tiles(), level) as usize
    }

    /// Structure statistics.
    pub fn stats(&self) -> AdsStats {
        let tiles = self.params.tiles();
        let occupied = self
            .depth()
            .iter()
            .filter(|[lo, hi]| ordered_to_f32(*lo) <= ordered_to_f32(*hi))
            .count() as u64;
        let mut max_list = 0;
        let mut nonempty_lists = 0u64;
        for w in self.lists.offsets.windows(2) {
            let n = w[1] - w[0];
            max_list = max_list.max(n);
            nonempty_lists += u64::from(n > 0);
        }
        AdsStats {
            views: self.views.views.len() as u32,
            views_with_content: self.views.views.iter().filter(|v| v.has_content).count() as u32,
            tiles_per_side: tiles,
            occupied_tiles: occupied,
            nodes: self.lists.ids.len() as u64,
            nonempty_lists,
            max_list,
            hiz_levels: self.hiz.len() as u32,
            timings: self.timings,
        }
    }

    /// Memory of each structure, next to the model of 001 Table 3.
    pub fn memory(&self) -> MemoryReport {
        let tiles = self.params.tiles() as u64;
        // Views without content store nothing; the model counts the views stored.
        let views = self.views.slots() as u64;
        let nb = self.params.buckets as u64;
        let nodes = self.lists.ids.len() as u64;
        let depth = views * tiles * tiles * 8;
        let hiz: u64 = self.hiz.iter().skip(1).map(|l| l.len() as u64 * 8).sum();
        let offsets = self.lists.offsets.len() as u64 * 4;
        let ids = nodes * 4;
        MemoryReport {
            entries: vec![
                MemoryEntry {
                    name: "depth bounds",
                    bytes: depth,
                    model: None,
                },
                MemoryEntry {
                    name: "hi-z levels 1..",
                    bytes: hiz,
                    model: None,
                },
                MemoryEntry {
                    name: "depth + hi-z",
                    bytes: depth + hiz,
                    // 001 Table 3: 8 B per tile per view, ×1.33 for the mip chain.
                    model: Some((views * tiles * tiles * 8) as f64 * 4.0 / 3.0),
                },
                MemoryEntry {
                    name: "list offsets",
                    bytes: offsets,
                    model: None,
                },
                MemoryEntry {
                    name: "list ids",
                    bytes: ids,
                    model: None,
                },
                MemoryEntry {
                    name: "id buffer",
                    bytes: offsets + ids,
                    // 001 Table 3: 4·B bytes of heads per tile + 8 B (id, next) per node.
                    model: Some((views * tiles * tiles * 4 * nb + 8 * nodes) as f64),
                },
            ],
        }
    }
}

/// Structure statistics (printed by `dirt info`).
#[derive(Clone, Debug, Default)]
pub struct AdsStats {
    pub views: u32,
    pub views_with_content: u32,
    pub tiles_per_side: u32,
    pub occupied_tiles: u64,
    pub nodes: u64,
    pub nonempty_lists: u64,
    pub max_list: u32,
    pub hiz_levels: u32,
    pub timings: BuildTimings,
}

impl fmt::Display for AdsStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        writeln!(
            f,
            "views:            {} ({} with geometry)",
            self.views, self.views_with_content
        )?;
        writeln!(f, "tiles per view:   {0} x {0}", self.tiles_per_side)?;
        writeln!(f, "occupied tiles:   {}", self.occupied_tiles)?;
        writeln!(f, "hi-z levels:      {}", self.hiz_levels)?;
        writeln!(
            f,
            "list nodes:       {} in {} non-empty lists (longest {})",
            self.nodes, self.nonempty_lists, self.max_list
        )?;
        write!(
            f,
            "build:            fill_depth {:.2} ms, mip_depth {:.2} ms, fill_primitives {:.2} ms, total {:.2} ms",
            ms(self.timings.fill_depth),
            ms(self.timings.mip_depth),
            ms(self.timings.fill_primitives),
            ms(self.timings.total())
        )
    }
}

/// One structure's memory.
#[derive(Clone, Debug)]
pub struct MemoryEntry {
    pub name: &'static str,
    pub bytes: u64,
    /// The 001 Table 3 model's figure for the same structure, where it has one.
    pub model: Option<f64>,
}

/// Memory per structure next to the 001 Table 3 model (printed by `dirt info`).
#[derive(Clone, Debug, Default)]
pub struct MemoryReport {
    pub entries: Vec<MemoryEntry>,
}

impl MemoryReport {
    /// Bytes of the structure (each byte counted once).
    pub fn total(&self) -> u64 {
        self.entries
            .iter()
            .filter(|e| {
                matches!(
                    e.name,
                    "depth bounds" | "hi-z levels 1.." | "list offsets" | "list ids"
                )
            })
            .map(|e| e.bytes)
            .sum()
    }
}

impl fmt::Display for MemoryReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mib = |b: f64| b / (1024.0 * 1024.0);
        writeln!(
            f,
            "{:<18} {:>12} {:>16}",
            "memory", "MiB", "001 Table 3 MiB"
        )?;
        for e in &self.entries {
            match e.model {
                Some(m) => writeln!(
                    f,
                    "{:<18} {:>12.3} {:>16.3}",
                    e.name,
                    mib(e.bytes as f64),
                    mib(m)
                )?,
                None => writeln!(f, "{:<18} {:>12.3} {:>16}", e.name, mib(e.bytes as f64), "")?,
            }
        }
        write!(f, "{:<18} {:>12.3}", "total", mib(self.total() as f64))
    }
}
