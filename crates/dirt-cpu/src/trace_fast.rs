//! The `trace` stage without the per-ray overhead of the plain loops in
//! [`crate::trace`](mod@crate::trace). Every float operation that decides
//! anything is the plain stage's, with the same operands in the same order,
//! so the hits *and* the per-ray statistics are bit-identical to it (and so
//! to `trace.wgsl`); `tests/trace_fast.rs` checks that on random scenes, rays
//! and parameters. What differs is only where values live, how often they are
//! computed, and which of them the compiler can put side by side in one
//! vector register:
//!
//! - Nothing is allocated per ray: the per-view rays, intervals and exits
//!   live in arrays of [`MAX_VIEWS`]; the Hi-Z stack (bounded by the walk's
//!   depth, `3·levels + 1`) is allocated once per thread and reused.
//! - Statistics are a const parameter: with `STATS = false` the counting is
//!   compiled out.
//! - Clipping by cuts. What one half-space does to a ray interval — the `t`
//!   where the ray crosses it, and whether that raises `t0`, lowers `t1`, or
//!   empties the interval — depends only on the half-space and the ray
//!   ([`Cut`], [`Interval::clip`] split in two). Cuts are computed without
//!   branches, several half-spaces as lanes of one vector ([`cut_lanes`]), and
//!   applied in the plain stage's order. Where the plain stage returns `EMPTY`
//!   as soon as an interval is empty, checking once at the end gives the same
//!   result: `t0` only rises and `t1` only falls, and neither is ever NaN.
//! - A Hi-Z child shares two of its four side half-spaces with its parent and
//!   the other two with a sibling, so an expansion computes only the four
//!   through the parent's middle ([`HiZCell::clip`] computed all four for
//!   every cell popped). The tests that do not depend on the best hit (empty
//!   interval, depth span against the cell's bounds) are made for the four
//!   children together, as lanes, when their parent is expanded, and only the
//!   cells that pass wait on the stack; the test against the best hit stays
//!   where the plain stage makes it, when a cell is popped. The same cells
//!   are visited in the same order.
//! - The linear walk prepares its bands [`BAND_LANES`] at a time: their
//!   cuts, intervals and the minor tile coordinates of their ends, as lanes
//!   (none of it depends on the best hit), then walks them one by one as the
//!   plain stage does, the termination test first. This breaks the chain of
//!   divisions from one band to the next. A tile's pair of minor-axis cuts
//!   is kept for the next band, whose first tile is usually the last tile of
//!   this one. In an orthographic view every side of an axis has the same
//!   slope, `±d`, so which of a cut's ends is bounded is decided once for
//!   the lanes ([`ortho_sides`]), not by selects in each.
//! - Without statistics, where the plain stage is exact ([`Scene::exact`]:
//!   every view set but a single view that does not hold every triangle),
//!   the tiles of a band are searched over the band's interval, without
//!   their minor-axis cuts. A tile's own interval is the band's cut by two
//!   more half-spaces, so it lies within it: the tile's depth span and
//!   segment box are wider and its candidates more, and the tiles of the
//!   band's index range whose own interval is empty are searched too. Each
//!   candidate gives a hit of the ray or none, and the plain stage's
//!   closest, every ray's closest of all triangles there, is among them, so
//!   the closest is the same; the walk still ends where a band starts after
//!   the best hit. Elsewhere a candidate the plain stage does not test could
//!   give a hit it misses, and the tiles are cut as before. The eval's rays,
//!   2 threads, best of four alternated runs: bunny (ortho r32 B8) 207 →
//!   199 ns a ray, cornell (ortho2 r16 B8) 371 → 352, layers (ortho r32 B8)
//!   137 → 126, 2CylinderEngine (ortho r128 B8) 471 → 416; foliage (ortho
//!   r16 B8) 552 → 608 and spheres (ortho r64 B8) 353 → 374 are slower,
//!   their tiles dense enough that the wider intervals cost more tests than
//!   the cuts did. Both come from bands whose ends lie in two tiles:
//!   cutting only the tiles reached through the dilation alone kept the
//!   loss and lost the gains; cutting only the tiles the ends reach lost
//!   the gains and most of the loss. At the fixed setting, cube r128 B8,
//!   whose rays cross more tiles, all three gain: bunny 809 → 636,
//!   cornell 1764 → 1391, foliage 2398 → 2179 (best of three). Also
//!   measured and not kept: a band's tiles cut only where they meet one
//!   another, each cut a product by `1 / d` widened to hold the division's
//!   (one thread: about half the gain elsewhere, foliage unchanged; two
//!   threads: foliage as slow as here), and the tiles' cuts made as lanes,
//!   four tiles of a band at a time (no gain).
//! - Without statistics, a short linear walk that could only reach cells
//!   whose depth bounds its depth span misses is left out
//!   ([`RayState::meets_nothing`], on at most four Hi-Z cells): it would
//!   test no triangle. Camera rays from a view's apex that miss the scene
//!   end there (the deforming grid's misses, 100,000 camera rays: 4.9 ms →
//!   4.1 ms). With statistics the walk is made, as the plain stage counts it.
//! - Without statistics, in a set of one perspective view, a ray that
//!   starts exactly at the view's apex (a camera's ray, the view placed at
//!   the camera) does not move across the tiles: its tile coordinate is its
//!   direction's. When every tile within the walk's dilation of it is empty
//!   ([`Apex::look`], on at most four Hi-Z cells), the ray misses,
//!   found before its set-up in the view. The deforming grid's 72,847
//!   misses of 100,000 camera rays (r256 B1, 1 thread): 108 → 54 ns each.
//!   For a batch of such rays with a ray per [`TILES_PER_RAY`] tiles, the
//!   tiles' emptiness is read from a bit a tile made once per call, not
//!   from the pyramid. Where some tile there holds content and the view
//!   holds every triangle (each inside its frustum shrunk by `eps`, found
//!   by `fill_depth` as it covers them: [`Ads::sees_all`]), the ray skips
//!   its set-up and walk too: every bucket of those few tiles is tested,
//!   front to back ([`RayState::direct`]), a superset of the walk's
//!   candidates, whose closest is the same hit because the walk's already
//!   is every triangle's closest there. The deforming grid's 100,000
//!   camera rays (r256 B1, alternated runs, best of 20 each): 13.9 → 12.4
//!   ms on 1 thread, 7.1 → 6.3 ms on 2.
//! - There, for a batch with a ray from the apex for every
//!   [`APEX_RAYS_PER_TRIANGLE`] triangles (with `DirtCpu`, counting the
//!   earlier traces of the build), each triangle's box in the view's image
//!   is computed first ([`apex_boxes`]: the range of its vertices' tile
//!   coordinates, widened as [`polygon_tile_range`] widens it before it
//!   floors them), and a listed triangle whose image box misses the ray's
//!   (its direction's tile coordinates within the look's margin,
//!   [`Apex::coords`]) is not tested. The view-space boxes above do not
//!   serve these rays: such a ray crosses a tile along its depth, and its
//!   segment's box spans the tile. That changes no hit: the closest hit
//!   point lies on the ray, so its tile coordinates lie within the margin
//!   of the direction's (what makes the look hold every tile the walk
//!   reaches), and on the triangle, so within its image range widened by
//!   the coverage rule's dilation (what makes the rule list the triangle
//!   in the tile that holds the point); a triangle left out is not entered
//!   in the mailbox. The deforming grid's 100,000 camera rays at r256 B1
//!   tested about a third as many triangles: 1383 → 946 instructions a ray
//!   (1 thread), 86 → 73 ns a ray on 2 threads (best of ten, alternated),
//!   and build plus first trace 12.7 → 11.6 ms; the boxes cost about 180
//!   instructions a triangle, which 5,000 rays on those 32,768 triangles
//!   would not earn back. A build at the rays' origin (`AdsParams::center`)
//!   makes the same boxes as `fill_depth` covers the triangles, from the
//!   values its lanes compute anyway ([`Ads::image_boxes`]), and every
//!   batch from the apex reads them: the deforming grid's build and one
//!   trace of its 5,000 camera rays (single r128 B2, 1 thread) took 58.3 M
//!   → 54.5 M instructions, `fill_depth` 30.6 M → 32.2 M (49 a triangle
//!   more), the trace 10.9 M → 5.5 M; the trace alone, best of 30 on 2
//!   threads, 0.97 → 0.61 ms.
//! - Without statistics, the rays of a chunk ([`LOOKS`]) are looked at from
//!   the apex before any is traced, [`LOOK_LANES`] side by side where the
//!   tiles' content bits are made ([`Scene::looks_at_apex`], each lane
//!   [`Apex::look`]'s operations, so its bits): a miss then costs no call
//!   of the trace, and a ray that goes on is not looked at again
//!   ([`trace_looked`]). The deforming grid's misses (r256 B1, 1 thread):
//!   about 45 → 36 ns each.
//! - Without statistics, a ray's interval in a view is cut to where its
//!   depth lies within the depth bounds of the view's whole content (its
//!   Hi-Z root cell) widened by twice the ray's `eps` ([`Scene::to_content`]):
//!   no hit lies outside them. The walk then starts where content can
//!   begin, and its dilation, set by the smallest depth of its interval, is
//!   that of the content's front, not of the near plane. A camera's ray from
//!   a single view placed at its eye entered 2.8 tiles on the deforming grid
//!   (the near plane at 0.71, the grid from about 2); its hits went from
//!   436 to 394 ns (1 thread, best of five alternated runs), and the apex
//!   check's margin ([`Apex::of`]) shrinks with it. In an orthographic view
//!   whose tiles with content lie within half its image, the interval is
//!   also cut to their rectangle, a tile wider each side ([`content_rect`]):
//!   2CylinderEngine's rays at ortho r128 B8 (content over 37 % of the
//!   rows) took 8.8 % fewer instructions with the linear walk, and the
//!   eval's, whose bounce and shadow rays leave those rows, were traced at
//!   2.46 Mrays/s instead of 1.30 (scripts/eval, 2 threads).
//! - Without statistics, the Hi-Z walk starts at the (at most 2 × 2) cells
//!   of the lowest level that hold every tile the ray can reach ([`reach`]),
//!   not at the root. A cell's interval and depth test do not depend on its
//!   parent, so every cell the plain walk visits below that level is still
//!   visited; the ancestors' tests could only drop more. Extra candidates
//!   change no hit. With statistics the walk starts at the root.
//! - Without statistics, a triangle already tested by this ray is not
//!   tested again (a mailbox of recent ids per thread, [`MAILBOX`] entries
//!   tagged with the ray): a triangle listed in several tiles and buckets
//!   along the ray gives the same candidate each time, which the best hit
//!   either already is or already beats, so skipping it changes no bit. With
//!   statistics every listed triangle is tested, as the plain stage counts.
//! - Without statistics, for a batch of rays that do not all start at the
//!   centre of perspective views and number at least one for every
//!   [`PAIRS_PER_RAY`] (triangle, view) pairs, every triangle's box in
//!   every view is computed first
//!   ([`triangle_boxes`]: the range of each view-space coordinate of its
//!   vertices, widened by twice the view's `eps`), and a listed triangle
//!   whose box misses the box of the ray's segment in the tile (each
//!   coordinate at both ends of its interval, widened by the ray's `eps`;
//!   its depth is the span the buckets are chosen by) is not tested there.
//!   The eval's cornell rays, every kind in one batch: the depth alone left
//!   out 39% of the listed tests, the box 73%. That changes no hit: where
//!   the plain stage finds the closest hit, in the tile that holds the hit
//!   point, the hit's `t` lies in the ray's interval there, so each of the
//!   point's coordinates lies in the ray's span of it (the point is within
//!   a quarter `eps` of the ray, [`EPS_RAY_REL`]) and in the triangle's
//!   range (the point lies in the triangle, the vertices' coordinates are
//!   rounded by a few ulps of the scale; the margin covers both roundings),
//!   so the triangle is tested there; a triangle left out is not entered in
//!   the mailbox; and until the closest hit is found, the walk's
//!   termination tests compare with a `t` no smaller than its own, so they
//!   do not stop it earlier. Testing fewer candidates that still hold the
//!   closest gives the same closest. The three coordinates are alike here:
//!   a view's coordinates are a rotation of the world's about its apex, the
//!   same operations for each. Rays from the centre of perspective views
//!   (a cube's centre, a single view's apex) cross a tile within its own
//!   narrow cone, along the depth axis, where the span is about the tile's
//!   whole extent: they skip little, so the boxes are not computed for
//!   them. Rays from one point elsewhere (a camera's, through orthographic
//!   views or a cube at the bounds' centre) cross tiles like any others:
//!   cornell's camera rays through two orthographic views (r16 B8) tested
//!   23.0 listed triangles a ray without the boxes, 3.3 with them.
//!   `DirtCpu` keeps the boxes across the traces of one build
//!   ([`BoxCache`]): there the rays traced on the build so far count
//!   towards paying for them, so that batches too small
//!   to pay alone (`spheres`, 33,794 triangles, batches of 5,000 rays) read
//!   them once their sum has paid (its trace, 1 thread: 998 → 880 ns a
//!   ray; `2CylinderEngine` 1214 → 1103).
//! - A bucket's triangles are tested [`LANES`] at a time
//!   ([`intersect_closest_lanes`]: the edge functions of several triangles
//!   side by side, each lane the scalar test's bits); the closest hit of a
//!   list does not depend on the order its triangles are tested in. Two or
//!   three left over are one more group, a triangle repeated in the spare
//!   lanes (testing a candidate twice changes no hit).
//! - Batches of [`ORDER_MIN_RAYS`] rays or more that do not all start at one
//!   point are traced in a coherent order ([`coherent_order`]: direction
//!   face, then Morton code of the origin); the results go back to input
//!   order. Rays from one point (a camera's) keep their own order.
//! - Tile boundary slopes ([`View::boundary`]) come from a table made once per
//!   `trace` call.
//! - A ray's set-up in every view (its view-space ray and its interval in the
//!   view's frustum) is computed for all views at once, one lane a view
//!   ([`ViewLanes`]), from the views' constants laid side by side once per
//!   `trace` call; as many lanes as the set has views, rounded up to 1, 4
//!   or 8 (a single view is one lane, not eight).
//!
//! [`HiZCell::clip`]: dirt_math::dda::HiZCell::clip
//! [`polygon_tile_range`]: dirt_math::clip::polygon_tile_range

use crate::Ads;
use crate::intersect_lanes::{LANES, intersect_closest_lanes};
use crate::trace::next_view;
use dirt_core::{RayStats, Traversal, ViewsKind};
use dirt_math::bucket::{bucket_ceil_depth, bucket_floor_depth, bucket_pair};
use dirt_math::clip::{HalfSpace, Interval, ray_depth, ray_point, tile_extent, view_frustum};
use dirt_math::dda::{child_order, dilation, hiz_width};
use dirt_math::encode::ordered_to_f32;
use dirt_math::num::{floor_index, fmax, fmin};
use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::view::EPS_RAY_REL;
use dirt_math::{Hit, Ray, Triangle, View, ViewRay, ViewSet};
use std::array::from_fn;
use std::borrow::Cow;

/// Most views a view set has (the cube); larger sets take the plain stage.
pub(crate) const MAX_VIEWS: usize = 6;

/// Most Hi-Z levels the fast path takes (`2^31` tiles per side); more take the plain stage.
const MAX_LEVELS: usize = 32;

/// Depth of the Hi-Z stack: at most three siblings wait per level, plus the
/// cell on top; one more slot, because a child is written before it is known
/// whether it is kept.
const STACK: usize = 3 * MAX_LEVELS + 2;

/// What a ray trace needs of the structure, gathered once per `trace` call.
pub(crate) struct Scene<'a> {
    ads: &'a Ads,
    tris: &'a [Triangle],
    views: &'a [View],
    /// Cells per side of each Hi-Z level.
    widths: [u32; MAX_LEVELS],
    levels: u32,
    buckets: u32,
    /// Per view, the slope of every tile boundary ([`View::boundary`]).
    slopes: Vec<Vec<f32>>,
    /// The views' constants as lanes, for [`ViewLanes::enter`].
    lanes: ViewLanes,
    /// [`triangle_boxes`], when [`Scene::prepare_for`] found they pay
    /// (computed, or kept from earlier traces in a [`BoxCache`]); else empty.
    boxes: Cow<'a, [ViewBox]>,
    /// [`apex_boxes`], when [`Scene::prepare_for`] found they pay; else empty.
    screen: Cow<'a, [ViewBox]>,
    /// A single perspective view's apex check ([`Apex`]).
    apex: Option<Apex<'a>>,
    /// Per view, the depth bounds of all its content (its Hi-Z root cell),
    /// decoded: `[+inf, -inf]` where it has none ([`Scene::to_content`]).
    content: [[f32; 2]; MAX_VIEWS],
    /// Per orthographic view, the view-space rectangle `[xlo, xhi, ylo,
    /// yhi]` that holds every tile with content, a tile wider on each side,
    /// where it is at most half the image ([`content_rect`]); `None` for
    /// perspective views and the others ([`Scene::to_content`]).
    rect: [Option<[f32; 4]>; MAX_VIEWS],
    /// Whether the plain stage's hit is every ray's closest of all
    /// triangles: every kind of view set but a single view that does not
    /// hold every triangle ([`ViewsKind`]'s docs, [`Ads::sees_all`]). Only
    /// there may the walk test more candidates than the plain stage.
    exact: bool,
}

impl<'a> Scene<'a> {
    /// `None` when the view set is larger than the fast path's arrays.
    pub(crate) fn new(ads: &'a Ads, tris: &'a [Triangle]) -> Option<Self> {
        let views = &ads.views.views[..];
        let levels = ads.hiz.len();
        if views.len() > MAX_VIEWS || levels == 0 || levels > MAX_LEVELS {
            return None;
        }
        let tiles = ads.params.tiles();
        let mut widths = [0; MAX_LEVELS];
        for (l, w) in widths.iter_mut().enumerate().take(levels) {
            *w = hiz_width(tiles, l as u32);
        }
        let slopes = views
            .iter()
            .map(|v| (0..=v.tiles).map(|k| v.boundary(k)).collect())
            .collect();
        let top = levels - 1;
        let root = widths[top] as usize * widths[top] as usize;
        let content = from_fn(|f| match views.get(f) {
            Some(v) if v.has_content => ads.hiz[top]
                .get(v.slot as usize * root)
                .map_or([f32::INFINITY, f32::NEG_INFINITY], |z| {
                    z.map(ordered_to_f32)
                }),
            _ => [f32::INFINITY, f32::NEG_INFINITY],
        });
        let rect = from_fn(|f| match views.get(f) {
            Some(v) if v.ortho && v.has_content => content_rect(ads, v, &widths[..levels]),
            _ => None,
        });
        Some(Scene {
            content,
            rect,
            exact: ads.views.kind != ViewsKind::Single || ads.sees_all,
            ads,
            tris,
            views,
            widths,
            levels: levels as u32,
            buckets: ads.params.buckets,
            slopes,
            lanes: ViewLanes::new(views),
            boxes: Cow::Borrowed(&[]),
            screen: Cow::Borrowed(&[]),
            apex: Apex::of(views, content[0][0], ads.sees_all),
        })
    }

    /// Whether no tile of `r` in `v` has depth bounds that the depth span
    /// `r.depth` meets; decided on the at most four cells of [`Reach::level`]
    /// (a cell's bounds hold its tiles' bounds).
    #[inline]
    fn nothing_in(&self, v: &View, r: &Reach) -> bool {
        let level = r.level(self.levels);
        let (dlo, dhi) = r.depth;
        let w = self.widths[level as usize];
        let cells = &self.ads.hiz[level as usize][v.slot as usize * (w * w) as usize..];
        for j in (r.j.0 >> level)..=(r.j.1 >> level) {
            for i in (r.i.0 >> level)..=(r.i.1 >> level) {
                let [zmin, zmax] = cells[(j * w + i) as usize];
                if dhi >= ordered_to_f32(zmin) && dlo <= ordered_to_f32(zmax) {
                    return false;
                }
            }
        }
        true
    }

    /// Computes the triangles' boxes ([`triangle_boxes`]) when they
    /// pay for `rays` (module docs): the rays do not all start at the
    /// centre of perspective views (a cube's, a single view's apex)
    /// and number at least one for every [`PAIRS_PER_RAY`] (triangle, view)
    /// pairs. With a `cache` (the traces of one build), the rays of the
    /// earlier traces count too, and the boxes, once computed, are kept
    /// there for the traces after. Only the trace without statistics reads
    /// them.
    ///
    /// For rays that all start at the apex of a single view ([`Apex`]),
    /// numbering at least one for every [`TILES_PER_RAY`] tiles, it marks
    /// the view's tiles with content instead ([`Apex::mark`]); where the
    /// view holds every triangle, it reads the triangles' image boxes the
    /// build made ([`Ads::image_boxes`]), or, for a structure without
    /// them, computes them ([`apex_boxes`]) once such rays number one for
    /// every [`APEX_RAYS_PER_TRIANGLE`] triangles (with a `cache`, counting
    /// those of the earlier traces, and kept there).
    /// `origin` is the rays' [`common_origin`](crate::cost::common_origin).
    pub(crate) fn prepare_for(
        &mut self,
        rays: &[Ray],
        origin: Option<dirt_math::Vec3>,
        cache: Option<&'a mut BoxCache>,
    ) {
        let pairs = self.tris.len().saturating_mul(self.ads.views.slots());
        let (ads, tris, n) = (self.ads, self.tris, rays.len() as u64);
        let (view_cache, image_cache) = match cache {
            Some(c) => (Some(&mut c.view), Some(&mut c.image)),
            None => (None, None),
        };
        let at_apex = match (origin, &self.apex) {
            (Some(o), Some(apex)) => o.to_array().map(f32::to_bits) == apex.at,
            _ => false,
        };
        // Rays from the centre of perspective views (a cube's, a single
        // view's apex) skip little (module docs): no view-space boxes for them.
        let views = &ads.views;
        let radial = origin.is_some_and(|o| {
            !views.kind.is_ortho()
                && o.to_array().map(f32::to_bits) == views.center.to_array().map(f32::to_bits)
        });
        if !radial {
            let pays = |rays: u64| rays.saturating_mul(PAIRS_PER_RAY as u64) >= pairs as u64;
            self.boxes = Paid::boxes(view_cache, n, pays, || triangle_boxes(&ads.views, tris));
        }
        if let (true, Some(apex)) = (at_apex, self.apex.as_mut()) {
            if rays.len().saturating_mul(TILES_PER_RAY) >= self.views[0].tile_count() {
                apex.mark(&ads.hiz[0][..self.views[0].tile_count()]);
            }
            if apex.direct && ads.image_boxes.len() == tris.len() {
                // Made by the build, as it covered the triangles: no cost here.
                self.screen = Cow::Borrowed(&ads.image_boxes);
            } else if apex.direct {
                let pays =
                    |rays: u64| rays.saturating_mul(APEX_RAYS_PER_TRIANGLE) >= tris.len() as u64;
                let v = apex.view;
                self.screen = Paid::boxes(image_cache, n, pays, || apex_boxes(v, tris));
            }
        }
    }

    /// The boxes of the triangles in `v` ([`Scene::prepare_for`]), if computed.
    #[inline]
    fn boxes(&self, v: &View) -> Option<&[ViewBox]> {
        let n = self.tris.len();
        let at = v.slot as usize * n;
        self.boxes.get(at..at + n)
    }

    /// `iv` cut to where the ray's depth in view `f` lies within its
    /// content's depth bounds widened by twice the ray's `eps`: empty for a
    /// view without content.
    ///
    /// Why no hit is lost: the closest hit lies in a tile of some view the
    /// ray walks, inside the depth extent of its triangle's fragment there,
    /// which lies within the tile's bounds and so within the root's. The
    /// ray's depth at the hit's `t` differs from the hit point's by less
    /// than one `eps` (what the tiles' depth tests allow for already), and
    /// the cut's rounding (`(z − o)/d`, a few ulps of `|z| + |o|`, both at
    /// most the scale `eps` is 2⁻¹² of) takes far less than the second.
    /// The walk then starts where content can begin: its dilation, set by
    /// the smallest depth of its interval, is no longer that of the near
    /// plane (a camera's ray from a view placed at its eye entered 2.8
    /// tiles on the deforming grid where its direction lies in one).
    ///
    /// In an orthographic view whose content fills at most half the image,
    /// `iv` is also cut to the rectangle of its tiles with content
    /// ([`content_rect`]): a ray from outside that part of the image then
    /// walks fewer bands and starts its Hi-Z walk lower.
    #[inline]
    fn to_content(&self, f: usize, vr: &ViewRay, iv: &mut Interval) {
        let [zmin, zmax] = self.content[f];
        let depth = (zmin - 2.0 * vr.eps, zmax + 2.0 * vr.eps);
        cut_to_slab(vr.o[2], vr.d[2], depth, iv);
        if let Some([xlo, xhi, ylo, yhi]) = self.rect[f] {
            cut_to_slab(vr.o[0], vr.d[0], (xlo, xhi), iv);
            cut_to_slab(vr.o[1], vr.d[1], (ylo, yhi), iv);
        }
    }
}

/// `iv` cut to where `o + t·d` lies in `[lo, hi]` (empty where `d` is 0
/// and `o` lies outside).
#[inline(always)]
fn cut_to_slab(o: f32, d: f32, (lo, hi): (f32, f32), iv: &mut Interval) {
    if d > 0.0 {
        iv.t0 = fmax(iv.t0, (lo - o) / d);
        iv.t1 = fmin(iv.t1, (hi - o) / d);
    } else if d < 0.0 {
        iv.t0 = fmax(iv.t0, (hi - o) / d);
        iv.t1 = fmin(iv.t1, (lo - o) / d);
    } else if !(o >= lo && o <= hi) {
        *iv = Interval::EMPTY;
    }
}

/// Cells per side of the Hi-Z level [`content_rect`] reads, at most.
const RECT_CELLS: u32 = 32;

/// For an orthographic view with content, the view-space rectangle `[xlo,
/// xhi, ylo, yhi]` of its tiles with content, read from the first Hi-Z
/// level at most [`RECT_CELLS`] cells wide (each cell holds its tiles'
/// bounds: a cell without content has none), one tile wider on every side.
/// `None` where no cell has content, and where the rectangle is more than
/// half the image: the ray's clip to the view's frustum has cut it to the
/// image already, and a cut to most of it costs two divisions a ray and
/// saves little (cornell's ortho2 r16 B8, content over two thirds of each
/// image: 1.1 % more instructions; 2CylinderEngine's ortho r128 B8, over
/// 37 % of the rows: 8.8 % fewer with the linear walk, 1.4 % with Hi-Z).
///
/// Why no hit is lost by cutting a ray to it ([`Scene::to_content`]): the
/// closest hit point lies on its triangle and in some tile, so that tile
/// lists a fragment of the triangle and has content; the ray's point at
/// the hit's `t` is within rounding of the hit point, far less than the
/// tile of margin (a tile is `2·half/tiles` wide, the rounding a few ulps
/// of the view's scale), and the cut's own rounding is as small.
fn content_rect(ads: &Ads, v: &View, widths: &[u32]) -> Option<[f32; 4]> {
    let level = widths.iter().position(|&w| w <= RECT_CELLS)?;
    let w = widths[level];
    let per = (w * w) as usize;
    let cells = ads.hiz[level].get(v.slot as usize * per..(v.slot as usize + 1) * per)?;
    let (mut i0, mut i1, mut j0, mut j1) = (u32::MAX, 0, u32::MAX, 0);
    for j in 0..w {
        for i in 0..w {
            let [zmin, zmax] = cells[(j * w + i) as usize];
            // Empty bounds are [+inf, -inf].
            if ordered_to_f32(zmin) <= ordered_to_f32(zmax) {
                (i0, i1, j0, j1) = (i0.min(i), i1.max(i), j0.min(j), j1.max(j));
            }
        }
    }
    if i0 > i1 {
        return None;
    }
    // Cells to tile boundaries, a tile wider each side, within the image.
    let first = |c: u32| (c << level).saturating_sub(1);
    let end = |c: u32| (((c + 1) << level) + 1).min(v.tiles);
    let area = u64::from(end(i1) - first(i0)) * u64::from(end(j1) - first(j0));
    if 2 * area > u64::from(v.tiles) * u64::from(v.tiles) {
        return None;
    }
    let (lo, hi) = (|c| v.boundary(first(c)), |c| v.boundary(end(c)));
    Some([lo(i0), hi(i1), lo(j0), hi(j1)])
}

/// Tiles whose content bit one ray from a single view's apex pays for
/// ([`Scene::prepare_for`]): a tile's bit costs less than a nanosecond,
/// and it saves such a ray that misses a load from the Hi-Z pyramid, often
/// from memory (camera rays come in no order).
const TILES_PER_RAY: usize = 8;

/// (Triangle, view) pairs whose boxes one ray of a batch pays for
/// ([`Scene::prepare_for`]): a box costs a few nanoseconds, a test left
/// out about 6 (the eval's cornell rays: 39% of the listed tests left out
/// with depths alone, 73% with the box). Not fewer: boxes for every batch
/// of 5,000 rays (1 thread, the eval's five kinds) made `2CylinderEngine`'s
/// trace 13-22% slower (121,496 triangles, 2.8 ms of boxes a call) and
/// `spheres`' no faster (33,794; 890-934 against 906-933 ns a ray).
const PAIRS_PER_RAY: usize = 4;

/// Per view slot, then triangle (`slot · tris.len() + id`): the triangle's
/// box in the view, `[min, max]` of each of its vertices' view-space
/// coordinates ([`View::to_view`]) widened by twice the view's `eps` (module
/// docs). A fragment's depth extent is clipped from those same depths,
/// widened by one `eps`; the second covers the clip's few ulps of rounding.
///
/// The cull rests on the hit point lying inside a view the ray walks. The
/// cube (its apexes shifted back so that nothing hides behind the near
/// planes) and the orthographic views cover the whole scene; a single view
/// covers it only when it sees all of it, and where it does not, the plain
/// stage can find a hit outside the view, on a triangle listed for its part
/// inside. So in a single view, a triangle not inside the frustum shrunk by
/// `eps` (each vertex inside every plane: the frustum is convex) gets the
/// whole space, [`ViewBox::WHOLE`], and is never left out.
pub(crate) fn triangle_boxes(set: &ViewSet, tris: &[Triangle]) -> Vec<ViewBox> {
    let n = tris.len();
    let mut out = vec![ViewBox::WHOLE; set.slots() * n];
    let partial = set.kind == ViewsKind::Single;
    for v in set.views.iter().filter(|v| v.has_content) {
        let planes = view_frustum(v);
        let at = v.slot as usize * n;
        let Some(slice) = out.get_mut(at..at + n) else {
            continue;
        };
        let margin = 2.0 * v.eps;
        boxes_of(slice, tris, |t| {
            let p: [[f32; 3]; 3] = from_fn(|k| v.to_view(t.vertex(k)));
            if partial
                && !planes
                    .iter()
                    .all(|h| p.iter().all(|&p| h.eval(p, -v.eps) >= 0.0))
            {
                return None;
            }
            let lo: [f32; 3] = from_fn(|c| fmin(fmin(p[0][c], p[1][c]), p[2][c]) - margin);
            let hi: [f32; 3] = from_fn(|c| fmax(fmax(p[0][c], p[1][c]), p[2][c]) + margin);
            Some(ViewBox::new(lo, hi))
        });
    }
    out
}

/// A box in a view's space: `[x, y, z]` and a fourth lane that every box
/// holds as 0 (so that a test is one vector comparison). A triangle's
/// ([`triangle_boxes`]) or a ray segment's ([`span_box`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct ViewBox {
    lo: [f32; 4],
    hi: [f32; 4],
}

impl ViewBox {
    /// Every point: a triangle that is never left out.
    pub(crate) const WHOLE: ViewBox = ViewBox {
        lo: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0],
        hi: [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0],
    };

    fn new(lo: [f32; 3], hi: [f32; 3]) -> ViewBox {
        ViewBox {
            lo: [lo[0], lo[1], lo[2], 0.0],
            hi: [hi[0], hi[1], hi[2], 0.0],
        }
    }

    /// Whether the boxes overlap in every coordinate (touching counts).
    #[inline(always)]
    fn meets(&self, other: &ViewBox) -> bool {
        let miss: [bool; 4] = from_fn(|c| (self.hi[c] < other.lo[c]) | (self.lo[c] > other.hi[c]));
        !miss.iter().any(|&m| m)
    }
}

/// The triangle boxes of one build, kept across its traces (`DirtCpu`):
/// computed in the trace whose rays, with those of the traces before it,
/// number one for every [`PAIRS_PER_RAY`] (triangle, view) pairs
/// ([`Scene::prepare_for`]), where a single trace would need that many
/// itself. Rays from the centre of perspective views do not count: they
/// do not read those boxes.
/// Rays from the apex of a single view that holds every triangle read the
/// triangles' image boxes instead, paid for and kept the same way. A new
/// build starts a new cache.
#[derive(Debug, Default)]
pub(crate) struct BoxCache {
    /// [`triangle_boxes`], for rays not from the centre of perspective
    /// views (without statistics).
    view: Paid,
    /// [`apex_boxes`], for rays from the apex of a single view that holds
    /// every triangle.
    image: Paid,
}

impl BoxCache {
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        (self.view.boxes.capacity() + self.image.boxes.capacity()) * std::mem::size_of::<ViewBox>()
    }
}

/// Boxes of one kind that the rays traced on a build pay for.
#[derive(Debug, Default)]
struct Paid {
    /// Rays traced of the kind that reads them.
    rays: u64,
    /// The boxes once computed; else empty.
    boxes: Vec<ViewBox>,
}

impl Paid {
    /// The boxes for a batch of `n` rays that read them: with a `cache`,
    /// computed by `make` once the rays traced on the build, these
    /// included, pay for them (`pays`) and kept there; without one,
    /// computed for this batch if it pays alone; else none.
    fn boxes<'a>(
        cache: Option<&'a mut Paid>,
        n: u64,
        pays: impl Fn(u64) -> bool,
        make: impl FnOnce() -> Vec<ViewBox>,
    ) -> Cow<'a, [ViewBox]> {
        match cache {
            Some(c) => {
                c.rays = c.rays.saturating_add(n);
                if c.boxes.is_empty() && pays(c.rays) {
                    c.boxes = make();
                }
                Cow::Borrowed(&c.boxes)
            }
            None if pays(n) => Cow::Owned(make()),
            None => Cow::Borrowed(&[]),
        }
    }
}

/// Rays from the apex ([`Apex::direct`]) one triangle's [`apex_boxes`] box
/// pays for is one over this ([`Scene::prepare_for`]).
const APEX_RAYS_PER_TRIANGLE: u64 = 2;

/// Per triangle, its box in `v`'s image, in tile coordinates: its
/// [`tile_extent`], which holds the image of every point within the
/// view's `eps` of the triangle (what [`polygon_tile_range`] floors to the
/// tiles it is listed in). Its depth is every depth. For a view that holds
/// every triangle ([`Apex::direct`]); a triangle with a vertex not in front
/// of half the near plane, or with coordinates that are not numbers, gets
/// [`ViewBox::WHOLE`].
///
/// [`polygon_tile_range`]: dirt_math::clip::polygon_tile_range
///
/// A build at the rays' origin makes the same boxes as it covers the
/// triangles ([`Ads::image_boxes`]); this is for a structure without them.
pub(crate) fn apex_boxes(v: &View, tris: &[Triangle]) -> Vec<ViewBox> {
    let mut out = vec![ViewBox::WHOLE; tris.len()];
    boxes_of(&mut out, tris, |t| {
        let p: [[f32; 3]; 3] = from_fn(|k| v.to_view(t.vertex(k)));
        let extent = tile_extent(v, &p)?;
        Some(image_box(v, p.map(|p| p[2]), extent))
    });
    out
}

/// [`apex_boxes`]' box of a triangle whose vertices have the depths `z` in
/// `v`, from its [`tile_extent`] `[x0, x1, y0, y1]`.
#[inline(always)]
pub(crate) fn image_box(v: &View, z: [f32; 3], [x0, x1, y0, y1]: [f32; 4]) -> ViewBox {
    // Where `View::w` would clamp a depth (not in front of half the near
    // plane, which a view that holds every triangle has none of), the
    // image is not the projection; and coordinates that are not numbers
    // (a degenerate view) bound nothing: never left out.
    let in_front = z.iter().all(|&z| z > v.near * 0.5);
    if in_front && [x0, x1, y0, y1].iter().all(|c| !c.is_nan()) {
        ViewBox::new([x0, y0, f32::NEG_INFINITY], [x1, y1, f32::INFINITY])
    } else {
        ViewBox::WHOLE
    }
}

/// Each triangle's box `f(t)` into its place in `out` (as long), where it
/// has one, on all threads.
fn boxes_of(
    out: &mut [ViewBox],
    tris: &[Triangle],
    f: impl Fn(&Triangle) -> Option<ViewBox> + Sync,
) {
    use rayon::prelude::*;
    out.par_chunks_mut(BOX_CHUNK)
        .zip(tris.par_chunks(BOX_CHUNK))
        .for_each(|(out, tris)| {
            for (o, t) in out.iter_mut().zip(tris) {
                if let Some(b) = f(t) {
                    *o = b;
                }
            }
        });
}

/// Triangles a task of [`triangle_boxes`] takes.
const BOX_CHUNK: usize = 4096;

/// Lanes of the per-view set-up: one a view, padded past the set's views.
const VIEW_LANES: usize = 8;

type Lanes = [f32; VIEW_LANES];

/// The views' constants side by side, so that a ray's set-up in every view —
/// [`View::ray`] and [`clip_ray_to_view`] — is computed as lanes of one
/// vector each (module docs). Lanes past the set's views repeat its first
/// view.
///
/// [`clip_ray_to_view`]: dirt_math::clip::clip_ray_to_view
struct ViewLanes {
    n: usize,
    apex: [Lanes; 3],
    /// `axes[r][c]`: component `c` of the view's right (`r = 0`), up, forward.
    axes: [[Lanes; 3]; 3],
    tan: Lanes,
    near: Lanes,
    far: Lanes,
    scale: Lanes,
    ortho: [bool; VIEW_LANES],
    has_content: [bool; VIEW_LANES],
}

/// A ray's set-up in every view ([`ViewLanes::enter`]): its view-space ray,
/// its interval in the view's frustum, and the side it leaves through (0..4).
type Entered = (
    [ViewRay; MAX_VIEWS],
    [Interval; MAX_VIEWS],
    [Option<usize>; MAX_VIEWS],
);

impl ViewLanes {
    fn new(views: &[View]) -> Self {
        // Scene::new takes at most MAX_VIEWS views.
        let n = views.len().min(MAX_VIEWS);
        let view = |k: usize| &views[if k < n { k } else { 0 }];
        let lanes = |f: &dyn Fn(&View) -> f32| -> Lanes { from_fn(|k| f(view(k))) };
        let axis = |r: usize, v: &View| [v.right, v.up, v.forward][r];
        ViewLanes {
            n,
            apex: from_fn(|c| lanes(&|v| v.apex[c])),
            axes: from_fn(|r| from_fn(|c| lanes(&|v| axis(r, v)[c]))),
            tan: lanes(&|v| v.tan),
            near: lanes(&|v| v.near),
            far: lanes(&|v| v.far),
            scale: lanes(&|v| v.scale),
            ortho: from_fn(|k| view(k).ortho),
            has_content: from_fn(|k| k < n && view(k).has_content),
        }
    }

    /// For every view, [`View::ray`] and, for views with content,
    /// [`clip_ray_to_view`](dirt_math::clip::clip_ray_to_view) from `tmin` to
    /// `tmax` (its six half-spaces as cuts, applied in its order): the same
    /// operations on the same operands, as lanes. Always inlined: its
    /// arrays are then written where the caller keeps them, not copied there.
    #[inline(always)]
    fn enter(&self, ray: &Ray) -> Entered {
        // As few lanes as hold the views: a single view's set-up is one lane.
        match self.n {
            1 => self.enter_lanes::<1>(ray),
            2..=4 => self.enter_lanes::<4>(ray),
            _ => self.enter_lanes::<VIEW_LANES>(ray),
        }
    }

    /// [`ViewLanes::enter`] on the first `N` lanes (`n <= N <= VIEW_LANES`).
    #[inline(always)]
    fn enter_lanes<const N: usize>(&self, ray: &Ray) -> Entered {
        let (org, dir) = (ray.origin(), ray.dir());
        let q: [[f32; N]; 3] = from_fn(|c| from_fn(|k| org[c] - self.apex[c][k]));
        let dw = [dir.x, dir.y, dir.z];
        // dirt_math::view::dot3 of each axis, in its order.
        let ax = &self.axes;
        let o: [[f32; N]; 3] = from_fn(|r| {
            from_fn(|k| q[0][k] * ax[r][0][k] + q[1][k] * ax[r][1][k] + q[2][k] * ax[r][2][k])
        });
        let d: [[f32; N]; 3] = from_fn(|r| {
            from_fn(|k| dw[0] * ax[r][0][k] + dw[1] * ax[r][1][k] + dw[2] * ax[r][2][k])
        });
        let eps: [f32; N] = from_fn(|k| {
            let m = fmax(fmax(o[0][k].abs(), o[1][k].abs()), o[2][k].abs());
            EPS_RAY_REL * (m + 2.0 * self.scale[k])
        });
        // dirt_math::clip::view_frustum: Lo x (s = -tan), Hi x (tan), Lo y, Hi y, Near, Far.
        let neg: [f32; N] = from_fn(|k| -self.tan[k]);
        let tan: [f32; N] = from_fn(|k| self.tan[k]);
        // The sides' `w` terms (w_terms): the depth, or 1 and 0 in an orthographic view.
        let wo: [f32; N] = from_fn(|k| if self.ortho[k] { 1.0 } else { o[2][k] });
        let wd: [f32; N] = from_fn(|k| if self.ortho[k] { 0.0 } else { d[2][k] });
        let parts: [([f32; N], [f32; N]); 6] = [
            (
                from_fn(|k| o[0][k] - neg[k] * wo[k] + eps[k]),
                from_fn(|k| d[0][k] - neg[k] * wd[k]),
            ),
            (
                from_fn(|k| tan[k] * wo[k] - o[0][k] + eps[k]),
                from_fn(|k| tan[k] * wd[k] - d[0][k]),
            ),
            (
                from_fn(|k| o[1][k] - neg[k] * wo[k] + eps[k]),
                from_fn(|k| d[1][k] - neg[k] * wd[k]),
            ),
            (
                from_fn(|k| tan[k] * wo[k] - o[1][k] + eps[k]),
                from_fn(|k| tan[k] * wd[k] - d[1][k]),
            ),
            (from_fn(|k| o[2][k] - self.near[k] + eps[k]), d[2]),
            (
                from_fn(|k| self.far[k] - o[2][k] + eps[k]),
                from_fn(|k| -d[2][k]),
            ),
        ];
        // A loop, not `parts.map`: the map's closure was left out of line.
        let mut cuts = [([0.0; N], [0.0; N]); 6];
        for (cut, (f0, f1)) in cuts.iter_mut().zip(&parts) {
            *cut = cuts_of(*f0, *f1);
        }
        let mut vrs = [ViewRay {
            o: [0.0; 3],
            d: [0.0; 3],
            eps: 0.0,
        }; MAX_VIEWS];
        let mut ivs = [Interval::EMPTY; MAX_VIEWS];
        let mut exits = [None; MAX_VIEWS];
        for f in 0..self.n {
            vrs[f] = ViewRay {
                o: [o[0][f], o[1][f], o[2][f]],
                d: [d[0][f], d[1][f], d[2][f]],
                eps: eps[f],
            };
            if !self.has_content[f] {
                continue;
            }
            // The ray leaves through the last half-space that lowered `t1`
            // (Interval::clip's "moved t1"; one that empties the interval
            // also counts, but then there is no exit).
            let mut iv = Interval {
                t0: ray.tmin,
                t1: ray.tmax,
            };
            let mut exit = None;
            for (k, (lo, hi)) in cuts.iter().enumerate() {
                let c = Cut {
                    lo: lo[f],
                    hi: hi[f],
                };
                if c.hi < iv.t1 {
                    exit = if k < 4 { Some(k) } else { None };
                }
                c.apply(&mut iv);
            }
            if !iv.is_empty() {
                (ivs[f], exits[f]) = (iv, exit);
            }
        }
        (vrs, ivs, exits)
    }
}

/// What one half-space does to a ray interval: `t0` rises to `lo` when
/// `lo > t0`, `t1` falls to `hi` when `hi < t1`. Exactly [`Interval::clip`]
/// with the same `eval`, `slope` and division, split into the part that
/// depends only on the half-space and the ray and the part that applies it.
#[derive(Clone, Copy, Debug)]
struct Cut {
    lo: f32,
    hi: f32,
}

impl Cut {
    const NONE: Cut = Cut {
        lo: f32::NEG_INFINITY,
        hi: f32::INFINITY,
    };

    #[inline]
    fn of(h: &HalfSpace, vr: &ViewRay) -> Cut {
        Cut::from_parts(h.eval(vr.o, vr.eps), h.slope(vr.d))
    }

    /// The cut of a half-space whose value along the ray is `f0 + t·f1`:
    /// [`Interval::clip`]'s branches as selects (`-f0 / f1` is computed even
    /// where it is not used; it raises no trap).
    #[inline]
    fn from_parts(f0: f32, f1: f32) -> Cut {
        let t = -f0 / f1;
        Cut {
            lo: cut_lo(f0, f1, t),
            hi: cut_hi(f0, f1, t),
        }
    }

    /// The cuts `[Lo x, Hi x, Lo y, Hi y]` of the side half-spaces of slope
    /// `sx` in x and `sy` in y.
    #[inline]
    fn sides(vr: &ViewRay, (wo, wd): (f32, f32), sx: f32, sy: f32) -> [Cut; 4] {
        let (o, d) = (vr.o, vr.d);
        let (px, py) = (sx * wo, sy * wo);
        let (qx, qy) = (sx * wd, sy * wd);
        // Lo: p[axis] - s·p[2] + eps, slope d[axis] - s·d[2]; Hi: the differences swapped.
        let (lo, hi) = cut_lanes(
            [o[0], px, o[1], py],
            [px, o[0], py, o[1]],
            [d[0], qx, d[1], qy],
            [qx, d[0], qy, d[1]],
            vr.eps,
        );
        from_fn(|k| Cut {
            lo: lo[k],
            hi: hi[k],
        })
    }

    #[inline]
    fn apply(self, iv: &mut Interval) {
        if self.lo > iv.t0 {
            iv.t0 = self.lo;
        }
        if self.hi < iv.t1 {
            iv.t1 = self.hi;
        }
    }
}

/// `lo` of [`Cut::from_parts`]: `t` when the half-space is entered (`f1 > 0`),
/// `+inf` (empty) when parallel and outside, else no bound.
#[inline(always)]
fn cut_lo(f0: f32, f1: f32, t: f32) -> f32 {
    let parallel = if f0 >= 0.0 {
        f32::NEG_INFINITY
    } else {
        f32::INFINITY
    };
    let other = if f1 < 0.0 {
        f32::NEG_INFINITY
    } else {
        parallel
    };
    if f1 > 0.0 { t } else { other }
}

/// `hi` of [`Cut::from_parts`]: `t` when the half-space is left (`f1 < 0`),
/// `-inf` (empty) when parallel and outside, else no bound.
#[inline(always)]
fn cut_hi(f0: f32, f1: f32, t: f32) -> f32 {
    let parallel = if f0 >= 0.0 {
        f32::INFINITY
    } else {
        f32::NEG_INFINITY
    };
    let other = if f1 > 0.0 { f32::INFINITY } else { parallel };
    if f1 < 0.0 { t } else { other }
}

/// The cuts of `N` half-spaces whose values along the ray are
/// `f0 = (a - b) + eps` and `f1 = c - e` ([`HalfSpace::eval`] and
/// [`HalfSpace::slope`] with their operands in these places), as lanes the
/// compiler can put in one vector: `(lo, hi)`.
#[inline(always)]
fn cut_lanes<const N: usize>(
    a: [f32; N],
    b: [f32; N],
    c: [f32; N],
    e: [f32; N],
    eps: f32,
) -> ([f32; N], [f32; N]) {
    cuts_of(from_fn(|k| a[k] - b[k] + eps), from_fn(|k| c[k] - e[k]))
}

/// The cuts `(lo, hi)` of `N` half-spaces whose values along the ray are
/// `f0 + t·f1`, as lanes ([`Cut::from_parts`] on each).
#[inline(always)]
fn cuts_of<const N: usize>(f0: [f32; N], f1: [f32; N]) -> ([f32; N], [f32; N]) {
    let t: [f32; N] = from_fn(|k| -f0[k] / f1[k]);
    (
        from_fn(|k| cut_lo(f0[k], f1[k], t[k])),
        from_fn(|k| cut_hi(f0[k], f1[k], t[k])),
    )
}

/// The cuts of the Lo sides at the boundaries (slopes) `lo` and the Hi
/// sides at `hi` of `axis` in view `v`, as lanes: `(Lo, Hi)`, each
/// `(lo, hi)`, [`Cut::of`]'s bits ([`ortho_sides`] in an orthographic view;
/// else [`cut_lanes`] with the sides' [`w_terms`]).
#[inline(always)]
fn side_cuts<const N: usize>(
    v: &View,
    vr: &ViewRay,
    axis: usize,
    lo: [f32; N],
    hi: [f32; N],
) -> (CutLanes<N>, CutLanes<N>) {
    let (o, d) = (vr.o[axis], vr.d[axis]);
    if v.ortho {
        return ortho_sides((o, d), lo, hi, vr.eps);
    }
    let (wo, wd) = w_terms(v, vr);
    (
        cut_lanes(
            [o; N],
            lo.map(|s| s * wo),
            [d; N],
            lo.map(|s| s * wd),
            vr.eps,
        ),
        cut_lanes(
            hi.map(|s| s * wo),
            [o; N],
            hi.map(|s| s * wd),
            [d; N],
            vr.eps,
        ),
    )
}

/// The `(lo, hi)` of `N` cuts, as lanes.
type CutLanes<const N: usize> = ([f32; N], [f32; N]);

/// The cuts of an orthographic view's Lo sides at the boundaries `lo` and
/// its Hi sides at `hi`, along an axis where the view ray is `o + t·d`:
/// `(Lo, Hi)`, each `(lo, hi)` as lanes, [`Cut::of`]'s bits. With
/// [`w_terms`] 1 and 0, a side's value `o − s·1 + eps` is `o − s + eps`,
/// and its slope `d − s·0` is `d` (the Hi side's `s·0 − d` is `−d`) but
/// for the sign of a zero, which no cut looks at: one slope for all lanes
/// ([`cuts_of_slope`]).
#[inline(always)]
fn ortho_sides<const N: usize>(
    (o, d): (f32, f32),
    lo: [f32; N],
    hi: [f32; N],
    eps: f32,
) -> (CutLanes<N>, CutLanes<N>) {
    (
        cuts_of_slope(from_fn(|k| o - lo[k] + eps), d),
        cuts_of_slope(from_fn(|k| hi[k] - o + eps), -d),
    )
}

/// [`cuts_of`] of `N` half-spaces whose slopes all equal `f1` wherever they
/// are not zero, decided once for the lanes: where `f1 > 0` each lane's
/// `lo` is its `t` and its `hi` no bound, where `f1 < 0` the other way
/// round, the bits [`cut_lo`] and [`cut_hi`] give lane by lane without
/// their three selects a value. A slope of zero goes to [`cuts_of`].
#[inline(always)]
fn cuts_of_slope<const N: usize>(f0: [f32; N], f1: f32) -> ([f32; N], [f32; N]) {
    if f1 > 0.0 {
        (from_fn(|k| -f0[k] / f1), [f32::INFINITY; N])
    } else if f1 < 0.0 {
        ([f32::NEG_INFINITY; N], from_fn(|k| -f0[k] / f1))
    } else {
        cuts_of(f0, [f1; N])
    }
}

/// [`tile_xy`](dirt_math::dda::tile_xy) at `ta` and at `tb`, as four lanes `[xa, ya, xb, yb]`.
#[inline(always)]
fn tile_xy2(v: &View, vr: &ViewRay, ta: f32, tb: f32) -> [f32; 4] {
    let (o, d) = (vr.o, vr.d);
    let oo = [o[0], o[1], o[0], o[1]];
    let dd = [d[0], d[1], d[0], d[1]];
    let tt = [ta, ta, tb, tb];
    let p: [f32; 4] = from_fn(|k| oo[k] + tt[k] * dd[k]);
    // An orthographic view's `w` is 1: the division by it is left out.
    let s = if v.ortho {
        p
    } else {
        let za = v.w(o[2] + ta * d[2]);
        let zb = v.w(o[2] + tb * d[2]);
        let zz = [za, za, zb, zb];
        from_fn(|k| p[k] / zz[k])
    };
    from_fn(|k| v.tile_coord(s[k]))
}

/// The terms a tile boundary `s` multiplies in a side's value `p[axis] − s·w`
/// and slope `d[axis] − s·w'` ([`HalfSpace::eval`], [`HalfSpace::slope`]):
/// the ray's depth `(o[2], d[2])` in a perspective view; `(1, 0)` in an
/// orthographic one, where `s·1` is `s` and `s·0` a zero, so the value is
/// the orthographic side's bit for bit and the slope too up to the sign of
/// a zero, which no cut looks at ([`cut_lo`], [`cut_hi`] test `f1 > 0` and
/// `f1 < 0` only).
#[inline(always)]
fn w_terms(v: &View, vr: &ViewRay) -> (f32, f32) {
    if v.ortho {
        (1.0, 0.0)
    } else {
        (vr.o[2], vr.d[2])
    }
}

/// `dirt_math::dda::index_range`, inlined.
#[inline]
fn index_range(a: f32, b: f32, d: f32, tiles: u32) -> Option<(u32, u32)> {
    let lo = fmin(a, b) - d;
    let hi = fmax(a, b) + d;
    if !(hi >= 0.0 && lo < tiles as f32) {
        return None;
    }
    let last = tiles - 1;
    Some((floor_index(lo, last), floor_index(hi, last)))
}

/// The box of the ray's segment over an interval, rounded outward by its
/// `eps`: in x and y from its ends ([`ray_point`]), in depth `depth`, the
/// span [`depth_span`] gave for the same interval.
#[inline]
fn span_box(vr: &ViewRay, iv: Interval, (lo, hi): (f32, f32)) -> ViewBox {
    let (a, b) = (ray_point(vr, iv.t0), ray_point(vr, iv.t1));
    let side = |c: usize| (fmin(a[c], b[c]) - vr.eps, fmax(a[c], b[c]) + vr.eps);
    let (x, y) = (side(0), side(1));
    ViewBox::new([x.0, y.0, lo], [x.1, y.1, hi])
}

/// The ray's depth span over an interval, rounded outward by its `eps`.
#[inline]
fn depth_span(vr: &ViewRay, iv: Interval) -> (f32, f32) {
    let za = ray_depth(vr, iv.t0);
    let zb = ray_depth(vr, iv.t1);
    (fmin(za, zb) - vr.eps, fmax(za, zb) + vr.eps)
}

/// The tiles a walk of a ray's interval in a view can reach, with a margin
/// of one tile, and the ray's depth span over the interval ([`reach`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach {
    i: (u32, u32),
    j: (u32, u32),
    depth: (f32, f32),
}

impl Reach {
    /// The lowest Hi-Z level (below `levels`) at which the tiles fit in 2 × 2 cells.
    #[inline]
    fn level(&self, levels: u32) -> u32 {
        let mut level = 0;
        while level + 1 < levels
            && ((self.i.1 >> level) - (self.i.0 >> level) > 1
                || (self.j.1 >> level) - (self.j.0 >> level) > 1)
        {
            level += 1;
        }
        level
    }
}

/// The tiles a walk of `iv` in `v` can reach: `dirt_math::dda::index_range`
/// of the ray's tile coordinates `[ax, ay, bx, by]` at `iv`'s ends
/// ([`tile_xy2`]) dilated by `delta`, grown by one tile; `None` where that
/// is not shown to hold them all (then walk from the top).
///
/// Why it holds them: a tile the walk enters is one whose (dilated) frustum
/// the ray crosses at some `t` in `iv`, where its tile coordinate is within
/// the dilation of the tile. That coordinate, `(o + t·d) / z(t)`, is
/// monotone in `t` where `z(t)` is positive and not clamped at `near / 2`
/// (checked on the ends: the depth is the same expression, monotone in `t`
/// in floats too), so it lies between its values at the ends, up to
/// rounding far below the margin. Every tile's depth span is inside the
/// span over `iv` likewise.
#[inline]
fn reach(
    v: &View,
    vr: &ViewRay,
    iv: Interval,
    [ax, ay, bx, by]: [f32; 4],
    delta: f32,
) -> Option<Reach> {
    let (za, zb) = (ray_depth(vr, iv.t0), ray_depth(vr, iv.t1));
    // In an orthographic view the coordinate is `o + t·d`, monotone everywhere.
    if !(v.ortho || fmin(za, zb) > v.near * 0.5) {
        return None;
    }
    let last = v.tiles - 1;
    let grow = |(lo, hi): (u32, u32)| (lo.saturating_sub(1), (hi + 1).min(last));
    Some(Reach {
        i: grow(index_range(ax, bx, delta, v.tiles)?),
        j: grow(index_range(ay, by, delta, v.tiles)?),
        depth: (fmin(za, zb) - vr.eps, fmax(za, zb) + vr.eps),
    })
}

/// A single perspective view's apex, for rays that start there (a camera's
/// rays, with the view placed at the camera): such a ray's tile coordinate
/// does not move along it, so where it looks is known from its direction
/// alone, before its set-up ([`ViewLanes::enter`]) and walk.
struct Apex<'a> {
    /// The view.
    view: &'a View,
    /// The apex's bits: a ray starts there when its origin has them.
    at: [u32; 3],
    /// `1 / step`.
    per_step: f32,
    /// Half the width, in tiles, of the range around the direction's tile
    /// coordinate that holds every tile a walk of such a ray can reach.
    margin: f32,
    /// A bit a tile (rows of [`Apex::row_words`] words), set where the
    /// tile's depth bounds are not empty, when [`Apex::mark`] made them.
    content: Vec<u64>,
    /// The view holds every triangle ([`Ads::sees_all`]): a ray from the
    /// apex is traced by [`RayState::direct`].
    direct: bool,
}

/// What [`Apex::look`] found for a ray: `None` where it did not look (the
/// ray is left to its walk), `Some(None)` for a miss, else the tiles.
pub(crate) type Look = Option<Option<Reach>>;

impl Scene<'_> {
    /// [`Apex::look`] for each of `rays` (at most [`LOOKS`]), into `looks`;
    /// all `None` without an apex. A chunk of rays is looked at first
    /// (`trace::trace_chunks`), [`LOOK_LANES`] at a time where the apex has
    /// its tiles' content marked ([`Apex::look_lanes`]), and each ray then
    /// goes on from its look ([`trace_looked`]): a miss does not enter the
    /// trace at all, and [`trace_ray`] would return [`Hit::MISS`] for it too
    /// (an invalid ray is a miss there whatever the apex shows).
    #[inline]
    pub(crate) fn looks_at_apex(&self, rays: &[Ray], looks: &mut [Look; LOOKS]) {
        let Some(apex) = &self.apex else {
            looks.fill(None);
            return;
        };
        let mut done = 0;
        if !apex.content.is_empty() {
            for (group, out) in rays
                .chunks_exact(LOOK_LANES)
                .zip(looks.chunks_exact_mut(LOOK_LANES))
            {
                let group: &[Ray; LOOK_LANES] = group.try_into().expect("a full group");
                let out: &mut [Look; LOOK_LANES] = out.try_into().expect("a full group");
                apex.look_lanes(group, out);
                done += LOOK_LANES;
            }
        }
        for (look, ray) in looks.iter_mut().zip(rays).skip(done) {
            *look = apex.look(self, ray);
        }
    }
}

/// Most rays [`Scene::looks_at_apex`] takes at once.
pub(crate) const LOOKS: usize = 32;

/// Rays [`Apex::look_lanes`] looks at together.
const LOOK_LANES: usize = 8;

impl<'a> Apex<'a> {
    /// For a set of one perspective view with content.
    fn of(views: &'a [View], content_near: f32, direct: bool) -> Option<Apex<'a>> {
        let [v] = views else { return None };
        if v.ortho || !v.has_content || v.tiles == 0 {
            return None;
        }
        // A walk's dilation (`dilation`): the ray's `eps` (that of every
        // ray from the apex) over its smallest depth less `eps`, plus
        // 1/256. The ray enters the near plane dilated by `eps`, and its
        // interval is cut to the content's depth less `2·eps`
        // ([`Scene::to_content`]), so that depth is the larger of
        // `near − 2·eps` and `content_near − 3·eps`, up to rounding (a 1/1024
        // share of it covers that); 1/64 of a tile more covers the rounding
        // of the coordinate along the ray.
        let eps = v.ray(&Ray::new(v.apex, v.forward, 0.0, f32::INFINITY)).eps;
        if !(eps < v.near * 0.25 && v.near >= f32::MIN_POSITIVE * 16_777_216.0) {
            return None;
        }
        let w = fmax(v.near - 2.0 * eps, content_near - 3.0 * eps) * (1.0 - 1.0 / 1024.0);
        let margin = eps / w / v.step + 1.0 / 256.0 + 1.0 / 64.0;
        margin.is_finite().then(|| Apex {
            view: v,
            at: v.apex.to_array().map(f32::to_bits),
            per_step: 1.0 / v.step,
            margin,
            content: Vec::new(),
            direct,
        })
    }

    /// Words a row of [`Apex::content`] takes.
    fn row_words(&self) -> usize {
        (self.view.tiles as usize).div_ceil(64)
    }

    /// Sets [`Apex::content`] from the view's depth bounds (Hi-Z level 0).
    fn mark(&mut self, bounds: &[[u32; 2]]) {
        let (tiles, words) = (self.view.tiles as usize, self.row_words());
        let mut content = vec![0u64; tiles * words];
        for (j, row) in bounds.chunks(tiles).enumerate() {
            for (i, &[zmin, zmax]) in row.iter().enumerate() {
                // Empty bounds are [+inf, -inf]: reversed.
                let full = ordered_to_f32(zmin) <= ordered_to_f32(zmax);
                content[j * words + i / 64] |= u64::from(full) << (i % 64);
            }
        }
        self.content = content;
    }

    /// For `ray`, a valid ray that starts at the apex and points ahead:
    /// `Some(None)` where every tile its walk could reach is empty, so that
    /// it hits nothing, else `Some(tiles)`, a range of tiles that holds
    /// every tile its walk could reach; `None` for any other ray, which is
    /// left to its walk.
    ///
    /// Such a ray's view-space origin is zero, and its tile coordinate at
    /// any `t` is `((t·d₀) / (t·d₂) + tan) / step`: `(d₀ / d₂ + tan) / step`
    /// up to a few ulps. The walk reaches tiles within its dilation of that
    /// coordinate at the ray's ends ([`reach`]; its depth there is at
    /// least the larger of `near − eps`, the ray having entered the dilated
    /// near plane, and the content's front less `2·eps`, where
    /// [`Scene::to_content`] cut it), so within [`Apex::margin`] of the
    /// direction's coordinate; and an empty tile (or cell) has bounds that
    /// no depth meets. A ray with content near walks without trying
    /// [`RayState::meets_nothing`], as its depth span runs from the
    /// content's front on.
    #[inline]
    fn look(&self, sc: &Scene<'_>, ray: &Ray) -> Option<Option<Reach>> {
        if ray.origin.map(f32::to_bits) != self.at {
            return None;
        }
        let (x, y, m) = self.coords(ray)?;
        let tiles = self.view.tiles as f32;
        if !(x + m >= 0.0 && y + m >= 0.0 && x - m < tiles && y - m < tiles) {
            // Beside the view (or not finite: left to the walk).
            return (x.is_finite() && y.is_finite()).then_some(None);
        }
        let last = self.view.tiles - 1;
        let r = Reach {
            i: (floor_index(x - m, last), floor_index(x + m, last)),
            j: (floor_index(y - m, last), floor_index(y + m, last)),
            // Any finite depth: only empty cells are met by none.
            depth: (f32::MIN, f32::MAX),
        };
        if self.content.is_empty() {
            return Some((!sc.nothing_in(self.view, &r)).then_some(r));
        }
        Some(self.any_content(r.i, r.j).then_some(r))
    }

    /// For a ray from the apex that points ahead, its direction's tile
    /// coordinates `(x, y)` and the margin `m` around them that holds the
    /// tile coordinate of every point of the ray that its walk could reach
    /// ([`Apex::look`]).
    #[inline(always)]
    fn coords(&self, ray: &Ray) -> Option<(f32, f32, f32)> {
        let [dx, dy, dz] = self.view.dir_to_view(ray.dir());
        if !(dz > 0.0) {
            return None;
        }
        // One division: the margin covers a few more roundings.
        let r = 1.0 / dz;
        let x = (dx * r + self.view.tan) * self.per_step;
        let y = (dy * r + self.view.tan) * self.per_step;
        // Wider for a coordinate so large that its ulps approach a tile.
        let m = self.margin + fmax(x.abs(), y.abs()) * (1.0 / 65536.0);
        Some((x, y, m))
    }

    /// [`Apex::look`] for each of `rays`, where the tiles' content is
    /// marked ([`Apex::mark`]): its direction's view-space coordinates and
    /// tile coordinates as lanes, each lane the same operations on the same
    /// operands as `look` (so the same bits), then each lane's decision as
    /// there. A loop over `look` waited on each ray's chain of products and
    /// its division in turn (the deforming grid's camera rays that miss:
    /// about 45 ns each, 36 ns here, one thread).
    #[inline(always)]
    fn look_lanes(&self, rays: &[Ray; LOOK_LANES], looks: &mut [Look; LOOK_LANES]) {
        type L = [f32; LOOK_LANES];
        let v = self.view;
        let at: [bool; LOOK_LANES] = from_fn(|k| rays[k].origin.map(f32::to_bits) == self.at);
        let d = |c: usize| -> L { from_fn(|k| rays[k].dir[c]) };
        let (d0, d1, d2) = (d(0), d(1), d(2));
        // View::dir_to_view: dot3 with right, up, forward.
        let dot =
            |b: dirt_math::Vec3| -> L { from_fn(|k| d0[k] * b.x + d1[k] * b.y + d2[k] * b.z) };
        let (dx, dy, dz) = (dot(v.right), dot(v.up), dot(v.forward));
        let r: L = from_fn(|k| 1.0 / dz[k]);
        let x: L = from_fn(|k| (dx[k] * r[k] + v.tan) * self.per_step);
        let y: L = from_fn(|k| (dy[k] * r[k] + v.tan) * self.per_step);
        let m: L = from_fn(|k| self.margin + fmax(x[k].abs(), y[k].abs()) * (1.0 / 65536.0));
        let tiles = v.tiles as f32;
        let ahead: [bool; LOOK_LANES] = from_fn(|k| at[k] && dz[k] > 0.0);
        let inside: [bool; LOOK_LANES] = from_fn(|k| {
            x[k] + m[k] >= 0.0 && y[k] + m[k] >= 0.0 && x[k] - m[k] < tiles && y[k] - m[k] < tiles
        });
        let finite: [bool; LOOK_LANES] = from_fn(|k| x[k].is_finite() && y[k].is_finite());
        let last = v.tiles - 1;
        // `x + (-1.0 · m)` is `x − m`, bit for bit.
        let index = |c: L, sign: f32| -> [u32; LOOK_LANES] {
            from_fn(|k| floor_index(c[k] + sign * m[k], last))
        };
        let (i0, i1, j0, j1) = (index(x, -1.0), index(x, 1.0), index(y, -1.0), index(y, 1.0));
        // A loop, not `from_fn`: that closure was left out of line.
        for k in 0..LOOK_LANES {
            looks[k] = if !ahead[k] {
                None
            } else if !inside[k] {
                finite[k].then_some(None)
            } else {
                let r = Reach {
                    i: (i0[k], i1[k]),
                    j: (j0[k], j1[k]),
                    depth: (f32::MIN, f32::MAX),
                };
                Some(self.any_content(r.i, r.j).then_some(r))
            };
        }
    }

    /// Whether a tile of the range `i × j` (inclusive) holds content, by
    /// [`Apex::content`].
    #[inline(always)]
    fn any_content(&self, i: (u32, u32), j: (u32, u32)) -> bool {
        let words = self.row_words();
        for j in j.0..=j.1 {
            let row = &self.content[j as usize * words..];
            for i in i.0..=i.1 {
                if row[i as usize / 64] >> (i % 64) & 1 != 0 {
                    return true;
                }
            }
        }
        false
    }
}

/// Bands of a walk short enough for [`RayState::meets_nothing`] to be tried.
const SHORT_WALK: u32 = 4;

/// Bands of the linear walk prepared together.
const BAND_LANES: usize = 4;

/// Fewest rays worth putting in a coherent order first.
pub(crate) const ORDER_MIN_RAYS: usize = 4096;

/// Spreads the low 10 bits of `x` to every third bit (for a 3D Morton code).
#[inline]
const fn spread3(x: u32) -> u32 {
    let x = x & 0x3ff;
    let x = (x | x << 16) & 0x0300_00ff;
    let x = (x | x << 8) & 0x0300_f00f;
    let x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

/// Batches of at least this many rays find their order's bounds and keys
/// on all threads; below it a thread does it alone (a parallel pass over a
/// few thousand rays cost more in its start and join than it saved).
const ORDER_PAR_RAYS: usize = 1 << 16;

/// Fewest and most bits an axis of [`coherent_order`]'s cells.
const ORDER_BITS: (u32, u32) = (2, 6);

/// [`spread3`] of every cell coordinate of [`coherent_order`], looked up.
const SPREAD: [u32; 1 << ORDER_BITS.1] = {
    let mut t = [0; 1 << ORDER_BITS.1];
    let mut x = 0;
    while x < t.len() {
        t[x] = spread3(x as u32);
        x += 1;
    }
    t
};

/// The rays' indices in an order that keeps neighbours close in the
/// structure: by the cube face their direction points to (axis and sign of
/// its largest component), then by the Morton code of the cell of their
/// origin, then by index. The cells divide the origins' bounds into `2^m`
/// along each axis, `m` the largest (within [`ORDER_BITS`]) with `6·8^m` at
/// most the number of rays: up to 12 million rays, one to eight rays a
/// (face, cell) key on average.
/// The order is a counting sort of those keys, two passes over the rays.
/// A comparison sort of finer keys (9 bits an axis) cost about 25 ns a ray,
/// this about 10 (the bunny's batches of 5,000 rays, 2 threads: 125 → 52
/// µs of a trace of about 1.2 ms). `None` for batches too small to be
/// worth it, and for rays that all start at one point (input order). The
/// order changes only the speed: each ray is traced on its own.
pub(crate) fn coherent_order(rays: &[Ray]) -> Option<Vec<u32>> {
    use rayon::prelude::*;
    let n = rays.len();
    if n < ORDER_MIN_RAYS || n > u32::MAX as usize {
        return None;
    }
    let parallel = n >= ORDER_PAR_RAYS;
    let empty = || ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    // `min` and `max` pass over NaN; an infinite origin makes the bounds
    // infinite, and then every cell 0 (the order is by face alone).
    let grow = |(lo, hi): ([f32; 3], [f32; 3]), r: &Ray| {
        (
            from_fn(|a| lo[a].min(r.origin[a])),
            from_fn(|a| hi[a].max(r.origin[a])),
        )
    };
    let (lo, hi) = if parallel {
        rays.par_iter()
            .fold(empty, grow)
            .reduce(empty, |(a, b), (c, d)| {
                (from_fn(|k| a[k].min(c[k])), from_fn(|k| b[k].max(d[k])))
            })
    } else {
        rays.iter().fold(empty(), grow)
    };
    // Rays that all start at one point (a camera's) differ only in their
    // direction face: in input order they are as coherent as a sort makes
    // them, and the sort, gather and scatter would cost more than they save.
    if lo == hi {
        return None;
    }
    // 6·8^m <= n: floor(log2(n / 6) / 3) bits an axis.
    let m = ((n / 6).max(1).ilog2() / 3).clamp(ORDER_BITS.0, ORDER_BITS.1);
    let top = ((1u32 << m) - 1) as f32;
    // NaN (empty or flat bounds, non-finite origins) goes to cell 0.
    let scale: [f32; 3] = from_fn(|a| top / (hi[a] - lo[a]));
    let cell = |r: &Ray, a: usize| ((r.origin[a] - lo[a]) * scale[a]).clamp(0.0, top) as u32;
    let key = |r: &Ray| {
        // The face without branches and the spread looked up: the keys of
        // 5,000 rays took about 37 µs so, 50 with branches and `spread3`.
        let d = r.dir.map(f32::abs);
        let x = u32::from((d[0] >= d[1]) & (d[0] >= d[2]));
        let y = (1 - x) & u32::from(d[1] >= d[2]);
        let z = 1 - x - y;
        let neg = r.dir.map(|c| u32::from(c < 0.0));
        let face = 2 * y + 4 * z + (x & neg[0]) + (y & neg[1]) + (z & neg[2]);
        let spread = |c: u32| SPREAD[c as usize];
        let morton = spread(cell(r, 0)) | spread(cell(r, 1)) << 1 | spread(cell(r, 2)) << 2;
        face << (3 * m) | morton
    };
    let keys: Vec<u32> = if parallel {
        rays.par_iter().map(key).collect()
    } else {
        rays.iter().map(key).collect()
    };
    // Counting sort: each key's start, then the indices in input order.
    let mut start = vec![0u32; (6 << (3 * m)) + 1];
    for &k in &keys {
        start[k as usize + 1] += 1;
    }
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    let mut order = vec![0u32; n];
    for (i, &k) in keys.iter().enumerate() {
        let at = &mut start[k as usize];
        order[*at as usize] = i as u32;
        *at += 1;
    }
    Some(order)
}

/// Entries of the per-thread mailbox of tested triangle ids (a power of two).
pub(crate) const MAILBOX: usize = 256;

/// A cell of the Hi-Z walk waiting on the stack: level, `i`, `j`, and the
/// ray's interval in it.
type Waiting = (u32, u32, u32, Interval);

/// Per-thread memory of the walk, reused from ray to ray: the Hi-Z stack
/// (its length is kept apart, so pushing a child is a store and an add), and
/// the side cuts of the cells of each level: `x[level][i & 1]` holds the
/// (Lo, Hi) x cuts of cell `i` of that level, `y` likewise by `j`. They are
/// written when the parent is expanded; depth first, every cell of a level
/// on the stack has the same parent, the one expanded last at the level above.
#[derive(Debug)]
pub(crate) struct Scratch {
    stack: Vec<Waiting>,
    x: [[(Cut, Cut); 2]; MAX_LEVELS],
    y: [[(Cut, Cut); 2]; MAX_LEVELS],
    /// `ray << 32 | id` of the triangle last tested at slot `id % MAILBOX`.
    mailbox: Vec<u64>,
    /// The ray's tag; the mailbox is cleared before it would repeat.
    ray: u32,
}

impl Scratch {
    pub(crate) fn new() -> Self {
        Scratch {
            stack: vec![(0, 0, 0, Interval::EMPTY); STACK],
            x: [[(Cut::NONE, Cut::NONE); 2]; MAX_LEVELS],
            y: [[(Cut::NONE, Cut::NONE); 2]; MAX_LEVELS],
            mailbox: vec![u64::MAX; MAILBOX],
            ray: 0,
        }
    }

    /// A new ray: its tag, never one an entry holds.
    fn next_ray(&mut self) {
        if self.ray >= u32::MAX - 1 {
            self.mailbox.fill(u64::MAX);
            self.ray = 0;
        } else {
            self.ray += 1;
        }
    }
}

/// One ray in flight.
struct RayState<'s, 'a, const STATS: bool> {
    sc: &'s Scene<'a>,
    scratch: &'s mut Scratch,
    ray: &'s Ray,
    sh: RayShear,
    best: Hit,
    stats: RayStats,
    /// [`Apex::look`] found content near the ray.
    looked: bool,
}

/// One ray, the same hit and statistics as [`crate::trace::trace_ray_plain`].
#[inline]
pub(crate) fn trace_ray<const STATS: bool>(
    sc: &Scene<'_>,
    scratch: &mut Scratch,
    ray: &Ray,
    traversal: Traversal,
) -> (Hit, RayStats) {
    if ray.validate().is_err() {
        return (Hit::MISS, RayStats::default());
    }
    let look = match &sc.apex {
        Some(apex) if !STATS => apex.look(sc, ray),
        _ => None,
    };
    trace_looked::<STATS>(sc, scratch, ray, traversal, look)
}

/// [`trace_ray`] of a valid ray, from what [`Apex::look`] found for it
/// (`None` where it did not look, always with statistics).
#[inline]
pub(crate) fn trace_looked<const STATS: bool>(
    sc: &Scene<'_>,
    scratch: &mut Scratch,
    ray: &Ray,
    traversal: Traversal,
    look: Look,
) -> (Hit, RayStats) {
    // Whether the ray is one from the apex with content near: then its short
    // walk is not tried for meeting nothing, which only a range ending
    // before that content would.
    let mut looked = false;
    if let Some(apex) = &sc.apex {
        match look {
            Some(None) => return (Hit::MISS, RayStats::default()),
            Some(Some(tiles)) if apex.direct => {
                scratch.next_ray();
                let mut st = RayState::<STATS>::new(sc, scratch, ray, true);
                st.direct(apex.view, &tiles);
                return (st.best, st.stats);
            }
            Some(Some(_)) => looked = true,
            None => {}
        }
    }
    let n = sc.views.len();
    let (vrs, mut ivs, exits) = sc.lanes.enter(ray);
    if !STATS {
        for f in 0..n {
            if !ivs[f].is_empty() {
                sc.to_content(f, &vrs[f], &mut ivs[f]);
            }
        }
        scratch.next_ray();
    }
    let mut st = RayState::<STATS>::new(sc, scratch, ray, looked);
    let mut visited = 0u32;
    let mut current = next_view(&ivs[..n], visited, None);
    while let Some(f) = current {
        visited |= 1 << f;
        if ivs[f].t0 <= st.best.t {
            if STATS {
                st.stats.views += 1;
            }
            match traversal {
                Traversal::Linear => st.linear(f, &vrs[f], ivs[f]),
                Traversal::HiZ => st.hiz(f, &vrs[f], ivs[f]),
            }
        }
        let adjacency = &sc.ads.views.adjacency;
        let across = exits[f].and_then(|e| adjacency.get(f).map(|a| a[e] as usize));
        current = next_view(&ivs[..n], visited, across);
    }
    (st.best, st.stats)
}

impl<'s, 'a, const STATS: bool> RayState<'s, 'a, STATS> {
    #[inline(always)]
    fn new(sc: &'s Scene<'a>, scratch: &'s mut Scratch, ray: &'s Ray, looked: bool) -> Self {
        RayState {
            sc,
            scratch,
            ray,
            sh: RayShear::new(ray),
            best: Hit::MISS,
            stats: RayStats::default(),
            looked,
        }
    }

    /// `dirt_math::dda::walk_tiles` with the plain stage's visitor, inlined.
    /// Bands and tiles are clipped with [`Cut`]s; a tile's pair of minor-axis
    /// cuts is kept for the next band, whose first tile is usually the last
    /// tile of this one. Without statistics, where the plain stage is exact
    /// ([`Scene::exact`]), a band's tiles are searched over the band's
    /// interval instead, without their cuts (module docs).
    fn linear(&mut self, f: usize, vr: &ViewRay, iv: Interval) {
        let sc = self.sc;
        let v = &sc.views[f];
        let slope = &sc.slopes[f][..];
        if iv.is_empty() || v.tiles == 0 {
            return;
        }
        let [ax, ay, bx, by] = tile_xy2(v, vr, iv.t0, iv.t1);
        let (a, b) = ([ax, ay], [bx, by]);
        let delta = dilation(v, vr, &iv);
        let major = if (b[0] - a[0]).abs() >= (b[1] - a[1]).abs() {
            0
        } else {
            1
        };
        let minor = 1 - major;
        let Some((k0, k1)) = index_range(a[major], b[major], delta, v.tiles) else {
            return;
        };
        // Tried on short walks only: a long one nearly always meets a cell
        // with something in it, and then the test is time lost.
        if !STATS
            && !self.looked
            && k1 - k0 < SHORT_WALK
            && reach(v, vr, iv, [ax, ay, bx, by], delta).is_some_and(|r| self.meets_nothing(v, &r))
        {
            return;
        }
        let forward = b[major] >= a[major];
        let minor_forward = b[minor] >= a[minor];
        let (o, d) = (vr.o, vr.d);
        // The cuts of Lo at boundary k and Hi at boundary k + 1 of an axis.
        let cuts = |axis: usize, k: u32| {
            let [s0, s1] = [slope[k as usize], slope[k as usize + 1]];
            let ((l_lo, l_hi), (h_lo, h_hi)) = side_cuts(v, vr, axis, [s0], [s1]);
            let lo = Cut {
                lo: l_lo[0],
                hi: l_hi[0],
            };
            let hi = Cut {
                lo: h_lo[0],
                hi: h_hi[0],
            };
            (lo, hi)
        };
        // Bands are prepared four at a time: their cuts, intervals and the
        // minor tile coordinates of their ends as lanes, none of which
        // depends on the best hit; then each is walked as the plain stage
        // walks it, termination test first.
        let bands = k1 - k0 + 1;
        let mut kept = (u32::MAX, Cut::NONE, Cut::NONE);
        let mut n = 0;
        while n < bands {
            let count = (bands - n).min(BAND_LANES as u32);
            // Lanes past the last band repeat it; they are not walked.
            let ks: [u32; BAND_LANES] = from_fn(|q| {
                let n = n + (q as u32).min(count - 1);
                if forward { k0 + n } else { k1 - n }
            });
            let s0: [f32; BAND_LANES] = from_fn(|q| slope[ks[q] as usize]);
            let s1: [f32; BAND_LANES] = from_fn(|q| slope[ks[q] as usize + 1]);
            let ((l_lo, l_hi), (h_lo, h_hi)) = side_cuts(v, vr, major, s0, s1);
            let mut t0 = [iv.t0; BAND_LANES];
            let mut t1 = [iv.t1; BAND_LANES];
            for (lo, hi) in [(l_lo, l_hi), (h_lo, h_hi)] {
                t0 = from_fn(|q| if lo[q] > t0[q] { lo[q] } else { t0[q] });
                t1 = from_fn(|q| if hi[q] < t1[q] { hi[q] } else { t1[q] });
            }
            // The minor coordinate of `tile_xy` at both ends of each band,
            // each step over the lanes at once (one vector division, not
            // four); an orthographic view's `w` is 1, where the division by
            // it is left out (`x / 1` is `x`).
            let minor_at = |t: [f32; BAND_LANES]| -> [f32; BAND_LANES] {
                let p: [f32; BAND_LANES] = from_fn(|q| o[minor] + t[q] * d[minor]);
                let s = if v.ortho {
                    p
                } else {
                    let z: [f32; BAND_LANES] = from_fn(|q| v.w(o[2] + t[q] * d[2]));
                    from_fn(|q| p[q] / z[q])
                };
                from_fn(|q| v.tile_coord(s[q]))
            };
            let (pm, qm) = (minor_at(t0), minor_at(t1));
            for q in 0..count as usize {
                let k = ks[q];
                let band = Interval {
                    t0: t0[q],
                    t1: t1[q],
                };
                if band.is_empty() {
                    continue;
                }
                if band.t0 > self.best.t {
                    return;
                }
                let Some((m0, m1)) = index_range(pm[q], qm[q], delta, v.tiles) else {
                    continue;
                };
                if !STATS && sc.exact {
                    // Each tile searched over the band's interval, which
                    // holds the tile's own: the same closest hit, without
                    // the tiles' cuts (module docs).
                    for e in 0..=(m1 - m0) {
                        let m = if minor_forward { m0 + e } else { m1 - e };
                        let (i, j) = if major == 0 { (k, m) } else { (m, k) };
                        self.visit_tile(v, vr, i, j, band);
                    }
                    continue;
                }
                for e in 0..=(m1 - m0) {
                    let m = if minor_forward { m0 + e } else { m1 - e };
                    if kept.0 != m {
                        let (lo, hi) = cuts(minor, m);
                        kept = (m, lo, hi);
                    }
                    let mut span = band;
                    kept.1.apply(&mut span);
                    kept.2.apply(&mut span);
                    if span.is_empty() {
                        continue;
                    }
                    let (i, j) = if major == 0 { (k, m) } else { (m, k) };
                    self.visit_tile(v, vr, i, j, span);
                }
            }
            n += count;
        }
    }

    /// Whether no tile of `r` has depth bounds that its depth span meets, so
    /// that a walk inside `r` would test no triangle: then the walk can be
    /// left out, which changes no hit (only the statistics, which is why it
    /// is not done when they are counted). Decided on the at most four cells
    /// of [`Reach::level`]: a cell's bounds hold its tiles' bounds. Camera
    /// rays from a view's apex that miss everything mostly end here, after
    /// their set-up.
    #[inline]
    fn meets_nothing(&self, v: &View, r: &Reach) -> bool {
        self.sc.nothing_in(v, r)
    }

    /// The plain stage's Hi-Z walk: depth-first, front to back. A cell is
    /// skipped when its interval is empty, when the ray's depth span there
    /// misses the cell's `[zmin, zmax]`, or when it is entered after the best
    /// hit. The first two do not depend on the best hit, so they are decided
    /// for all four children when their parent is expanded, and only the
    /// children that pass are pushed, with their interval; the third is
    /// decided when a cell is popped, as in the plain stage. The same cells
    /// are visited in the same order. Cell intervals come from cuts computed
    /// once per expansion (module docs).
    fn hiz(&mut self, f: usize, vr: &ViewRay, iv: Interval) {
        let sc = self.sc;
        let v = &sc.views[f];
        let slope = &sc.slopes[f][..];
        let tiles = v.tiles;
        let slot = v.slot as usize;
        // dirt_math::dda::projected_direction
        let [ax, ay, bx, by] = tile_xy2(v, vr, iv.t0, iv.t1);
        let (dx, dy) = (bx - ax, by - ay);
        let order = child_order(dx, dy);
        let lo = |axis: usize, k: u32| Cut::of(&v.lo(axis, slope[k as usize]), vr);
        let hi = |axis: usize, k: u32| Cut::of(&v.hi(axis, slope[k as usize]), vr);
        let wt = w_terms(v, vr);
        // The interval of a cell from its four cuts (in `block_frustum`'s
        // order), if it is not empty and its depth span meets `[zmin, zmax]`.
        let enter = |cuts: [Cut; 4], [zmin, zmax]: [u32; 2]| -> Option<Interval> {
            let mut civ = iv;
            for c in cuts {
                c.apply(&mut civ);
            }
            let (zmin, zmax) = (ordered_to_f32(zmin), ordered_to_f32(zmax));
            let (dlo, dhi) = depth_span(vr, civ);
            (!civ.is_empty() && dhi >= zmin && dlo <= zmax).then_some(civ)
        };
        // Cells waiting, each with its interval: `stack[..len]`.
        let mut len = 0;
        let top = sc.levels - 1;
        // Without statistics, the walk starts at the (at most 2 × 2) cells
        // of the lowest level that hold every tile it can reach ([`reach`]),
        // not at the root: the cells it would have found on the way down
        // are still visited (a cell's interval and depth test do not depend
        // on its parent), so the same tiles are searched, and perhaps a few
        // more that the ancestors' tests would have dropped. More candidates
        // change no hit; the statistics would differ, so with them the walk
        // starts at the root, as the plain stage does.
        let reached = if STATS {
            None
        } else {
            reach(v, vr, iv, [ax, ay, bx, by], dilation(v, vr, &iv))
        };
        // The root, cell (0, 0) of the top level, covers every tile.
        let (level, ci, cj) = match reached {
            Some(r) => {
                let level = r.level(sc.levels);
                let cells = |(lo, hi): (u32, u32)| (lo >> level, hi >> level);
                (level, cells(r.i), cells(r.j))
            }
            None => (top, (0, 0), (0, 0)),
        };
        let l = level as usize;
        let w = sc.widths[l];
        // A cell's sides: its first tile's lower boundary, the next cell's
        // (clamped to the grid: the root's is [0, min(2^top, tiles))).
        for c in [ci.0, ci.1] {
            self.scratch.x[l][(c & 1) as usize] =
                (lo(0, c << level), hi(0, ((c + 1) << level).min(tiles)));
        }
        for c in [cj.0, cj.1] {
            self.scratch.y[l][(c & 1) as usize] =
                (lo(1, c << level), hi(1, ((c + 1) << level).min(tiles)));
        }
        for &(di, dj) in order.iter().rev() {
            let (i, j) = (ci.0 + di, cj.0 + dj);
            if i > ci.1 || j > cj.1 {
                continue;
            }
            let (xl, xh) = self.scratch.x[l][(i & 1) as usize];
            let (yl, yh) = self.scratch.y[l][(j & 1) as usize];
            let cell = sc.ads.hiz[l][slot * (w * w) as usize + (j * w + i) as usize];
            if let Some(civ) = enter([xl, xh, yl, yh], cell) {
                self.scratch.stack[len] = (level, i, j, civ);
                len += 1;
            }
        }
        while len > 0 {
            len -= 1;
            let (level, i, j, civ) = self.scratch.stack[len];
            if civ.t0 > self.best.t {
                continue;
            }
            if level == 0 {
                self.visit_tile(v, vr, i, j, civ);
                continue;
            }
            // Children: tiles [i0, mid) and [mid, i1) in x, same in y; the
            // mid boundary clamped to the grid, where its cut is the parent's.
            let c = level - 1;
            let cw = sc.widths[c as usize];
            let mx = ((2 * i + 1) << c).min(tiles);
            let my = ((2 * j + 1) << c).min(tiles);
            let [xlm, xhm, ylm, yhm] = Cut::sides(vr, wt, slope[mx as usize], slope[my as usize]);
            let (xl, xh) = self.scratch.x[level as usize][(i & 1) as usize];
            let (yl, yh) = self.scratch.y[level as usize][(j & 1) as usize];
            self.scratch.x[c as usize] = [(xl, xhm), (xlm, xh)];
            self.scratch.y[c as usize] = [(yl, yhm), (ylm, yh)];
            // Lane k: child (di, dj) = (k & 1, k >> 1); its cuts in block_frustum's order.
            let cuts = [
                [xl, xhm, yl, yhm],
                [xlm, xh, yl, yhm],
                [xl, xhm, ylm, yh],
                [xlm, xh, ylm, yh],
            ];
            let cells = &sc.ads.hiz[c as usize];
            let base = slot * (cw * cw) as usize;
            // Children past the grid's edge read a neighbour's bounds and are dropped.
            let (i0, i1) = (2 * i, (2 * i + 1).min(cw - 1));
            let (j0, j1) = (2 * j, (2 * j + 1).min(cw - 1));
            let z = [
                cells[base + (j0 * cw + i0) as usize],
                cells[base + (j0 * cw + i1) as usize],
                cells[base + (j1 * cw + i0) as usize],
                cells[base + (j1 * cw + i1) as usize],
            ];
            let exists = [
                true,
                2 * i + 1 < cw,
                2 * j + 1 < cw,
                2 * i + 1 < cw && 2 * j + 1 < cw,
            ];
            // Lane k: child k's interval (its cuts applied in order) and its depth test.
            let mut t0 = [iv.t0; 4];
            let mut t1 = [iv.t1; 4];
            let by_position: [[Cut; 4]; 4] = from_fn(|q| from_fn(|k| cuts[k][q]));
            for cut in by_position {
                let lo: [f32; 4] = from_fn(|k| cut[k].lo);
                let hi: [f32; 4] = from_fn(|k| cut[k].hi);
                t0 = from_fn(|k| if lo[k] > t0[k] { lo[k] } else { t0[k] });
                t1 = from_fn(|k| if hi[k] < t1[k] { hi[k] } else { t1[k] });
            }
            let zmin: [f32; 4] = from_fn(|k| ordered_to_f32(z[k][0]));
            let zmax: [f32; 4] = from_fn(|k| ordered_to_f32(z[k][1]));
            let za: [f32; 4] = from_fn(|k| ray_depth(vr, t0[k]));
            let zb: [f32; 4] = from_fn(|k| ray_depth(vr, t1[k]));
            let dlo: [f32; 4] = from_fn(|k| fmin(za[k], zb[k]) - vr.eps);
            let dhi: [f32; 4] = from_fn(|k| fmax(za[k], zb[k]) + vr.eps);
            let pass: [bool; 4] =
                from_fn(|k| exists[k] && t0[k] <= t1[k] && dhi[k] >= zmin[k] && dlo[k] <= zmax[k]);
            // Written whether kept or not: no branch on `pass`.
            for &(di, dj) in order.iter().rev() {
                let k = (dj * 2 + di) as usize;
                let civ = Interval {
                    t0: t0[k],
                    t1: t1[k],
                };
                self.scratch.stack[len] = (c, 2 * i + di, 2 * j + dj, civ);
                len += usize::from(pass[k]);
            }
        }
    }

    /// A ray from the apex of a single view that holds every triangle
    /// ([`Apex::direct`]), without its set-up or walk: every bucket of
    /// every tile of `tiles` with content, front to back in each, ends
    /// tested as [`RayState::buckets`] tests them. `tiles` holds every tile
    /// the walk could reach ([`Apex::look`]), and a walk's buckets are some
    /// of its tiles' buckets, so the triangles tested include the walk's;
    /// where the view holds every triangle the walk finds the closest hit
    /// of all triangles (the plain stage is exact there), so the closest of
    /// more candidates is the same hit. Only where the view holds every
    /// triangle: elsewhere a triangle that crosses the near plane could be
    /// hit before it from a tile the walk does not reach.
    fn direct(&mut self, v: &View, tiles: &Reach) {
        let vr = v.ray(self.ray);
        let base = v.slot as usize * v.tile_count();
        // The ray's box in the image, against the triangles' (module docs).
        let screen = &self.sc.screen[..];
        let point = match &self.sc.apex {
            Some(apex) if !screen.is_empty() => apex.coords(self.ray),
            _ => None,
        };
        let boxes = point.map(|(x, y, m)| {
            let ray = ViewBox::new(
                [x - m, y - m, f32::NEG_INFINITY],
                [x + m, y + m, f32::INFINITY],
            );
            (screen, ray)
        });
        for j in tiles.j.0..=tiles.j.1 {
            for i in tiles.i.0..=tiles.i.1 {
                let tile = base + (j * v.tiles + i) as usize;
                let [zmin, zmax] = self.sc.ads.hiz[0][tile];
                let (zmin, zmax) = (ordered_to_f32(zmin), ordered_to_f32(zmax));
                // Empty bounds are [+inf, -inf].
                if zmin <= zmax {
                    let all = (f32::NEG_INFINITY, f32::INFINITY);
                    self.buckets(&vr, tile, (zmin, zmax), all, boxes);
                }
            }
        }
    }

    fn visit_tile(&mut self, v: &View, vr: &ViewRay, i: u32, j: u32, iv: Interval) {
        if STATS {
            self.stats.tiles += 1;
        }
        let tile = v.slot as usize * v.tile_count() + (j * v.tiles + i) as usize;
        let [zmin, zmax] = self.sc.ads.hiz[0][tile];
        let (zmin, zmax) = (ordered_to_f32(zmin), ordered_to_f32(zmax));
        let (lo, hi) = depth_span(vr, iv);
        if !(hi >= zmin && lo <= zmax) {
            return;
        }
        let boxes = if STATS { None } else { self.sc.boxes(v) };
        let boxes = boxes.map(|b| (b, span_box(vr, iv, (lo, hi))));
        self.buckets(vr, tile, (zmin, zmax), (lo, hi), boxes);
    }

    /// The rest of `visit_tile` for a tile whose depth bounds the ray's span
    /// `[lo, hi]` meets: its buckets in the ray's depth order. A triangle
    /// whose box in `boxes` misses the ray segment's there is left out
    /// (module docs).
    fn buckets(
        &mut self,
        vr: &ViewRay,
        tile: usize,
        (zmin, zmax): (f32, f32),
        (lo, hi): (f32, f32),
        boxes: Option<(&[ViewBox], ViewBox)>,
    ) {
        let sc = self.sc;
        let nb = sc.buckets;
        let (b0, b1) = bucket_pair(lo, hi, zmin, zmax, nb);
        let ascending = vr.d[2] >= 0.0;
        let lists = &sc.ads.lists;
        let first = tile * nb as usize;
        let mut best = self.best;
        for n in 0..=(b1 - b0) {
            let k = if ascending { b0 + n } else { b1 - n };
            if best.is_hit() {
                // Depth of the best hit on this ray; no point of a later bucket can be closer.
                let zb = ray_depth(vr, best.t);
                if ascending && bucket_floor_depth(k, zmin, zmax, nb) > zb + vr.eps {
                    break;
                }
                if !ascending && bucket_ceil_depth(k, zmin, zmax, nb) < zb - vr.eps {
                    break;
                }
            }
            let list = first + k as usize;
            let ids = &lists.ids[lists.offsets[list] as usize..lists.offsets[list + 1] as usize];
            if STATS {
                self.stats.buckets += 1;
                self.stats.tests += ids.len() as u32;
            }
            // Tested LANES at a time; the rest of the list one by one.
            let mut lanes = [0u32; LANES];
            let mut n = 0;
            for &id in ids {
                if !STATS {
                    if let Some((boxes, span)) = boxes
                        && !boxes[id as usize].meets(&span)
                    {
                        continue;
                    }
                    let tag = u64::from(self.scratch.ray) << 32 | u64::from(id);
                    let slot = &mut self.scratch.mailbox[id as usize % MAILBOX];
                    if *slot == tag {
                        continue;
                    }
                    *slot = tag;
                }
                lanes[n] = id;
                n += 1;
                if n == LANES {
                    intersect_closest_lanes(self.ray, &self.sh, sc.tris, lanes, &mut best);
                    n = 0;
                }
            }
            if n >= 2 {
                // Two or three left: one more group, its last lanes repeating
                // a triangle (the same candidate twice changes no hit).
                let last = lanes[n - 1];
                lanes[n..].fill(last);
                intersect_closest_lanes(self.ray, &self.sh, sc.tris, lanes, &mut best);
            } else if n == 1 {
                let id = lanes[0];
                intersect_closest(self.ray, &self.sh, &sc.tris[id as usize], id, &mut best);
            }
        }
        self.best = best;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread3_interleaves() {
        assert_eq!(spread3(0b1), 0b1);
        assert_eq!(spread3(0b11), 0b1001);
        assert_eq!(spread3(0x3ff), 0x0924_9249);
        for x in 0..1024u32 {
            let mut want = 0;
            for b in 0..10 {
                want |= ((x >> b) & 1) << (3 * b);
            }
            assert_eq!(spread3(x), want);
        }
    }

    /// A ray's tag is never one the mailbox holds, even when the tags wrap.
    #[test]
    fn the_mailbox_is_cleared_before_tags_repeat() {
        let mut s = Scratch::new();
        assert!(s.mailbox.iter().all(|&e| e >> 32 != u64::from(s.ray)));
        s.mailbox[3] = u64::from(u32::MAX - 2) << 32 | 3;
        s.ray = u32::MAX - 3;
        s.next_ray();
        assert_eq!(s.ray, u32::MAX - 2);
        s.next_ray();
        assert_eq!(s.ray, u32::MAX - 1);
        assert_eq!(s.mailbox[3] >> 32, u64::from(u32::MAX - 2));
        s.next_ray();
        assert_eq!(s.ray, 0);
        assert!(s.mailbox.iter().all(|&e| e == u64::MAX));
    }

    #[test]
    fn coherent_order_is_a_permutation() {
        let rays: Vec<Ray> = (0..5000)
            .map(|i| {
                let f = i as f32;
                let o = if i % 97 == 0 {
                    Vec3::splat(f32::NAN)
                } else {
                    Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), (f * 0.05).sin() * 3.0)
                };
                Ray::new(
                    o,
                    Vec3::new((f * 0.7).cos(), (f * 0.3).sin(), -0.5),
                    0.0,
                    1.0,
                )
            })
            .collect();
        let order = coherent_order(&rays).expect("enough rays");
        let mut seen: Vec<usize> = order.iter().map(|&i| i as usize).collect();
        seen.sort_unstable();
        assert!(seen.iter().copied().eq(0..rays.len()));
        // Grouped by the face the direction points to, in face order.
        let face = |r: &Ray| {
            let d = r.dir.map(f32::abs);
            let axis = (0..3)
                .find(|&a| (0..3).all(|b| d[a] >= d[b]))
                .expect("finite");
            2 * axis + usize::from(r.dir[axis] < 0.0)
        };
        let faces: Vec<usize> = order.iter().map(|&i| face(&rays[i as usize])).collect();
        assert!(faces.windows(2).all(|w| w[0] <= w[1]), "{faces:?}");
        assert!(faces.first() < faces.last());
        assert!(coherent_order(&rays[..100]).is_none());
        // Rays from one point (NaN origins aside) stay in input order.
        let eye: Vec<Ray> = rays
            .iter()
            .map(|r| {
                let o = if r.origin[0].is_nan() {
                    r.origin()
                } else {
                    Vec3::new(0.5, 1.0, 2.0)
                };
                Ray::new(o, r.dir(), 0.0, 1.0)
            })
            .collect();
        assert!(coherent_order(&eye).is_none());
    }

    /// The boxes are computed for rays when there are enough of them, from
    /// several points or from one, but not for rays from the centre of
    /// perspective views (a single view's apex; from there its tiles'
    /// content bits are computed, when there are enough); in a single view
    /// that does not see the whole scene, a triangle it does not hold gets
    /// the whole space, and one it holds its vertices' box, which a box
    /// beside it in any coordinate misses.
    #[test]
    fn boxes_are_computed_where_they_pay_and_span_what_a_view_misses() {
        let tris = dirt_scene::builtin("cornell").expect("built-in").triangles;
        let ray = |o: Vec3| Ray::new(o, Vec3::new(0.1, -0.2, -1.0), 0.0, f32::INFINITY);
        let eye = Vec3::new(0.0, 1.0, 3.0);
        let single = dirt_core::AdsParams {
            views: ViewsKind::Single,
            center: Some(eye),
            ..dirt_core::AdsParams::default()
        };
        let ads = Ads::build(&tris, &single).expect("build");
        let pairs = tris.len() * ads.views.slots();
        let mut sc = Scene::new(&ads, &tris).expect("fast path");
        let prepare = |sc: &mut Scene, rays: &[Ray]| {
            sc.prepare_for(rays, crate::cost::common_origin(rays), None);
        };
        let one_point = vec![ray(eye); pairs];
        prepare(&mut sc, &one_point);
        assert!(sc.boxes.is_empty(), "rays from the apex");
        // From the single view's apex: its tiles' content bits, when they pay.
        let tiles = ads.views.views[0].tile_count();
        let marked = |sc: &Scene| sc.apex.as_ref().is_some_and(|a| !a.content.is_empty());
        assert_eq!(marked(&sc), pairs * TILES_PER_RAY >= tiles);
        // From one point elsewhere: as from several points.
        let elsewhere = vec![ray(Vec3::new(0.1, 0.9, 2.5)); pairs];
        let mut sc = Scene::new(&ads, &tris).expect("fast path");
        prepare(&mut sc, &elsewhere[..pairs / PAIRS_PER_RAY - 1]);
        assert!(sc.boxes.is_empty(), "too few rays from one point");
        prepare(&mut sc, &elsewhere[..pairs / PAIRS_PER_RAY + 1]);
        assert_eq!(sc.boxes.len(), pairs, "rays from one point beside the apex");
        let mut sc = Scene::new(&ads, &tris).expect("fast path");
        prepare(&mut sc, &vec![ray(eye); tiles.div_ceil(TILES_PER_RAY)]);
        assert!(marked(&sc), "enough rays from the apex");
        let mut sc = Scene::new(&ads, &tris).expect("fast path");
        prepare(&mut sc, &vec![ray(eye); tiles / TILES_PER_RAY - 1]);
        assert!(!marked(&sc), "too few rays from the apex");
        let mut two_points = one_point.clone();
        two_points[0] = ray(Vec3::ZERO);
        prepare(&mut sc, &two_points[..pairs / PAIRS_PER_RAY - 1]);
        assert!(sc.boxes.is_empty(), "too few rays");
        prepare(&mut sc, &two_points[..pairs / PAIRS_PER_RAY + 1]);
        assert_eq!(sc.boxes.len(), pairs);
        // A view from inside the box sees part of it: some triangles get the whole line.
        let v = &ads.views.views[0];
        let whole = |b: &ViewBox| *b == ViewBox::WHOLE;
        let held = sc.boxes.iter().filter(|b| !whole(b)).count();
        assert!(held > 0 && held < tris.len(), "{held} of {}", tris.len());
        for (t, b) in tris.iter().zip(sc.boxes.iter()) {
            if !whole(b) {
                for k in 0..3 {
                    let p = v.to_view(t.vertex(k));
                    for c in 0..3 {
                        assert!(b.lo[c] < p[c] && p[c] < b.hi[c], "{b:?} holds {p:?}");
                    }
                    // The vertex's own point, as a ray segment of no length, meets the box.
                    let at = ViewBox::new(p, p);
                    assert!(b.meets(&at) && at.meets(b));
                }
                // A box beside it in any one coordinate does not.
                for c in 0..3 {
                    let mut beside = *b;
                    beside.lo[c] = b.hi[c] + 1.0;
                    beside.hi[c] = b.hi[c] + 2.0;
                    assert!(!b.meets(&beside) && !beside.meets(b), "{c}");
                }
            }
        }
    }

    /// Numbers in [-1, 1] from an xorshift generator seeded with `rng`.
    fn uniform(mut rng: u32) -> impl FnMut() -> f32 {
        move || {
            rng ^= rng << 13;
            rng ^= rng >> 17;
            rng ^= rng << 5;
            rng as f32 / u32::MAX as f32 * 2.0 - 1.0
        }
    }

    /// A single view is marked as holding every triangle only when each
    /// lies inside its frustum shrunk by `eps`; then rays from its apex skip
    /// their walk ([`RayState::direct`]) and still get brute force's hits,
    /// the plain stage's. From an eye inside the box the view holds only
    /// part of it, and its rays walk.
    #[test]
    fn rays_from_a_view_that_holds_every_triangle_skip_their_walk_and_keep_their_hits() {
        use crate::trace::trace_ray_plain;
        let tris = dirt_scene::builtin("cornell").expect("built-in").triangles;
        let single = |center: Option<Vec3>, resolution, buckets| dirt_core::AdsParams {
            views: ViewsKind::Single,
            center,
            resolution,
            buckets,
            ..dirt_core::AdsParams::default()
        };
        let outside = Vec3::new(0.3, 1.2, 7.0);
        let inside = Vec3::new(0.1, 1.0, 0.5);
        for (p, holds) in [
            (single(Some(outside), 64, 4), true),
            (single(Some(outside), 256, 1), true),
            (single(None, 32, 8), true),
            (single(Some(inside), 64, 4), false),
            (dirt_core::AdsParams::default(), false),
        ] {
            let ads = Ads::build(&tris, &p).expect("build");
            assert_eq!(ads.sees_all, holds, "{p:?}");
            if holds {
                // Every vertex inside every plane shrunk by eps.
                let v = &ads.views.views[0];
                for t in &tris {
                    for k in 0..3 {
                        let q = v.to_view(t.vertex(k));
                        assert!(view_frustum(v).iter().all(|h| h.eval(q, -v.eps) >= 0.0));
                    }
                }
            }
            let eye = ads.views.views[0].apex;
            // Towards vertices, edges' midpoints and anywhere, from the apex;
            // as many as mark the tiles' content bits, and a few.
            let mut next = uniform(0x2545_f491);
            let rays: Vec<Ray> = (0..3000)
                .map(|k| {
                    let t = &tris[k * 7 % tris.len()];
                    let d = match k % 3 {
                        0 => t.vertex(k % 3) - eye,
                        1 => (t.vertex(0) + t.vertex(1)) * 0.5 - eye,
                        _ => Vec3::new(next(), next(), next()),
                    };
                    Ray::new(eye, d, 0.0, f32::INFINITY)
                })
                .collect();
            let mut sc = Scene::new(&ads, &tris).expect("fast path");
            assert_eq!(sc.apex.as_ref().is_some_and(|a| a.direct), holds, "{p:?}");
            // Enough rays for the triangles' image boxes, which `trace` reads.
            sc.prepare_for(&rays, Some(eye), None);
            assert_eq!(!sc.screen.is_empty(), holds, "{p:?}");
            // A build at the rays' origin made those boxes as it covered the
            // triangles, so that a few rays read them too; others made none.
            let made = holds && p.center.is_some();
            assert_eq!(!ads.image_boxes.is_empty(), made, "{p:?}");
            if made {
                let want = apex_boxes(&ads.views.views[0], &tris);
                assert_eq!(format!("{:?}", ads.image_boxes), format!("{want:?}"));
            }
            let few = &rays[..2];
            assert!(few.len() as u64 * APEX_RAYS_PER_TRIANGLE < tris.len() as u64);
            let mut sc = Scene::new(&ads, &tris).expect("fast path");
            sc.prepare_for(few, Some(eye), None);
            assert_eq!(!sc.screen.is_empty(), made, "{p:?}");
            for trav in [Traversal::Linear, Traversal::HiZ] {
                let hits = crate::trace(&ads, &tris, &rays, trav);
                // Few rays (the build's boxes only, where made): the same hits.
                let some = crate::trace(&ads, &tris, &rays[..60], trav);
                let bits = |h: &[Hit]| h.iter().map(Hit::bits).collect::<Vec<_>>();
                assert_eq!(bits(&some), bits(&hits[..60]), "{p:?} {trav:?}");
                for (r, h) in rays.iter().zip(&hits) {
                    let mut st = RayStats::default();
                    let want = trace_ray_plain(&ads, &tris, r, trav, &mut st);
                    assert_eq!(h.bits(), want.bits(), "{p:?} {trav:?} {r:?}");
                    if holds {
                        let bf = crate::brute_force::trace_ray(&tris, r);
                        assert_eq!(h.bits(), bf.bits(), "{p:?} {trav:?} {r:?}");
                    }
                }
                // Most rays hit (where the view holds the box: outside it, a
                // single view finds only what it sees).
                let hit = hits.iter().filter(|h| h.is_hit()).count();
                assert!(!holds || hit > rays.len() / 2, "{p:?}: {hit} hits");
            }
        }
    }

    /// The looks of a chunk of rays, taken side by side where the apex has
    /// its tiles' content marked, are each ray's own [`Apex::look`], to the
    /// bit: rays from the apex in any direction (ahead, beside the view,
    /// behind, along an axis, not finite), rays from elsewhere, and chunks
    /// of every length up to [`LOOKS`].
    #[test]
    fn looks_side_by_side_are_each_rays_own() {
        let tris = dirt_scene::builtin("cornell").expect("built-in").triangles;
        // A look as bits, for comparing.
        let bits =
            |l: &Look| l.map(|r| r.map(|r| (r.i, r.j, r.depth.0.to_bits(), r.depth.1.to_bits())));
        let mut next = uniform(0x1234_5679);
        let mut looked = [0usize; 3];
        for (eye, resolution) in [
            (Vec3::new(0.3, 1.2, 7.0), 64),
            (Vec3::new(0.3, 1.2, 7.0), 256),
            (Vec3::new(-2.0, 0.4, 3.5), 32),
        ] {
            let p = dirt_core::AdsParams {
                views: ViewsKind::Single,
                center: Some(eye),
                resolution,
                buckets: 2,
                ..dirt_core::AdsParams::default()
            };
            let ads = Ads::build(&tris, &p).expect("build");
            let eye = ads.views.views[0].apex;
            let special = [0.0, -0.0, 1e-30, 1e30, f32::INFINITY, f32::NAN];
            let rays: Vec<Ray> = (0..4000)
                .map(|k| {
                    let mut d = [next() * 2.0, next() * 2.0, next() * 2.0];
                    if k % 5 == 0 {
                        d[k % 3] = special[k / 5 % special.len()];
                    }
                    if k % 3 == 0 {
                        // Towards the box.
                        d = (tris[k % tris.len()].vertex(k % 3) - eye).to_array();
                    }
                    let origin = if k % 97 == 0 {
                        eye + Vec3::X * 1e-3
                    } else {
                        eye
                    };
                    Ray {
                        origin: origin.to_array(),
                        tmin: 0.0,
                        dir: d,
                        tmax: f32::INFINITY,
                    }
                })
                .collect();
            let mut sc = Scene::new(&ads, &tris).expect("fast path");
            // As `prepare_for` marks them for enough rays from the apex.
            let tiles = sc.views[0].tile_count();
            let apex = sc.apex.as_mut().expect("a single view's apex");
            apex.mark(&ads.hiz[0][..tiles]);
            assert!(!apex.content.is_empty(), "the tiles' content is marked");
            let apex = sc.apex.as_ref().expect("a single view's apex");
            let mut at = 0;
            let mut len = 0;
            while at < rays.len() {
                let chunk = &rays[at..(at + len).min(rays.len())];
                let mut looks = [Some(None); LOOKS];
                sc.looks_at_apex(chunk, &mut looks);
                for (ray, look) in chunk.iter().zip(&looks) {
                    let want = apex.look(&sc, ray);
                    assert_eq!(bits(look), bits(&want), "{ray:?}");
                    looked[match want {
                        None => 0,
                        Some(None) => 1,
                        Some(Some(_)) => 2,
                    }] += 1;
                }
                at += chunk.len();
                len = (len + 1) % (LOOKS + 1);
            }
        }
        // Every kind of look was met.
        assert!(looked.iter().all(|&n| n > 100), "{looked:?}");
    }

    #[test]
    fn rays_are_cut_to_their_views_content_and_keep_every_point_near_it() {
        let tris = dirt_scene::builtin("cornell").expect("built-in").triangles;
        let eye = Vec3::new(0.0, 1.0, 3.0);
        let mut next = uniform(0x9e37_79b9);
        let mut cut_near = 0;
        for views in [ViewsKind::Single, ViewsKind::Cube, ViewsKind::OrthoSplit] {
            let p = dirt_core::AdsParams {
                views,
                center: (views == ViewsKind::Single).then_some(eye),
                ..dirt_core::AdsParams::default()
            };
            let ads = Ads::build(&tris, &p).expect("build");
            let sc = Scene::new(&ads, &tris).expect("fast path");
            for k in 0..300 {
                let o = if k % 2 == 0 {
                    eye
                } else {
                    Vec3::new(next(), 1.0 + next(), next())
                };
                let d = Vec3::new(next(), next(), next() - 0.5);
                let ray = Ray::new(o, d, 0.0, f32::INFINITY);
                let (vrs, ivs, _) = sc.lanes.enter(&ray);
                for f in 0..sc.views.len() {
                    let (vr, iv) = (&vrs[f], ivs[f]);
                    if iv.is_empty() {
                        continue;
                    }
                    let mut cut = iv;
                    sc.to_content(f, vr, &mut cut);
                    let [zmin, zmax] = sc.content[f];
                    if !(zmin <= zmax) {
                        assert!(cut.is_empty(), "a view without content");
                        continue;
                    }
                    cut_near += usize::from(cut.t0 > iv.t0);
                    // Every point of the interval within one eps of the
                    // content's depth stays (the ends and 64 points between).
                    let t1 = if iv.t1.is_finite() {
                        iv.t1
                    } else {
                        iv.t0 + 100.0
                    };
                    for q in 0..=65 {
                        let t = fmin(iv.t0 + (t1 - iv.t0) * (q as f32 / 65.0), iv.t1);
                        let z = ray_depth(vr, t);
                        if z >= zmin - vr.eps && z <= zmax + vr.eps {
                            assert!(
                                cut.t0 <= t && t <= cut.t1,
                                "{views:?} view {f}: t {t} (depth {z}) left out of {cut:?}"
                            );
                        }
                    }
                    // What is left lies within three eps of the content.
                    if !cut.is_empty() {
                        for t in [cut.t0, cut.t1].into_iter().filter(|t| t.is_finite()) {
                            let z = ray_depth(vr, t);
                            assert!(
                                z >= zmin - 3.0 * vr.eps && z <= zmax + 3.0 * vr.eps,
                                "{views:?} view {f}: depth {z} of {cut:?} past [{zmin}, {zmax}]"
                            );
                        }
                    }
                }
            }
        }
        assert!(cut_near > 100, "rays whose start is cut: {cut_near}");
        // The apex check's margin follows the content's depth, not the near plane.
        let single = dirt_core::AdsParams {
            views: ViewsKind::Single,
            center: Some(eye),
            ..dirt_core::AdsParams::default()
        };
        let ads = Ads::build(&tris, &single).expect("build");
        let sc = Scene::new(&ads, &tris).expect("fast path");
        let v = &ads.views.views[..];
        let margin = |a: Option<Apex>| a.expect("an apex").margin;
        assert!(
            sc.content[0][0] > v[0].near * 2.0,
            "content well past the near plane"
        );
        assert!(margin(Apex::of(v, sc.content[0][0], false)) < margin(Apex::of(v, 0.0, false)));
    }

    /// In an orthographic view whose content is a strip of the image, a
    /// ray's interval is cut to the strip's tiles: every point of it in a
    /// tile with content, at a depth within `eps` of the content's, stays,
    /// and the hits of both walks are brute force's, bit for bit.
    #[test]
    fn rays_are_cut_to_the_tiles_with_content_and_keep_their_hits() {
        // Along x, thin in y and z: the image (square over the widest side,
        // looking along y) holds content in a few rows.
        let tris: Vec<Triangle> = (0..64)
            .map(|k| {
                let x = -4.0 + k as f32 * 0.125;
                Triangle::new(
                    Vec3::new(x, -0.2, 0.0),
                    Vec3::new(x + 0.125, -0.2, 0.3),
                    Vec3::new(x, 0.2, 0.6),
                )
            })
            .collect();
        let p = dirt_core::AdsParams {
            views: ViewsKind::Ortho,
            resolution: 64,
            buckets: 4,
            ..dirt_core::AdsParams::default()
        };
        let ads = Ads::build(&tris, &p).expect("build");
        let sc = Scene::new(&ads, &tris).expect("fast path");
        let v = &sc.views[0];
        let [xlo, xhi, ylo, yhi] = sc.rect[0].expect("content over a strip");
        assert!((xhi - xlo) * (yhi - ylo) <= 0.5 * (2.0 * v.tan) * (2.0 * v.tan));
        let [zmin, zmax] = sc.content[0];
        let full = |x: f32, y: f32| {
            let (i, j) = (v.tile_coord(x).floor(), v.tile_coord(y).floor());
            let n = v.tiles as f32;
            if !(i >= 0.0 && j >= 0.0 && i < n && j < n) {
                return false;
            }
            let [lo, hi] = ads.hiz[0][(j as u32 * v.tiles + i as u32) as usize];
            ordered_to_f32(lo) <= ordered_to_f32(hi)
        };
        let mut next = uniform(0x2545_f491);
        let rays: Vec<Ray> = (0..3000)
            .map(|_| {
                let o = Vec3::new(6.0 * next(), 2.0 * next(), 6.0 * next());
                let aim = Vec3::new(4.0 * next(), 0.2 * next(), 0.3 + 0.3 * next());
                // Half aimed at the strip, half anywhere.
                let d = if next() > 0.0 {
                    aim - o
                } else {
                    Vec3::new(next(), next(), next())
                };
                Ray::new(o, d, 0.0, f32::INFINITY)
            })
            .filter(|r| r.validate().is_ok())
            .collect();
        let mut shortened = 0;
        for ray in &rays {
            let (vrs, ivs, _) = sc.lanes.enter(ray);
            let (vr, iv) = (&vrs[0], ivs[0]);
            if iv.is_empty() {
                continue;
            }
            let mut cut = iv;
            sc.to_content(0, vr, &mut cut);
            shortened += usize::from(cut.t0 > iv.t0 || cut.t1 < iv.t1);
            let t1 = if iv.t1.is_finite() {
                iv.t1
            } else {
                iv.t0 + 100.0
            };
            for q in 0..=65 {
                let t = fmin(iv.t0 + (t1 - iv.t0) * (q as f32 / 65.0), iv.t1);
                let [x, y, z] = ray_point(vr, t);
                if full(x, y) && z >= zmin - vr.eps && z <= zmax + vr.eps {
                    assert!(
                        cut.t0 <= t && t <= cut.t1,
                        "t {t} at ({x}, {y}, {z}) left out of {cut:?}"
                    );
                }
            }
        }
        assert!(shortened > 500, "rays cut: {shortened}");
        let truth = crate::brute_force::trace(&tris, &rays);
        assert!(truth.iter().filter(|h| h.is_hit()).count() > 500);
        for traversal in Traversal::ALL {
            let hits = crate::trace::trace(&ads, &tris, &rays, traversal);
            for (k, (h, b)) in hits.iter().zip(&truth).enumerate() {
                assert_eq!(h.bits(), b.bits(), "{traversal:?} ray {k}");
            }
        }
    }

    use dirt_math::clip::clip_ray_to_view;
    use dirt_math::{Aabb, Vec3, ViewSet};
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f32> {
        prop_oneof![
            -3.0f32..3.0,
            Just(0.0),
            Just(-0.0),
            Just(1.0),
            Just(-1.0),
            Just(1e30),
            Just(-1e-30)
        ]
    }

    fn v3() -> impl Strategy<Value = Vec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        // The views' set-up as lanes, and the cut form of a tile's clip
        // (Hi-Z cell, band, tile), give the plain functions' bits.
        #[test]
        fn cuts_clip_like_the_plain_functions(
            o in v3(), d in v3(), tmin in prop_oneof![Just(0.0f32), 0.0f32..2.0],
            tmax in prop_oneof![Just(f32::INFINITY), 0.0f32..5.0],
            kind in 0usize..4, axis in 0usize..3, face in 0usize..6, tiles in 1u32..40, k in 0u32..41, l in 0u32..41,
        ) {
            let bounds = Aabb { min: Vec3::splat(-2.0), max: Vec3::splat(2.0) };
            let axis = dirt_math::view::Axis::ALL[axis];
            let vs = match kind {
                0 => ViewSet::cube(Vec3::new(0.1, -0.2, 0.05), &bounds, tiles),
                1 => ViewSet::single(None, &bounds, tiles),
                2 => ViewSet::ortho(axis, None, &bounds, tiles),
                _ => ViewSet::ortho(axis, Some(0.3), &bounds, tiles),
            };
            let ray = Ray::new(o, d, tmin, tmax);
            prop_assume!(ray.validate().is_ok());
            // Every view's set-up as lanes: View::ray and clip_ray_to_view's bits.
            let (vrs, ivs, exits) = ViewLanes::new(&vs.views).enter(&ray);
            for (f, v) in vs.views.iter().enumerate() {
                let vr = v.ray(&ray);
                let bits = |r: &ViewRay| (r.o.map(f32::to_bits), r.d.map(f32::to_bits), r.eps.to_bits());
                prop_assert_eq!(bits(&vrs[f]), bits(&vr));
                let (a, ea) = if v.has_content {
                    clip_ray_to_view(v, &vr, tmin, tmax)
                } else {
                    (Interval::EMPTY, None)
                };
                prop_assert_eq!((a.t0.to_bits(), a.t1.to_bits(), ea), (ivs[f].t0.to_bits(), ivs[f].t1.to_bits(), exits[f]));
            }
            let v = &vs.views[face % vs.views.len()];
            let vr = v.ray(&ray);
            let (a, _) = clip_ray_to_view(v, &vr, tmin, tmax);
            let (k, l) = (k.min(tiles), l.min(tiles));
            let cell = dirt_math::clip::block_frustum(v, k.min(l), k.max(l), l.min(k), k.max(l));
            let mut plain = a;
            let mut cut = a;
            for h in &cell {
                plain.clip(h, &vr);
                Cut::of(h, &vr).apply(&mut cut);
            }
            if plain.is_empty() {
                prop_assert!(cut.is_empty());
            } else {
                prop_assert_eq!((plain.t0.to_bits(), plain.t1.to_bits()), (cut.t0.to_bits(), cut.t1.to_bits()));
            }
            let (sx, sy) = (v.boundary(k), v.boundary(l));
            let sides = Cut::sides(&vr, w_terms(v, &vr), sx, sy);
            let planes = [v.lo(0, sx), v.hi(0, sx), v.lo(1, sy), v.hi(1, sy)];
            for (c, h) in sides.iter().zip(&planes) {
                let one = Cut::of(h, &vr);
                prop_assert_eq!((c.lo.to_bits(), c.hi.to_bits()), (one.lo.to_bits(), one.hi.to_bits()));
            }
            // An orthographic view's sides with one slope for all lanes.
            if v.ortho {
                for a in 0..2 {
                    let ((llo, lhi), (hlo, hhi)) = ortho_sides((vr.o[a], vr.d[a]), [sx, sy], [sy, sx], vr.eps);
                    for (q, s) in [sx, sy].into_iter().enumerate() {
                        let (lo, hi) = (Cut::of(&v.lo(a, s), &vr), Cut::of(&v.hi(a, [sy, sx][q]), &vr));
                        prop_assert_eq!((llo[q].to_bits(), lhi[q].to_bits()), (lo.lo.to_bits(), lo.hi.to_bits()));
                        prop_assert_eq!((hlo[q].to_bits(), hhi[q].to_bits()), (hi.lo.to_bits(), hi.hi.to_bits()));
                    }
                }
            }
        }
    }
}
