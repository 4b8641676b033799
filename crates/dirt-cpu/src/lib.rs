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
//!
//! Peers measured against it: [`grid`] (exact) and [`screen_space`], the
//! seeds' approximate screen-space tracers:
//!
//! | tracer | module | views | per pixel |
//! |---|---|---|---|
//! | MMRT (004) | [`screen_space`] | cubemap | all fragments in `B` depth buckets (A-buffer) |
//! | single layer | [`screen_space`] | one view at the camera | the nearest fragment |

mod blocks;
pub mod brute_force;
pub mod cache;
pub mod cost;
mod cover_lanes;
pub mod fill_depth;
pub mod fill_primitives;
pub mod grid;
mod intersect_lanes;
pub mod mip_depth;
pub mod screen_space;
pub mod trace;
mod trace_fast;
pub mod tracer;

pub use cache::{BuildCache, Geometry, Reuse};
pub use trace::{trace, trace_into, trace_with_stats};
pub use tracer::DirtCpu;

use dirt_core::{
    AdsParams, BuildTimings, CoreError, IdLists, Triangle, views_for_all, views_for_bounded,
};
use dirt_math::Aabb;
use dirt_math::ViewSet;
use dirt_math::dda::hiz_width;
use dirt_math::encode::ordered_to_f32;
use std::fmt;
use std::time::Duration;
use web_time::Instant;

impl From<CpuError> for CoreError {
    fn from(e: CpuError) -> Self {
        match e {
            CpuError::Core(e) => e,
            other => CoreError::backend("dirt-cpu", other),
        }
    }
}

/// Errors of the CPU backend.
#[derive(Debug, thiserror::Error)]
pub enum CpuError {
    /// Bad parameters or triangles (checked by `dirt_core`).
    #[error(transparent)]
    Core(#[from] CoreError),
    #[error(
        "the structure would hold {nodes} list nodes, more than 2^32-1; use fewer buckets or a lower resolution"
    )]
    TooManyNodes { nodes: u64 },
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
    /// For a single perspective view: whether every triangle lies inside
    /// its frustum shrunk by its `eps`, so that its hits are every ray's
    /// closest (`fill_depth` finds it while it covers the triangles).
    /// `false` for other sets, where it is not needed.
    pub(crate) sees_all: bool,
    /// Where `sees_all` holds for a view placed at the rays' origin
    /// (`params.center`): every triangle's box in the view's image, made by
    /// `fill_depth` as it covers the triangles. The trace of rays from the
    /// apex leaves out a listed triangle whose box misses the ray's
    /// (`trace_fast`). Empty elsewhere: a scene pays for them only there.
    pub(crate) image_boxes: Vec<trace_fast::ViewBox>,
}

/// Runs `f` on a thread of rayon's pool (the caller's own, if it is one).
/// A build or trace is several parallel loops; each started from a thread
/// outside the pool is handed over and waited for (18 µs on the 2-core
/// machine of docs/RESULTS.md), each started inside it is pushed on a
/// worker's own queue (2 µs): cornell's build was a third hand-overs.
fn in_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::scope(|_| f())
}

impl Ads {
    /// Builds the structure: `fill_depth`, `mip_depth`, `fill_primitives`,
    /// over the views of [`views_for`](dirt_core::views_for) (views no
    /// triangle reaches left out).
    pub fn build(tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        Self::build_bounded(tris, params, None)
    }

    /// [`Ads::build`] with the bounds of [`dirt_core::views_for_bounded`].
    pub(crate) fn build_bounded(
        tris: &[Triangle],
        params: &AdsParams,
        bounds: Option<Aabb>,
    ) -> Result<Ads, CpuError> {
        in_pool(|| Self::build_over(views_for_bounded(tris, params, bounds)?, tris, params))
    }

    /// [`Ads::build`] over every view of [`views_for_all`]: nothing left out.
    pub fn build_all_views(tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        in_pool(|| Self::build_over(views_for_all(tris, params)?, tris, params))
    }

    fn build_over(views: ViewSet, tris: &[Triangle], params: &AdsParams) -> Result<Ads, CpuError> {
        let t0 = Instant::now();
        // fill_primitives needs fill_depth's fragments again: kept while they
        // take no more memory than three times the list offsets will (12 B a
        // fragment, 4 B a list) and two and a quarter times the nodes the
        // fragments found so far will become (fill_depth's EARN), which
        // keeps the peak within its bound (ARCHITECTURE.md, "Memory"). Twice
        // the offsets left the deforming grid's r128 B2 build 15 of its 128
        // pieces to clip again (fill_primitives 0.92 -> 0.76 ms; its peak
        // 1.66x -> 1.79x the structure, peak_memory.rs).
        let tiles = views.slots() * views.views.first().map_or(0, |v| v.tile_count());
        let keep = tiles.saturating_mul(params.buckets as usize);
        // Image boxes for a single view placed where the rays start: the
        // lanes have each triangle's image range already (trace_fast).
        let at_origin = views.kind == dirt_core::ViewsKind::Single && params.center.is_some();
        let (depth, mut fragments) = fill_depth::fill_depth_imaging(&views, tris, keep, at_origin);
        let sees_all = fragments.inside && views.kind == dirt_core::ViewsKind::Single;
        // Only a view that holds every triangle serves rays from its apex
        // this way; elsewhere they are freed before the lists are made.
        let images = std::mem::take(&mut fragments.images);
        let image_boxes = if sees_all { images } else { Vec::new() };
        let t1 = Instant::now();
        // The depth bounds become Hi-Z level 0, which fill_primitives reads.
        let hiz = mip_depth::mip_depth_over(&views, depth);
        let t2 = Instant::now();
        let lists = fill_primitives::fill_primitives_from(
            &views,
            &hiz[0],
            params.buckets,
            tris,
            fragments,
        )?;
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
            sees_all,
            image_boxes,
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
        let mut report = MemoryReport {
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
        };
        // Only where the build made them (a view at the rays' origin).
        if !self.image_boxes.is_empty() {
            report.entries.push(MemoryEntry {
                name: "image boxes",
                bytes: std::mem::size_of_val(&self.image_boxes[..]) as u64,
                model: None,
            });
        }
        report
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
                    "depth bounds"
                        | "hi-z levels 1.."
                        | "list offsets"
                        | "list ids"
                        | "image boxes"
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
