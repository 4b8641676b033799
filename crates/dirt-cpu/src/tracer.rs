//! DIRT on the CPU as a [`Tracer`]: [`DirtCpu`] owns the structure and a copy
//! of the triangles it was built over.

use crate::cost::{self, AutoChoice, CostModel, TraversalChoice};
use crate::trace::trace_into_from;
use crate::trace_fast::BoxCache;
use crate::{Ads, CpuError};
use dirt_core::{
    AdsParams, BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Traversal,
    Triangle, ViewsKind, check_lengths,
};
use dirt_math::view::single_sees_all;
use dirt_math::{Aabb, Vec3};
use web_time::Instant;

/// Rays in the sample [`DirtCpu::auto`] measures candidates with.
pub const AUTO_SAMPLE: usize = 512;

/// Rays in the sample [`DirtCpu::auto`] times the two traversals on, when
/// none is given: enough for milliseconds on a small scene.
pub const TRAVERSAL_SAMPLE: usize = 4000;

/// DIRT on the CPU: [`Ads::build`] and [`crate::trace`] behind [`Tracer`].
#[derive(Debug)]
pub struct DirtCpu {
    pub params: AdsParams,
    pub traversal: Traversal,
    ads: Option<Ads>,
    tris: Vec<Triangle>,
    /// With [`DirtCpu::auto`]: the rays per frame the cost model chooses for.
    auto: Option<u64>,
    /// The last choice and the triangle count it was made for.
    choice: Option<(usize, AutoChoice)>,
    /// With [`DirtCpu::auto`] and no traversal given: the traversal is timed
    /// at each choice ([`cost::faster_traversal`]); the last timing.
    measure_traversal: bool,
    traversal_choice: Option<TraversalChoice>,
    /// Where a frame's rays start, when the caller says ([`DirtCpu::with_origin`]).
    origin: Option<Vec3>,
    /// Rays like a frame's, when the caller gives them ([`DirtCpu::with_sample`]).
    sample: Option<Vec<Ray>>,
    /// Whether the caller said where the rays start ([`DirtCpu::set_origin`]);
    /// otherwise [`DirtCpu::auto`] watches the rays it traces.
    origin_given: bool,
    /// What the traces since the last build showed (watching).
    seen: Option<Seen>,
    /// The traced rays the next choice is made on (watching).
    seen_sample: Option<Vec<Ray>>,
    /// The triangle boxes of the last build, once its traces have paid for
    /// them (`trace_fast::BoxCache`).
    boxes: BoxCache,
}

/// The rays traced since the last build: the point they all start at, if
/// they do, and a sample of the first batch.
#[derive(Debug)]
struct Seen {
    origin: Option<Vec3>,
    sample: Vec<Ray>,
}

impl DirtCpu {
    /// A tracer that builds with `params` and walks with `traversal`; call
    /// [`Tracer::build`] before tracing.
    pub fn new(params: AdsParams, traversal: Traversal) -> Self {
        Self {
            params,
            traversal,
            ads: None,
            tris: Vec::new(),
            auto: None,
            choice: None,
            measure_traversal: false,
            traversal_choice: None,
            origin: None,
            sample: None,
            origin_given: false,
            seen: None,
            seen_sample: None,
            boxes: BoxCache::default(),
        }
    }

    /// Gives [`DirtCpu::auto`] rays like a frame's (`None`: generated ones).
    /// The cost model measures its candidates on at most [`AUTO_SAMPLE`] of
    /// them, evenly strided ([`cost::stride_sample`]), and the traversals are
    /// timed on at most [`TRAVERSAL_SAMPLE`]: a choice made on the rays the
    /// frames trace fits them better than one made on generated rays. Used at
    /// the next choice.
    pub fn set_sample(&mut self, rays: Option<&[Ray]>) {
        self.sample = rays.map(|r| cost::stride_sample(r, TRAVERSAL_SAMPLE));
    }

    /// [`DirtCpu::set_sample`] as a builder.
    pub fn with_sample(mut self, rays: &[Ray]) -> Self {
        self.set_sample(Some(rays));
        self
    }

    /// Tells [`DirtCpu::auto`] where each frame's rays start (a camera's eye;
    /// `None`: anywhere). The cost model then weighs the views placed there
    /// ([`cost::candidates_at`]: the cube centred at the origin, and the single
    /// view from it when it sees the whole scene), measured on the sample of
    /// [`DirtCpu::set_sample`], else on rays from the origin
    /// ([`cost::sample_rays_from`]). Each of them is exact for every ray,
    /// from anywhere, so a ray that starts elsewhere is still traced right. A
    /// choice placed at the origin follows it when it moves (set it before
    /// each frame's build); a single view whose scene has grown out of its
    /// frustum, or whose origin is gone, is chosen again. Without
    /// [`DirtCpu::auto`] the origin is not used. Once it is set (to `None`
    /// too), the tracer no longer watches the rays it traces for one
    /// ([`DirtCpu::auto`]).
    pub fn set_origin(&mut self, origin: Option<Vec3>) {
        self.origin = origin;
        self.origin_given = true;
        self.seen = None;
    }

    /// [`DirtCpu::set_origin`] as a builder.
    pub fn with_origin(mut self, origin: Vec3) -> Self {
        self.set_origin(Some(origin));
        self
    }

    /// A tracer whose parameters the cost model chooses
    /// ([`cost::auto_budgeted`] with [`cost::KEPT_BUDGET`]) for frames of
    /// `rays_per_frame` rays: the library's default. The choice is made at
    /// the first build, from a sample of rays leaving the triangles
    /// ([`cost::sample_rays`]), and kept while the triangle count stays the
    /// same (a deforming mesh keeps its choice; another scene gets a new one),
    /// which is why it may search longer than a one-off choice ([`cost::auto`]).
    /// Its time is the build's first stage, `choose`; that build then keeps
    /// the winning candidate's structure, built while choosing, so its other
    /// stages are absent. With `traversal` `None`, the faster traversal
    /// through the chosen structure is measured too, on [`TRAVERSAL_SAMPLE`]
    /// rays of the same kind ([`cost::faster_traversal`]; inside `choose`);
    /// both give the same hits, so only time depends on that measurement.
    ///
    /// It watches the rays it traces, unless told where they start
    /// ([`DirtCpu::set_origin`]): when every ray traced between two builds
    /// starts at one point (a camera's primary rays), the next build places
    /// the views there ([`cost::candidates_at`]) and later builds move them
    /// with that point. Where the rays begin or stop sharing one point, the
    /// cost model chooses again at the next build, on a sample of the rays
    /// traced ([`DirtCpu::set_sample`] overrides it). Every choice is exact
    /// for every ray.
    pub fn auto(traversal: Option<Traversal>, rays_per_frame: u64) -> Self {
        Self {
            auto: Some(rays_per_frame),
            measure_traversal: traversal.is_none(),
            ..Self::new(AdsParams::default(), traversal.unwrap_or(Traversal::HiZ))
        }
    }

    /// The timing behind the traversal of [`DirtCpu::auto`] without a
    /// traversal given (after a build).
    pub fn traversal_choice(&self) -> Option<&TraversalChoice> {
        self.traversal_choice.as_ref()
    }

    /// The cost model's last choice, with what it ranked and skipped
    /// (only with [`DirtCpu::auto`], after a build).
    pub fn choice(&self) -> Option<&AutoChoice> {
        self.choice.as_ref().map(|(_, c)| c)
    }

    /// [`DirtCpu::new`] and a build over `tris`.
    pub fn built(
        tris: &[Triangle],
        params: &AdsParams,
        traversal: Traversal,
    ) -> Result<Self, CpuError> {
        Ok(Self::from_ads(Ads::build(tris, params)?, tris, traversal))
    }

    /// A tracer over a structure already built from `tris`.
    pub fn from_ads(ads: Ads, tris: &[Triangle], traversal: Traversal) -> Self {
        let params = ads.params;
        Self {
            ads: Some(ads),
            tris: tris.to_vec(),
            ..Self::new(params, traversal)
        }
    }

    /// The structure of the last build.
    pub fn ads(&self) -> Option<&Ads> {
        self.ads.as_ref()
    }

    /// Bytes of the triangles' boxes kept beside the last build for its
    /// traces: 0 until the rays traced on it, but for those from the
    /// centre of perspective views (a cube's, a single view's apex), number
    /// one for every 4 (triangle, view) pairs; then 32 bytes a pair
    /// until the next build. A trace of such rays leaves out a listed
    /// triangle whose box misses the ray's segment in a tile.
    pub fn boxes_bytes(&self) -> usize {
        self.boxes.bytes()
    }

    /// Keeps `ads`, built over `tris`, and reports its build.
    fn keep(
        &mut self,
        ads: Ads,
        tris: &[Triangle],
        stages: Vec<(&'static str, std::time::Duration)>,
    ) -> BuildReport {
        let report = BuildReport {
            stages,
            memory: Some(ads.memory().total()),
        };
        self.tris.clear();
        self.tris.extend_from_slice(tris);
        self.ads = Some(ads);
        report
    }
}

impl DirtCpu {
    /// [`Tracer::build`]'s work, on a thread of the pool.
    fn rebuild(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        // The old structure's boxes go with it, whether this build succeeds or not.
        self.ads = None;
        self.boxes = BoxCache::default();
        let mut stages = Vec::new();
        if let Some(o) = self.origin
            && !o.is_finite()
        {
            return Err(CoreError::InvalidParams(format!(
                "the rays' origin {o} is not finite"
            )));
        }
        if self.auto.is_some()
            && !self.origin_given
            && let Some(seen) = self.seen.take()
        {
            // The rays began or stopped starting at one point: choose again, on them.
            if seen.origin.is_some() != self.origin.is_some() {
                self.choice = None;
                self.seen_sample = Some(seen.sample);
            }
            self.origin = seen.origin;
        }
        // Only a choice at an origin reads the bounds; read once, they also
        // place the views of the build.
        let mut known: Option<Aabb> = None;
        let mut bounds = || *known.get_or_insert_with(|| dirt_core::bounds_of(tris));
        // (A centre of the split orthographic views is their cut, not an origin.)
        if self.auto.is_some() && self.params.center.is_some() && !self.params.views.is_ortho() {
            // A choice placed at the origin moves with it; a single view must
            // still see the whole scene from there, else the choice is made again.
            match self.origin {
                Some(o) => self.params.center = Some(o),
                None => self.choice = None,
            }
            if let Some(c) = self.params.center
                && self.params.views == ViewsKind::Single
                && !single_sees_all(c, &bounds())
            {
                self.choice = None;
            }
        }
        if let Some(rays_per_frame) = self.auto
            && self.choice.as_ref().is_none_or(|(n, _)| *n != tris.len())
        {
            let start = Instant::now();
            // Rays that all start at one point are best served by views
            // placed there (one point of a view a ray): only those are weighed.
            let candidates = match self.origin {
                Some(o) => cost::candidates_at(o, &bounds()),
                None => cost::candidates_all(&AdsParams::default(), tris),
            };
            // The caller's rays, else those traced, else generated ones.
            let given = self.sample.as_ref().or(self.seen_sample.as_ref());
            let sample = match (given, self.origin) {
                (Some(rays), _) => cost::stride_sample(rays, AUTO_SAMPLE),
                (None, Some(o)) => cost::sample_rays_from(o, tris, AUTO_SAMPLE, 1),
                (None, None) => cost::sample_rays(tris, AUTO_SAMPLE, 1),
            };
            let mut choice = cost::auto_budgeted(
                tris,
                &sample,
                rays_per_frame,
                self.traversal,
                &CostModel::CALIBRATED,
                &candidates,
                None,
                cost::KEPT_BUDGET,
            )?;
            self.params = choice.best.params;
            let built = choice.best_ads.take();
            self.choice = Some((tris.len(), choice));
            let mut choose = start.elapsed();
            // The winner was built while choosing, over these very triangles.
            let (ads, built_stages) = match built {
                Some(ads) => (ads, Vec::new()),
                None => {
                    let ads = Ads::build_bounded(tris, &self.params, known)?;
                    let built_stages = ads.timings.stages();
                    (ads, built_stages)
                }
            };
            if self.measure_traversal {
                let start = Instant::now();
                let sample = match (given, self.origin) {
                    (Some(rays), _) => rays.clone(),
                    (None, Some(o)) => cost::sample_rays_from(o, tris, TRAVERSAL_SAMPLE, 2),
                    (None, None) => cost::sample_rays(tris, TRAVERSAL_SAMPLE, 2),
                };
                let timed = cost::faster_traversal(&ads, tris, &sample);
                self.traversal = timed.traversal;
                self.traversal_choice = Some(timed);
                choose += start.elapsed();
            }
            self.seen_sample = None;
            stages.push(("choose", choose));
            stages.extend(built_stages);
            return Ok(self.keep(ads, tris, stages));
        }
        let ads = Ads::build_bounded(tris, &self.params, known)?;
        stages.extend(ads.timings.stages());
        Ok(self.keep(ads, tris, stages))
    }
}

impl Tracer for DirtCpu {
    fn name(&self) -> String {
        if self.choice().is_none() {
            return format!("dirt-cpu ({})", self.traversal);
        }
        // Say what the cost model chose, since nobody gave it (the centre
        // follows the origin, so it is read from the parameters in use).
        let p = self.params;
        let at = match p.center {
            // The split orthographic views' centre is a point of their cut.
            Some(c) if p.views.is_ortho() => format!(" cut through {},{},{}", c.x, c.y, c.z),
            Some(_) => " at the rays' origin".to_string(),
            None => String::new(),
        };
        format!(
            "dirt-cpu ({}; the cost model's {} r{} B{} S{}{at})",
            self.traversal, p.views, p.resolution, p.buckets, p.tile
        )
    }

    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        // In the pool, with the choice's builds and sample traces.
        crate::in_pool(|| self.rebuild(tris))
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        check_lengths(rays, hits, stats.as_deref())?;
        let ads = self.ads.as_ref().ok_or_else(|| CoreError::NotBuilt {
            tracer: self.name(),
        })?;
        let with_stats = stats.is_some();
        let origin = trace_into_from(
            ads,
            &self.tris,
            rays,
            self.traversal,
            hits,
            stats,
            Some(&mut self.boxes),
        );
        if self.auto.is_some() && !self.origin_given && !rays.is_empty() {
            // Watching: do all rays since the last build start at one point?
            self.seen = Some(match self.seen.take() {
                None => Seen {
                    origin,
                    sample: cost::stride_sample(rays, TRAVERSAL_SAMPLE),
                },
                Some(seen) => Seen {
                    origin: origin.filter(|o| seen.origin == Some(*o)),
                    sample: seen.sample,
                },
            });
        }
        Ok(TraceReport {
            continuation_rounds: 0,
            stats: with_stats,
        })
    }

    fn counts_stats(&self) -> bool {
        true
    }
}
