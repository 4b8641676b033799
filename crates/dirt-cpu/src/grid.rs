//! The compact uniform grid of Lagae and Dutré (seed 002, "Compact, Fast and
//! Robust Grids for Ray Tracing"): a classic baseline that rebuilds fast,
//! exact with DIRT's triangle test.
//!
//! **Build** (two passes, no per-cell allocation): `ρ·N` cells over the
//! scene's bounds (`M_i = S_i · ∛(ρN / V)`, the density `ρ` being the knob);
//! pass one counts, per cell, the triangles whose bounding box (grown by a
//! margin) overlaps it; an exclusive prefix sum turns the counts into
//! offsets; pass two writes the triangle ids, in ascending order per cell.
//! The structure is one offset per cell (plus one) and one id per reference.
//!
//! **Trace**: a 3D DDA (Amanatides and Woo) from the cell where the ray
//! enters the grid, testing every triangle of each cell with
//! [`intersect_closest`] (the test and tie-break brute force uses), until the
//! closest hit so far lies before the current cell's exit.
//!
//! **Exactness.** Every crossing is computed afresh from the cell's integer
//! index (nothing accumulates), so the DDA's position is off by a few
//! rounding errors of the coordinates' magnitude; triangles are binned with a
//! margin far larger than that (at least 1e-3 of a cell and 2^-13 of the
//! scene's largest coordinate), so a cell the DDA visits holds every
//! triangle the exact ray meets there, and the early stop cannot pass a
//! closer hit. A ray whose origin is so far away (over 64 times the scene's
//! largest coordinate) that its rounding could exceed the margin is traced
//! against every triangle instead. The hits are brute force's, bit for bit
//! (`crates/dirt-cpu/tests/grid.rs`).

use std::sync::atomic::{AtomicU64, Ordering};

use dirt_core::{
    BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Triangle, trace_each,
};
use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::{Aabb, Vec3};

/// The density the compact-grid paper found best for time to image.
pub const DEFAULT_DENSITY: f32 = 4.0;
/// Most cells a grid may have (64 MiB of offsets).
pub const MAX_CELLS: u64 = 1 << 24;
/// Most cell references a grid may hold (1 GiB of ids).
pub const MAX_REFERENCES: u64 = 1 << 28;

/// A compact uniform grid over a triangle list.
pub struct Grid {
    density: f32,
    tris: Vec<Triangle>,
    /// The grid's box: `min` and the cell size per axis.
    min: Vec3,
    cell: Vec3,
    dims: [u32; 3],
    /// `offsets[c]..offsets[c + 1]` are cell `c`'s ids (`c = (z·My + y)·Mx + x`).
    offsets: Vec<u32>,
    ids: Vec<u32>,
    /// World distance every triangle's box is grown by before binning.
    margin: f32,
    /// The scene's largest absolute coordinate.
    magnitude: f32,
    fallbacks: AtomicU64,
    built: bool,
}

impl std::fmt::Debug for Grid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Grid")
            .field("density", &self.density)
            .field("triangles", &self.tris.len())
            .field("dims", &self.dims)
            .field("references", &self.ids.len())
            .field("margin", &self.margin)
            .finish()
    }
}

impl Grid {
    /// An empty grid of density `density` (cells per triangle), to be built.
    pub fn new(density: f32) -> Result<Self, CoreError> {
        if !(density.is_finite() && density > 0.0) {
            return Err(CoreError::InvalidParams(format!(
                "grid density {density} must be a positive number (cells per triangle)"
            )));
        }
        Ok(Self {
            density,
            tris: Vec::new(),
            min: Vec3::ZERO,
            cell: Vec3::ONE,
            dims: [1; 3],
            offsets: vec![0, 0],
            ids: Vec::new(),
            margin: 0.0,
            magnitude: 0.0,
            fallbacks: AtomicU64::new(0),
            built: false,
        })
    }

    /// A grid of density `density` built over `tris`.
    pub fn built(tris: &[Triangle], density: f32) -> Result<Self, CoreError> {
        let mut g = Self::new(density)?;
        g.rebuild(tris)?;
        Ok(g)
    }

    /// Cells per axis.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// Cell references (ids) the grid holds.
    pub fn references(&self) -> usize {
        self.ids.len()
    }

    /// Bytes of the structure: offsets and ids (the triangles are the input).
    pub fn memory_bytes(&self) -> u64 {
        4 * (self.offsets.len() + self.ids.len()) as u64
    }

    /// Rays traced against every triangle since the last build, because
    /// their origin lay too far away for the grid's margin.
    pub fn fallbacks(&self) -> u64 {
        self.fallbacks.load(Ordering::Relaxed)
    }

    fn cell_of(&self, x: f32, axis: usize) -> u32 {
        let c = ((x - self.min[axis]) / self.cell[axis]).floor();
        // NaN and negatives clamp to 0.
        (c.max(0.0) as u32).min(self.dims[axis] - 1)
    }

    fn rebuild(&mut self, tris: &[Triangle]) -> Result<(), CoreError> {
        if let Some(index) = dirt_core::first_non_finite(tris) {
            return Err(CoreError::NonFiniteTriangle { index });
        }
        self.tris.clear();
        self.tris.extend_from_slice(tris);
        self.built = true;
        self.fallbacks.store(0, Ordering::Relaxed);
        self.ids.clear();
        self.offsets.clear();
        if tris.is_empty() {
            self.dims = [1; 3];
            self.offsets.extend([0, 0]);
            return Ok(());
        }
        let bounds = Aabb::of_triangles(tris);
        let ext = bounds.extent();
        let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element();
        let diag = ext.length();
        // A flat axis still gets a thickness, so the volume is not zero.
        let pad = (1e-3 * diag).max(1e-6 * magnitude).max(f32::MIN_POSITIVE);
        let size = ext.max(Vec3::splat(pad));
        let (sx, sy, sz) = (size.x as f64, size.y as f64, size.z as f64);
        let n = tris.len() as f64;
        let mut k = (f64::from(self.density) * n / (sx * sy * sz)).cbrt();
        let dims = loop {
            let d = [sx, sy, sz].map(|s| (s * k).ceil().clamp(1.0, 65_536.0) as u64);
            if d[0] * d[1] * d[2] <= MAX_CELLS || k < 1e-30 {
                break d.map(|x| x as u32);
            }
            k *= 0.9;
        };
        let cell_min = (0..3)
            .map(|a| size[a] / dims[a] as f32)
            .fold(f32::INFINITY, f32::min);
        let margin = (1e-3 * cell_min).max(magnitude * f32::EPSILON * 1024.0);
        // The grid's box: the bounds grown by twice the margin on each side.
        let min = bounds.min - Vec3::splat(2.0 * margin);
        let full = size + Vec3::splat(4.0 * margin);
        self.min = min;
        self.dims = dims;
        self.cell = Vec3::new(
            full.x / dims[0] as f32,
            full.y / dims[1] as f32,
            full.z / dims[2] as f32,
        );
        self.margin = margin;
        self.magnitude = magnitude;

        let cells = dims.iter().map(|&d| d as usize).product::<usize>();
        let range = |g: &Grid, t: &Triangle| {
            let (v0, v1, v2) = (t.vertex(0), t.vertex(1), t.vertex(2));
            let lo = v0.min(v1).min(v2) - Vec3::splat(margin);
            let hi = v0.max(v1).max(v2) + Vec3::splat(margin);
            let a = [0, 1, 2].map(|ax| g.cell_of(lo[ax], ax));
            let b = [0, 1, 2].map(|ax| g.cell_of(hi[ax], ax));
            (a, b)
        };
        // The references, counted before anything is written.
        let total: u64 = tris
            .iter()
            .map(|t| {
                let (a, b) = range(self, t);
                (0..3)
                    .map(|ax| u64::from(b[ax] - a[ax] + 1))
                    .product::<u64>()
            })
            .sum();
        if total > MAX_REFERENCES {
            return Err(CoreError::InvalidParams(format!(
                "a grid of density {} over {} triangles would hold {total} cell references, more than {MAX_REFERENCES}; lower the density",
                self.density,
                tris.len()
            )));
        }
        // Pass one: counts.
        let mut counts = vec![0u32; cells + 1];
        for t in tris {
            let (a, b) = range(self, t);
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    let row = (z as usize * dims[1] as usize + y as usize) * dims[0] as usize;
                    for x in a[0]..=b[0] {
                        counts[row + x as usize] += 1;
                    }
                }
            }
        }
        // Exclusive prefix sum.
        let mut sum = 0u32;
        for c in counts.iter_mut() {
            let n = *c;
            *c = sum;
            sum += n;
        }
        // Pass two: ids in ascending order per cell.
        let mut cursor = counts.clone();
        self.ids.resize(sum as usize, 0);
        for (id, t) in tris.iter().enumerate() {
            let (a, b) = range(self, t);
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    let row = (z as usize * dims[1] as usize + y as usize) * dims[0] as usize;
                    for x in a[0]..=b[0] {
                        let c = &mut cursor[row + x as usize];
                        self.ids[*c as usize] = id as u32;
                        *c += 1;
                    }
                }
            }
        }
        self.offsets = counts;
        Ok(())
    }

    /// The closest hit of one ray.
    pub fn trace_ray(&self, ray: &Ray) -> Hit {
        let mut best = Hit::MISS;
        if ray.validate().is_err() || self.ids.is_empty() {
            return best;
        }
        let o = Vec3::from_array(ray.origin);
        let d = Vec3::from_array(ray.dir);
        let sh = RayShear::new(ray);
        // Rounding of a far origin could exceed the margin: test everything.
        if 16.0 * f32::EPSILON * (o.abs().max_element() + self.magnitude) > self.margin {
            self.fallbacks.fetch_add(1, Ordering::Relaxed);
            for (id, t) in self.tris.iter().enumerate() {
                intersect_closest(ray, &sh, t, id as u32, &mut best);
            }
            return best;
        }
        let max = self.min
            + Vec3::new(
                self.cell.x * self.dims[0] as f32,
                self.cell.y * self.dims[1] as f32,
                self.cell.z * self.dims[2] as f32,
            );
        let (mut t0, mut t1) = (ray.tmin, ray.tmax);
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < self.min[a] || o[a] > max[a] {
                    return best;
                }
                continue;
            }
            let (ta, tb) = ((self.min[a] - o[a]) / d[a], (max[a] - o[a]) / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if !(t0 <= t1) {
            return best;
        }
        let start = o + d * t0;
        let mut idx = [0, 1, 2].map(|a| self.cell_of(start[a], a) as i64);
        let step = [0, 1, 2].map(|a| {
            if d[a] > 0.0 {
                1i64
            } else if d[a] < 0.0 {
                -1
            } else {
                0
            }
        });
        // The ray's parameter where it leaves the current cell along `a`.
        let next = |idx: i64, a: usize| -> f32 {
            match step[a] {
                0 => f32::INFINITY,
                s => {
                    let boundary = if s > 0 { idx + 1 } else { idx };
                    (self.min[a] + boundary as f32 * self.cell[a] - o[a]) / d[a]
                }
            }
        };
        let mut t_next = [next(idx[0], 0), next(idx[1], 1), next(idx[2], 2)];
        let dims = self.dims.map(i64::from);
        loop {
            let c = ((idx[2] * dims[1] + idx[1]) * dims[0] + idx[0]) as usize;
            let (lo, hi) = (self.offsets[c] as usize, self.offsets[c + 1] as usize);
            for &id in &self.ids[lo..hi] {
                intersect_closest(ray, &sh, &self.tris[id as usize], id, &mut best);
            }
            let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            let exit = t_next[a];
            // The closest hit lies before this cell's exit, or the ray ends here.
            if best.t <= exit || exit > t1 {
                return best;
            }
            idx[a] += step[a];
            if idx[a] < 0 || idx[a] >= dims[a] {
                return best;
            }
            t_next[a] = next(idx[a], a);
        }
    }
}

impl Tracer for Grid {
    fn name(&self) -> String {
        format!("grid ρ{}", self.density)
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        let start = web_time::Instant::now();
        // In the pool, as DIRT's build is: the same footing for the peer.
        crate::in_pool(|| self.rebuild(tris))?;
        Ok(BuildReport {
            stages: vec![("grid", start.elapsed())],
            memory: Some(self.memory_bytes()),
        })
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        if !self.built {
            return Err(CoreError::NotBuilt {
                tracer: self.name(),
            });
        }
        let g = &*self;
        crate::in_pool(|| trace_each(rays, hits, stats.as_deref(), |r| g.trace_ray(r)))
    }
}
