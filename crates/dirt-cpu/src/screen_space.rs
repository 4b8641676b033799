//! The seeds' two *approximate* screen-space tracers, for measuring what
//! DIRT's exactness buys: the multiview multilayer A-buffer ray tracer of
//! seed 004 (MMRT, Vardis et al., I3D 2016) and the single-layer screen-space
//! tracer that 004 and 001 improve on (McGuire and Mara 2014: one view, one
//! depth layer). Both are one [`ScreenSpace`] [`Tracer`]; the parameters
//! ([`ScreenSpaceParams`]) say which.
//!
//! | | MMRT ([`ScreenSpaceParams::mmrt`]) | single layer ([`ScreenSpaceParams::single_layer`]) |
//! |---|---|---|
//! | views | the cubemap of 004 §3.2 ([`ViewSet::cube`] at the bounds' centre) | one 90° view from the eye ([`ViewSet::single`]) |
//! | per pixel | every fragment, in `B` depth buckets ([`Layers::All`]) | the nearest fragment ([`Layers::Nearest`]) |
//! | known loss | triangles that cover no pixel centre | that, occluded surfaces, everything outside the frustum |
//!
//! **Build.** Every triangle is rasterised into every view at *pixel centres*
//! (a pixel of a view is a DIRT tile of a view with `tiles = resolution`): a
//! fragment wherever the view ray through a pixel centre passes inside the
//! triangle (closed edges) within the view's near and far planes, its depth
//! the view-space `z` of the triangle's plane along that centre ray. A
//! triangle that covers no pixel centre leaves no fragment; non-finite and
//! zero-area triangles are skipped. For [`Layers::All`] (004 §3.3):
//! - stage `fragments` (004's *depth bounds* and *store* stages): a first
//!   pass counts the fragments per pixel and takes their depth bounds
//!   `[zmin, zmax]`; a prefix sum turns the counts into offsets; a second pass
//!   writes each fragment's (eye-space z, primitive id) into one flat *id
//!   buffer*. This replaces 004's atomic counter and head/next pointers: the
//!   same content, in flat arrays instead of linked lists.
//! - stage `reorder` (004's *reorder* stage): each pixel's fragments are
//!   sorted by depth (then id), and per pixel and bucket a head offset is
//!   recorded: bucket `b = floor(B·(z − zmin)/(zmax − zmin))` (004 §3.3,
//!   uniform in linear depth, [`bucket_of`]) holds `heads[p·B + b] ..
//!   heads[p·B + b + 1]`. Sorted per pixel means sorted per bucket, and a
//!   slice can be read in both directions, which is what 004's double links
//!   (`next`/`prev`, heads and tails) are for.
//!
//! For [`Layers::Nearest`], `fragments` keeps per pixel only the nearest
//! fragment (smaller depth, then smaller id): a depth buffer and an id
//! buffer; `reorder` has nothing to do but the Hi-Z pyramid (below).
//!
//! **Trace** (004 §3.4). For each view the ray is clipped to the frustum and
//! the pixels it crosses are walked in order with the tile walk of DIRT's
//! linear traversal ([`walk_tiles`]). In a pixel the ray's depth span
//! `[rz0, rz1]` over the pixel is compared with the fragments: a fragment at
//! depth `z_f` is hit when `[rz0, rz1]` overlaps `[z_f, z_f + thickness]`
//! (surfaces are taken to be `thickness` thick behind their front, McGuire and
//! Mara 2014). Only the buckets that span overlaps are visited (004's
//! *fragment bucket skipping*), in the ray's depth direction, and pixels whose
//! bounds it misses are skipped (004's *early skip*); the first fragment met
//! ends the view. Across views the closest hit wins ([`Hit::closer_than`]).
//! Buckets only skip work: the hits do not depend on `B`.
//!
//! **Hi-Z** ([`ScreenSpaceParams::hiz`], on by default for the single layer:
//! "one depth buffer + its Hi-Z, traced with a thickness", as screen-space
//! reflection tracers do). The build adds a min/max depth pyramid over the
//! per-pixel depth bounds (stage `reorder`), and each view is marched
//! hierarchically: cells whose depth bounds (widened by the thickness) the
//! ray's depth span over the cell cannot overlap are skipped whole. The hits
//! are those of the linear march, bit for bit ([`hiz`] says how the order is
//! kept). It works for [`Layers::All`] too, over the pixels' `[zmin, zmax]`
//! (off by default there: MMRT marches linearly).
//!
//! **Reported hits.** `prim` is the fragment's primitive; `t` is where the
//! ray's view depth equals the fragment's (`(z_f − o_z)/d_z`), clamped into
//! the ray's interval over the pixel and `[tmin, tmax]` (the interval's
//! midpoint when the ray's depth barely changes over the pixel); `u`, `v` are
//! the barycentrics (weights of vertices 1 and 2, as
//! [`dirt_math::triangle::intersect`]) of `origin + t·dir` projected onto the
//! triangle's plane and clamped into the triangle. They approximate the true
//! hit; how far they are from it is what the evaluation measures.

pub mod hiz;

use std::time::{Duration, Instant};

use dirt_core::{
    BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Triangle, trace_each,
};
use dirt_math::bucket::bucket_of;
use dirt_math::clip::{Interval, clip_ray_to_view, clip_triangle_to_view, polygon_tile_range};
use dirt_math::dda::{Walk, walk_tiles};
use dirt_math::triangle::is_degenerate;
use dirt_math::{Aabb, INVALID_ID, Vec3, View, ViewRay, ViewSet};
use rayon::prelude::*;

/// Default thickness, as a fraction of the scene bounds' diagonal. Neither
/// seed fixes one: 004 §5 names the thickness of McGuire and Mara 2014 as the
/// remedy for its sampling error without a value, and 001 §5.1 tunes it per
/// scene ("adjusted to produce the optimal quality result"). 1% of the
/// diagonal is a few centimetres in a room-sized scene: the order of the
/// thickness of a wall or a table top, thick enough that rays do not slip
/// between neighbouring pixels' fragments of one surface at moderate
/// resolutions, thin enough not to extrude objects much (001 Fig. 7).
pub const DEFAULT_THICKNESS: f32 = 0.01;
/// Largest resolution (pixels per side of a view).
pub const MAX_RESOLUTION: u32 = 4096;
/// Largest number of depth buckets.
pub const MAX_BUCKETS: u32 = 64;
/// Most fragments a build may store (2 GiB of id buffer); a build that would
/// store more is refused.
pub const MAX_FRAGMENTS: u64 = 1 << 28;
/// Most per-pixel bucket heads a build may store (1 GiB).
pub const MAX_HEADS: u64 = 1 << 28;

/// Which fragments a pixel keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layers {
    /// Every fragment, in depth buckets: the A-buffer of MMRT.
    All,
    /// Only the nearest: one depth layer (a depth buffer and an id buffer).
    Nearest,
}

/// Where the views are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placement {
    /// The cubemap of six 90° views at the bounds' centre ([`ViewSet::cube`]).
    Cube,
    /// One 90° view from this eye towards the bounds' centre ([`ViewSet::single`]).
    Camera(Vec3),
}

/// The knobs of a [`ScreenSpace`] tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenSpaceParams {
    pub placement: Placement,
    pub layers: Layers,
    /// Pixels per side of each view.
    pub resolution: u32,
    /// Depth buckets per pixel ([`Layers::All`]; [`Layers::Nearest`] ignores it).
    /// They only skip work: the hits do not depend on them.
    pub buckets: u32,
    /// Surface thickness behind each fragment, as a fraction of the scene
    /// bounds' diagonal (converted to view depth units at build).
    pub thickness: f32,
    /// Most pixels marched per view and ray; 0 = unbounded. A ray that runs
    /// out reports what it found so far. A bounded march is always linear
    /// (with [`ScreenSpaceParams::hiz`] too), so the bound means the same
    /// pixels, in the same order.
    pub max_steps: u32,
    /// Trace through a Hi-Z (min/max depth) pyramid over the depth bounds
    /// instead of marching every pixel: the same hits bit for bit, more
    /// memory ([`ScreenSpace::memory_bytes`]), less time on rays that cross
    /// empty or far-off regions. True for the single layer, false for MMRT.
    pub hiz: bool,
}

impl ScreenSpaceParams {
    /// MMRT: the cube, every layer, `buckets` buckets, unbounded march.
    pub fn mmrt(resolution: u32, buckets: u32, thickness: f32) -> Self {
        Self {
            placement: Placement::Cube,
            layers: Layers::All,
            resolution,
            buckets,
            thickness,
            max_steps: 0,
            hiz: false,
        }
    }

    /// The single-layer tracer: one view from `eye`, the nearest layer, one
    /// bucket, unbounded march through the Hi-Z pyramid.
    pub fn single_layer(eye: Vec3, resolution: u32, thickness: f32) -> Self {
        Self {
            placement: Placement::Camera(eye),
            layers: Layers::Nearest,
            resolution,
            buckets: 1,
            thickness,
            max_steps: 0,
            hiz: true,
        }
    }

    /// Checks the ranges: resolution `1..=4096`, buckets `1..=64`, thickness
    /// finite and `>= 0`, eye finite.
    pub fn validate(&self) -> Result<(), CoreError> {
        let bad = |m: String| Err(CoreError::InvalidParams(m));
        if !(1..=MAX_RESOLUTION).contains(&self.resolution) {
            return bad(format!(
                "screen-space resolution {} must be in 1..={MAX_RESOLUTION} pixels per side",
                self.resolution
            ));
        }
        if !(1..=MAX_BUCKETS).contains(&self.buckets) {
            return bad(format!(
                "screen-space buckets {} must be in 1..={MAX_BUCKETS}",
                self.buckets
            ));
        }
        if !(self.thickness.is_finite() && self.thickness >= 0.0) {
            return bad(format!(
                "screen-space thickness {} must be a finite number >= 0 (a fraction of the scene's diagonal)",
                self.thickness
            ));
        }
        if let Placement::Camera(eye) = self.placement
            && !eye.is_finite()
        {
            return bad(format!(
                "screen-space camera eye {eye} must have finite coordinates"
            ));
        }
        Ok(())
    }

    /// The tracer's name: `mmrt` for every layer, `1-layer` for the nearest.
    pub fn name(&self) -> &'static str {
        match self.layers {
            Layers::All => "mmrt",
            Layers::Nearest => "1-layer",
        }
    }

    /// A short label with the knobs, e.g. `mmrt r128 B8 th1e-2`,
    /// `1-layer r128 th1e-2`, with ` steps64` when the march is bounded and
    /// ` camera` / ` cube` when the placement is not the method's own, and
    /// ` linear` / ` hiz` at the end when the march is not the method's own
    /// (a single layer without its Hi-Z, MMRT with one).
    pub fn label(&self) -> String {
        let mut s = self.name().to_string();
        match (self.layers, self.placement) {
            (Layers::All, Placement::Camera(_)) => s.push_str(" camera"),
            (Layers::Nearest, Placement::Cube) => s.push_str(" cube"),
            _ => {}
        }
        s.push_str(&format!(" r{}", self.resolution));
        if self.layers == Layers::All {
            s.push_str(&format!(" B{}", self.buckets));
        }
        s.push_str(&format!(" th{:e}", self.thickness));
        if self.max_steps > 0 {
            s.push_str(&format!(" steps{}", self.max_steps));
        }
        match (self.layers, self.hiz) {
            (Layers::Nearest, false) => s.push_str(" linear"),
            (Layers::All, true) => s.push_str(" hiz"),
            _ => {}
        }
        s
    }
}

/// One stored fragment: eye-space depth and primitive id (an id-buffer node).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Frag {
    z: f32,
    prim: u32,
}

const NO_FRAG: Frag = Frag {
    z: f32::INFINITY,
    prim: INVALID_ID,
};

/// What one view stores.
#[derive(Debug, Default)]
struct ViewStore {
    view: Option<View>,
    /// [`Layers::All`]: per pixel `[zmin, zmax]` (`[inf, -inf]` when empty).
    bounds: Vec<[f32; 2]>,
    /// [`Layers::All`]: bucket `b` of pixel `p` is `frags[heads[p·B+b]..heads[p·B+b+1]]`.
    heads: Vec<u32>,
    /// [`Layers::All`]: the id buffer, by pixel, bucket and depth.
    /// [`Layers::Nearest`]: one per pixel ([`NO_FRAG`] when empty).
    frags: Vec<Frag>,
    /// With [`ScreenSpaceParams::hiz`]: levels `1..` of the Hi-Z pyramid
    /// (level 0 is `bounds`, or the depths of `frags`).
    hiz: Vec<hiz::Level>,
}

/// An approximate screen-space tracer (module docs): MMRT or the single layer.
#[derive(Debug)]
pub struct ScreenSpace {
    params: ScreenSpaceParams,
    built: bool,
    tris: Vec<Triangle>,
    stores: Vec<ViewStore>,
    /// Thickness in view depth units (world units: views are orthonormal).
    thickness: f32,
    fragments: usize,
}

impl ScreenSpace {
    /// A tracer with `params` (checked), to be built.
    pub fn new(params: ScreenSpaceParams) -> Result<Self, CoreError> {
        params.validate()?;
        Ok(Self {
            params,
            built: false,
            tris: Vec::new(),
            stores: Vec::new(),
            thickness: 0.0,
            fragments: 0,
        })
    }

    pub fn params(&self) -> &ScreenSpaceParams {
        &self.params
    }

    /// Fragments stored by the last build.
    pub fn fragments(&self) -> usize {
        self.fragments
    }

    /// Views stored by the last build (those that can see the scene's bounds).
    pub fn views(&self) -> usize {
        self.stores.len()
    }

    fn pixels(&self) -> u64 {
        let r = u64::from(self.params.resolution);
        self.stores.len() as u64 * r * r
    }

    /// Bytes of what the last build stores: for [`Layers::All`] the depth
    /// bounds (8 B per pixel), the bucket heads (4 B per pixel and bucket,
    /// plus one) and the id buffer (8 B per fragment: depth and id); for
    /// [`Layers::Nearest`] a depth and an id buffer (8 B per pixel); with
    /// [`ScreenSpaceParams::hiz`] also the pyramid's levels above the pixels
    /// (8 B per cell: min and max; about a third of a pixel each).
    pub fn memory_bytes(&self) -> u64 {
        let size = |s: &ViewStore| {
            8 * s.bounds.len() as u64
                + 4 * s.heads.len() as u64
                + 8 * s.frags.len() as u64
                + s.hiz.iter().map(|l| 8 * l.cells.len() as u64).sum::<u64>()
        };
        self.stores.iter().map(size).sum()
    }

    /// 004 Table 2's memory for the same views, resolution, `B` and fragment
    /// count: DLLB (004's own A-buffer), `Σ_j w_j·h_j·(m_p + n_p·m_f)` with
    /// `m_p = 8 + 8B` (depth bounds, B heads and B tails) and `m_f = 12 +
    /// size{data_f}` (eye-space z, next, prev, plus the data node), where
    /// the data node is the 4-byte primitive id: `V·r²·(8 + 8B) + 16·F`,
    /// `V` being the views built ([`ScreenSpace::views`]: the cube faces that
    /// can see the scene; 004 also counts its camera view `j = 0`, which is
    /// not built here).
    /// For [`Layers::Nearest`]: a depth and an id buffer, `V·r²·8`.
    /// Neither counts a Hi-Z pyramid: 004's model has none (see
    /// [`ScreenSpace::memory_bytes`] for what this build stores).
    pub fn model_bytes(&self) -> u64 {
        let px = self.pixels();
        match self.params.layers {
            Layers::All => {
                px * (8 + 8 * u64::from(self.params.buckets)) + 16 * self.fragments as u64
            }
            Layers::Nearest => px * 8,
        }
    }

    fn rebuild(&mut self, tris: &[Triangle]) -> Result<[Duration; 2], CoreError> {
        let p = self.params;
        self.built = false;
        self.tris.clear();
        self.stores.clear();
        self.fragments = 0;
        let mut bounds = Aabb::EMPTY;
        for t in tris.iter().filter(|t| t.is_finite()) {
            for i in 0..3 {
                bounds.grow(t.vertex(i));
            }
        }
        if bounds.is_empty() {
            // Nothing to rasterise: every ray misses.
            self.built = true;
            return Ok([Duration::ZERO; 2]);
        }
        let diag = {
            let e = bounds.extent().as_dvec3();
            (e.length() as f32).min(f32::MAX)
        };
        self.thickness = p.thickness * diag;
        let set = match p.placement {
            Placement::Cube => ViewSet::cube(bounds.center(), &bounds, p.resolution),
            Placement::Camera(eye) => ViewSet::single(Some(eye), &bounds, p.resolution),
        };
        let views: Vec<View> = set.views.into_iter().filter(|v| v.has_content).collect();
        let r = u64::from(p.resolution);
        let px = r * r;
        let buckets = match p.layers {
            Layers::All => u64::from(p.buckets),
            Layers::Nearest => 1,
        };
        let heads = views.len() as u64 * px * buckets;
        if heads > MAX_HEADS {
            return Err(CoreError::InvalidParams(format!(
                "{}: {} views of {}x{} pixels with {} buckets would need {heads} bucket heads, more than {MAX_HEADS}; lower the resolution or the buckets",
                p.label(),
                views.len(),
                p.resolution,
                p.resolution,
                buckets
            )));
        }
        let t0 = Instant::now();
        let stores = match p.layers {
            Layers::Nearest => {
                let stores: Vec<ViewStore> = views
                    .par_iter()
                    .map(|v| {
                        let mut frags = vec![NO_FRAG; px as usize];
                        rasterise(v, tris, |pixel, z, prim| {
                            let f = &mut frags[pixel];
                            if z < f.z || (z == f.z && prim < f.prim) {
                                *f = Frag { z, prim };
                            }
                        });
                        ViewStore {
                            view: Some(*v),
                            frags,
                            ..ViewStore::default()
                        }
                    })
                    .collect();
                self.fragments = stores
                    .iter()
                    .flat_map(|s| &s.frags)
                    .filter(|f| f.prim != INVALID_ID)
                    .count();
                let t1 = Instant::now();
                self.stores = stores;
                if p.hiz {
                    self.stores.par_iter_mut().for_each(|s| {
                        let frags = &s.frags;
                        s.hiz = hiz::pyramid(p.resolution, |k| {
                            let f = frags[k];
                            if f.prim == INVALID_ID {
                                [f32::INFINITY, f32::NEG_INFINITY]
                            } else {
                                [f.z, f.z]
                            }
                        });
                    });
                }
                self.install(tris);
                return Ok([t1 - t0, Instant::now() - t1]);
            }
            Layers::All => {
                // Pass one: counts and depth bounds.
                let counted: Vec<(Vec<u32>, Vec<[f32; 2]>)> = views
                    .par_iter()
                    .map(|v| {
                        let mut counts = vec![0u32; px as usize];
                        let mut zb = vec![[f32::INFINITY, f32::NEG_INFINITY]; px as usize];
                        rasterise(v, tris, |pixel, z, _| {
                            counts[pixel] = counts[pixel].saturating_add(1);
                            let b = &mut zb[pixel];
                            b[0] = b[0].min(z);
                            b[1] = b[1].max(z);
                        });
                        (counts, zb)
                    })
                    .collect();
                let total: u64 = counted
                    .iter()
                    .flat_map(|(c, _)| c)
                    .map(|&c| u64::from(c))
                    .sum();
                if total > MAX_FRAGMENTS {
                    return Err(CoreError::InvalidParams(format!(
                        "{}: the A-buffer would store {total} fragments, more than {MAX_FRAGMENTS}; lower the resolution",
                        p.label()
                    )));
                }
                // Prefix sums, then pass two: the id buffer, by pixel.
                views
                    .par_iter()
                    .zip(counted)
                    .map(|(v, (counts, zb))| {
                        let mut offsets = Vec::with_capacity(counts.len() + 1);
                        let mut sum = 0u32;
                        for &c in &counts {
                            offsets.push(sum);
                            sum += c;
                        }
                        offsets.push(sum);
                        let mut cursor = offsets.clone();
                        let mut frags = vec![NO_FRAG; sum as usize];
                        rasterise(v, tris, |pixel, z, prim| {
                            let c = &mut cursor[pixel];
                            frags[*c as usize] = Frag { z, prim };
                            *c += 1;
                        });
                        (*v, zb, offsets, frags)
                    })
                    .collect::<Vec<_>>()
            }
        };
        let t1 = Instant::now();
        // Reorder: sort each pixel by depth, record the bucket heads.
        let nb = p.buckets;
        self.stores = stores
            .into_par_iter()
            .map(|(v, zb, offsets, mut frags)| {
                let mut heads = Vec::with_capacity(px as usize * nb as usize + 1);
                for (pixel, &[zmin, zmax]) in zb.iter().enumerate() {
                    let (s, e) = (offsets[pixel] as usize, offsets[pixel + 1] as usize);
                    let list = &mut frags[s..e];
                    list.sort_unstable_by(|a, b| a.z.total_cmp(&b.z).then(a.prim.cmp(&b.prim)));
                    // bucket_of is monotonic in z: the buckets are consecutive runs.
                    let mut k = s;
                    for b in 0..nb {
                        heads.push(k as u32);
                        while k < e && bucket_of(frags[k].z, zmin, zmax, nb) == b {
                            k += 1;
                        }
                    }
                    debug_assert_eq!(k, e);
                }
                heads.push(frags.len() as u32);
                let hiz = if p.hiz {
                    hiz::pyramid(p.resolution, |k| zb[k])
                } else {
                    Vec::new()
                };
                ViewStore {
                    view: Some(v),
                    bounds: zb,
                    heads,
                    frags,
                    hiz,
                }
            })
            .collect();
        self.fragments = self.stores.iter().map(|s| s.frags.len()).sum();
        let t2 = Instant::now();
        self.install(tris);
        Ok([t1 - t0, t2 - t1])
    }

    fn install(&mut self, tris: &[Triangle]) {
        self.tris.extend_from_slice(tris);
        self.built = true;
    }

    /// The hit of one ray (a miss for a ray that fails [`Ray::validate`]).
    pub fn trace_ray(&self, ray: &Ray) -> Hit {
        let mut best = Hit::MISS;
        if ray.validate().is_err() {
            return best;
        }
        for s in &self.stores {
            let Some(v) = &s.view else { continue };
            let vr = v.ray(ray);
            let (iv, _) = clip_ray_to_view(v, &vr, ray.tmin, ray.tmax);
            if iv.is_empty() || iv.t0 > best.t {
                continue;
            }
            let h = if self.params.hiz && self.params.max_steps == 0 {
                self.march_hiz(s, v, &vr, iv, ray, best.t)
            } else {
                self.march(s, v, &vr, iv, ray, best.t)
            };
            if let Some(h) = h
                && h.closer_than(&best)
            {
                best = h;
            }
        }
        best
    }

    /// The first fragment the ray meets in one view.
    fn march(
        &self,
        s: &ViewStore,
        v: &View,
        vr: &ViewRay,
        iv: Interval,
        ray: &Ray,
        bound: f32,
    ) -> Option<Hit> {
        let mut found = None;
        let mut steps = 0u32;
        let max = self.params.max_steps;
        let ascending = vr.d[2] >= 0.0;
        walk_tiles(v, vr, iv, &mut || bound, &mut |span| {
            if max > 0 && steps >= max {
                return Walk::Stop;
            }
            steps += 1;
            let pixel = (span.j * v.tiles + span.i) as usize;
            let za = vr.o[2] + span.iv.t0 * vr.d[2];
            let zb = vr.o[2] + span.iv.t1 * vr.d[2];
            let (lo, hi) = (za.min(zb), za.max(zb));
            match self.first_in_pixel(s, pixel, lo, hi, ascending) {
                Some(f) => {
                    found = Some(self.hit(f, vr, span.iv, ray, lo, hi));
                    Walk::Stop
                }
                None => Walk::Continue,
            }
        });
        found
    }

    /// The first fragment of `pixel` whose thick slab `[z, z + thickness]`
    /// the depth span `[lo, hi]` overlaps, in the ray's depth direction.
    fn first_in_pixel(
        &self,
        s: &ViewStore,
        pixel: usize,
        lo: f32,
        hi: f32,
        ascending: bool,
    ) -> Option<Frag> {
        let th = self.thickness;
        let hits = |f: &Frag| hi >= f.z && lo <= f.z + th;
        match self.params.layers {
            Layers::Nearest => {
                let f = s.frags[pixel];
                (f.prim != INVALID_ID && hits(&f)).then_some(f)
            }
            Layers::All => {
                let [zmin, zmax] = s.bounds[pixel];
                // Early skip: the span misses every slab of the pixel.
                if !(hi >= zmin && lo <= zmax + th) {
                    return None;
                }
                let nb = self.params.buckets;
                // One more bucket each side: the overlap test decides, the
                // buckets only skip, and `z + th` rounds differently from `lo - th`.
                let b0 = bucket_of(lo - th, zmin, zmax, nb).saturating_sub(1);
                let b1 = (bucket_of(hi, zmin, zmax, nb) + 1).min(nb - 1);
                let base = pixel * nb as usize;
                let bucket = |b: u32| {
                    let k = base + b as usize;
                    &s.frags[s.heads[k] as usize..s.heads[k + 1] as usize]
                };
                if ascending {
                    (b0..=b1).find_map(|b| bucket(b).iter().find(|f| hits(f)).copied())
                } else {
                    (b0..=b1)
                        .rev()
                        .find_map(|b| bucket(b).iter().rev().find(|f| hits(f)).copied())
                }
            }
        }
    }

    /// The reported hit on fragment `f` met over the pixel interval `iv`.
    fn hit(&self, f: Frag, vr: &ViewRay, iv: Interval, ray: &Ray, lo: f32, hi: f32) -> Hit {
        let flat = !(hi - lo > 1e-6 * hi.abs().max(lo.abs()));
        let mid = 0.5 * iv.t0 + 0.5 * iv.t1;
        let t = if flat {
            mid
        } else {
            let t = (f.z - vr.o[2]) / vr.d[2];
            if t.is_nan() {
                mid
            } else {
                t.clamp(iv.t0, iv.t1)
            }
        };
        let mut t = t.clamp(ray.tmin, ray.tmax);
        if !t.is_finite() {
            t = ray.tmin;
        }
        let (u, v) = barycentrics(&self.tris[f.prim as usize], ray.at(t));
        Hit {
            prim: f.prim,
            t,
            u,
            v,
        }
    }
}

/// Barycentrics `(u, v)` (weights of vertices 1 and 2) of `p` projected onto
/// the triangle's plane, clamped into the triangle.
fn barycentrics(tri: &Triangle, p: Vec3) -> (f32, f32) {
    let a = tri.vertex(0).as_dvec3();
    let e1 = tri.vertex(1).as_dvec3() - a;
    let e2 = tri.vertex(2).as_dvec3() - a;
    let w = p.as_dvec3() - a;
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (w.dot(e1), w.dot(e2));
    let den = d00 * d11 - d01 * d01;
    if !(den > 0.0) || !den.is_finite() {
        return (0.0, 0.0);
    }
    let u = ((d11 * d20 - d01 * d21) / den).max(0.0);
    let v = ((d00 * d21 - d01 * d20) / den).max(0.0);
    let (u, v) = if !(u.is_finite() && v.is_finite()) {
        (0.0, 0.0)
    } else if u + v > 1.0 {
        (u / (u + v), v / (u + v))
    } else {
        (u, v)
    };
    (u as f32, v as f32)
}

/// Rasterises every triangle into view `v` at pixel centres: calls
/// `emit(pixel, z, prim)` for every pixel centre whose view ray passes inside
/// the triangle (closed edges) at a depth `z` within `[near, far]`, `z` being
/// the depth of the triangle's plane along that ray. Triangles are visited
/// in id order and pixels row by row, so two calls emit the same sequence.
fn rasterise(v: &View, tris: &[Triangle], mut emit: impl FnMut(usize, f32, u32)) {
    let n = v.tiles as usize;
    let step = 2.0 * f64::from(v.tan) / n as f64;
    let tan = f64::from(v.tan);
    let (near, far) = (f64::from(v.near), f64::from(v.far));
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (id, t) in tris.iter().enumerate() {
        if !t.is_finite() || is_degenerate(t) {
            continue;
        }
        let q = [
            v.to_view(t.vertex(0)),
            v.to_view(t.vertex(1)),
            v.to_view(t.vertex(2)),
        ];
        if !q.iter().flatten().all(|c| c.is_finite()) {
            continue;
        }
        let Some(poly) = clip_triangle_to_view(v, q) else {
            continue;
        };
        let Some((i0, i1, j0, j1)) = polygon_tile_range(v, &poly) else {
            continue;
        };
        let [a, b, c] = q.map(|p| p.map(f64::from));
        // Edge functions of the centre ray d: d·(b×c), d·(c×a), d·(a×b); the
        // ray meets the plane at z = det(a, b, c) / (their sum).
        let (bc, ca, ab) = (cross(b, c), cross(c, a), cross(a, b));
        let det = dot(a, bc);
        for j in j0..=j1 {
            let sy = (f64::from(j) + 0.5) * step - tan;
            for i in i0..=i1 {
                let d = [(f64::from(i) + 0.5) * step - tan, sy, 1.0];
                let (e0, e1, e2) = (dot(d, bc), dot(d, ca), dot(d, ab));
                let inside =
                    (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
                let sum = e0 + e1 + e2;
                if !inside || sum == 0.0 {
                    continue;
                }
                let z = det / sum;
                if z >= near && z <= far && z.is_finite() {
                    emit(j as usize * n + i as usize, z as f32, id as u32);
                }
            }
        }
    }
}

impl Tracer for ScreenSpace {
    fn name(&self) -> String {
        self.params.name().to_string()
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        let [fragments, reorder] = self.rebuild(tris)?;
        Ok(BuildReport {
            stages: vec![("fragments", fragments), ("reorder", reorder)],
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
        let me = &*self;
        trace_each(rays, hits, stats.as_deref(), |r| me.trace_ray(r))
    }
}
