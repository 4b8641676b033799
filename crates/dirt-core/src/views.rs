//! View selection: the view set both backends build over, and which views are
//! left out because no geometry reaches them.

use crate::{AdsParams, CoreError};
use dirt_math::clip::{clip_triangle_to_view, polygon_tile_range};
use dirt_math::{Aabb, Triangle, Vec3, View, ViewSet, ViewsKind};

/// Checks `params` and `tris` and makes the view set both backends build over.
///
/// Views that no triangle reaches (see [`views_reached`]) are left out: they
/// get no build passes and no memory, and rays skip them. That changes no hit.
pub fn views_for(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CoreError> {
    views_for_bounded(tris, params, None)
}

/// [`views_for`], given the scene bounds where the caller has them already
/// (`bounds` must be [`bounds_of`]`(tris)`: a builder that read them to
/// decide where its views go does not pay for a second pass over every
/// vertex, a fortieth of a deforming grid's frame).
pub fn views_for_bounded(
    tris: &[Triangle],
    params: &AdsParams,
    bounds: Option<Aabb>,
) -> Result<ViewSet, CoreError> {
    let mut views = views_for_all_bounded(tris, params, bounds)?;
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
            let reaches = |t: &Triangle| reaches(v, t);
            // A view is nearly always reached by one of the first triangles:
            // those are tried here, and only the rest (a view left out)
            // goes to the pool, whose hand-over costs more than they do.
            let (head, rest) = tris.split_at(tris.len().min(ON_CALLER));
            v.has_content
                && (head.iter().any(reaches) || (!rest.is_empty() && rest.par_iter().any(reaches)))
        })
        .collect()
}

/// Whether `t`, clipped to `v`'s (dilated) frustum, is not empty and has a
/// tile range.
fn reaches(v: &View, t: &Triangle) -> bool {
    let tv = [
        v.to_view(t.vertex(0)),
        v.to_view(t.vertex(1)),
        v.to_view(t.vertex(2)),
    ];
    clip_triangle_to_view(v, tv)
        .and_then(|p| polygon_tile_range(v, &p))
        .is_some()
}

/// Triangles a check of the build set-up runs through on the calling thread
/// before it hands the rest to the thread pool: handing over and waiting
/// costs tens of microseconds, a whole small scene's check less.
const ON_CALLER: usize = 4096;

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
pub fn left_out_views(
    tris: &[Triangle],
    params: &AdsParams,
) -> Result<Vec<LeftOutView>, CoreError> {
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
                ViewsKind::Ortho => "ortho",
                ViewsKind::OrthoSplit => ["ortho, before the cut", "ortho, after the cut"]
                    .get(k)
                    .copied()
                    .unwrap_or("?"),
            },
            reason: if v.has_content {
                LeftOutReason::NoTriangleReaches
            } else {
                LeftOutReason::BoundsBehind
            },
        })
        .collect())
}

/// [`Aabb::of_triangles`], on all threads past 4,096 triangles: the
/// union of the parts' bounds is the sequential bounds exactly
/// ([`Aabb::union`]).
pub fn bounds_of(tris: &[Triangle]) -> Aabb {
    use rayon::prelude::*;
    if tris.len() <= ON_CALLER {
        return Aabb::of_triangles(tris);
    }
    tris.par_chunks(ON_CALLER)
        .map(Aabb::of_triangles)
        .reduce(|| Aabb::EMPTY, |a, b| a.union(&b))
}

/// The index of the first triangle with a coordinate that is not finite.
/// Chunks are checked without a branch per triangle (the compiler vectorises
/// the fold), and only a failing chunk is searched for the index: a
/// per-triangle parallel search cost 0.5 ms on 32k triangles, a seventh of
/// a deforming grid's rebuild.
pub fn first_non_finite(tris: &[Triangle]) -> Option<usize> {
    use rayon::prelude::*;
    const CHUNK: usize = ON_CALLER;
    let check = |(c, chunk): (usize, &[Triangle])| {
        let finite = chunk.iter().fold(true, |ok, t| {
            ok & t
                .v
                .as_flattened()
                .iter()
                .fold(true, |ok, x| ok & x.is_finite())
        });
        if finite {
            None
        } else {
            chunk
                .iter()
                .position(|t| !t.is_finite())
                .map(|i| c * CHUNK + i)
        }
    };
    if tris.len() <= CHUNK {
        return check((0, tris));
    }
    tris.par_chunks(CHUNK).enumerate().find_map_first(check)
}

/// [`views_for`] without leaving out the views no triangle reaches: every
/// view whose frustum meets the scene bounds is built (the papers'
/// configuration; the baseline that leaving out is measured against).
pub fn views_for_all(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CoreError> {
    views_for_all_bounded(tris, params, None)
}

/// [`views_for_all`] with the bounds of [`views_for_bounded`].
fn views_for_all_bounded(
    tris: &[Triangle],
    params: &AdsParams,
    bounds: Option<Aabb>,
) -> Result<ViewSet, CoreError> {
    params.validate()?;
    if let Some(index) = first_non_finite(tris) {
        return Err(CoreError::NonFiniteTriangle { index });
    }
    let bits = |b: &Aabb| {
        (
            b.min.to_array().map(f32::to_bits),
            b.max.to_array().map(f32::to_bits),
        )
    };
    debug_assert!(
        bounds.is_none_or(|b| bits(&b) == bits(&bounds_of(tris))),
        "views_for_bounded: bounds that are not the triangles' own"
    );
    let mut bounds = bounds.unwrap_or_else(|| bounds_of(tris));
    if bounds.is_empty() {
        bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
    }
    Ok(views_over(params, &bounds))
}

/// The views `params` place over `bounds` (not empty), none left out yet:
/// [`views_for_all`] without its checks of the parameters and the
/// triangles, for a caller that has made them (the cost model, which looks
/// at where the triangles fall in a placement's views before building it).
pub fn views_over(params: &AdsParams, bounds: &Aabb) -> ViewSet {
    let tiles = params.tiles();
    match params.views {
        ViewsKind::Cube => ViewSet::cube(params.center.unwrap_or(bounds.center()), bounds, tiles),
        ViewsKind::Single => ViewSet::single(params.center, bounds, tiles),
        ViewsKind::Ortho | ViewsKind::OrthoSplit => {
            let axis = params.ortho_axis(bounds);
            let cut = (params.views == ViewsKind::OrthoSplit)
                .then(|| params.center.unwrap_or(bounds.center())[axis.index()]);
            ViewSet::ortho(axis, cut, bounds, tiles)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles on both sides of the threshold below which the set-up's
    /// checks stay on the calling thread.
    const SIZES: [usize; 6] = [
        0,
        1,
        ON_CALLER - 1,
        ON_CALLER,
        ON_CALLER + 1,
        2 * ON_CALLER + 7,
    ];

    /// A small triangle at `p`.
    fn speck(p: Vec3) -> Triangle {
        Triangle::new(p, p + Vec3::X * 0.01, p + Vec3::Y * 0.01)
    }

    #[test]
    fn bounds_on_the_caller_or_the_pool_are_the_sequential_bounds() {
        for n in SIZES {
            let tris: Vec<Triangle> = (0..n)
                .map(|k| {
                    let f = k as f32;
                    speck(Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), -0.0 * f))
                })
                .collect();
            let (a, b) = (bounds_of(&tris), Aabb::of_triangles(&tris));
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(
                (bits(a.min), bits(a.max)),
                (bits(b.min), bits(b.max)),
                "{n}"
            );
        }
    }

    /// Bounds handed in place the views exactly where the views' own
    /// reading of the bounds does, for every kind of view set.
    #[test]
    fn views_given_the_bounds_are_the_views_found_without_them() {
        let tris: Vec<Triangle> = (0..ON_CALLER + 9)
            .map(|k| {
                let f = k as f32;
                speck(Vec3::new(
                    (f * 0.37).sin() * 3.0,
                    (f * 0.11).cos(),
                    (f * 0.05).sin() - 0.5,
                ))
            })
            .collect();
        for views in [
            ViewsKind::Cube,
            ViewsKind::Single,
            ViewsKind::Ortho,
            ViewsKind::OrthoSplit,
        ] {
            let params = AdsParams {
                views,
                ..AdsParams::default()
            };
            let given = views_for_bounded(&tris, &params, Some(bounds_of(&tris))).expect("views");
            let found = views_for(&tris, &params).expect("views");
            assert_eq!(given, found, "{views:?}");
        }
    }

    /// Bounds of other triangles are a caller's error, caught where
    /// assertions are on (they would place the views wrongly).
    #[cfg(debug_assertions)]
    #[test]
    #[should_panic(expected = "not the triangles' own")]
    fn views_given_other_bounds_are_refused() {
        let tris = [speck(Vec3::ZERO), speck(Vec3::ONE)];
        let _ = views_for_bounded(&tris, &AdsParams::default(), Some(bounds_of(&tris[..1])));
    }

    /// Which views a triangle past the first `ON_CALLER` reaches is found
    /// as if every triangle were tried in turn.
    #[test]
    fn views_reached_tries_every_triangle() {
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let views = ViewSet::cube(Vec3::ZERO, &bounds, 8);
        let reached_plainly = |tris: &[Triangle]| -> Vec<bool> {
            views
                .views
                .iter()
                .map(|v| v.has_content && tris.iter().any(|t| reaches(v, t)))
                .collect()
        };
        for n in SIZES {
            // Every triangle in front of the +x face only, then one in
            // front of the -x face at the start, the end or past the head.
            let tris = vec![speck(Vec3::new(0.9, 0.0, 0.0)); n];
            let want = reached_plainly(&tris);
            assert_eq!(views_reached(&views, &tris), want, "{n}");
            assert!(
                n == 0 || want.iter().filter(|&&r| r).count() < 6,
                "{n}: a face is left out"
            );
            for at in [0, ON_CALLER - 1, ON_CALLER, n.saturating_sub(1)] {
                if at >= n {
                    continue;
                }
                let mut t = tris.clone();
                t[at] = speck(Vec3::new(-0.9, 0.0, 0.0));
                let want_here = reached_plainly(&t);
                assert_ne!(want_here, want, "{n}, at {at}: the -x face is reached");
                assert_eq!(views_reached(&views, &t), want_here, "{n}, at {at}");
            }
        }
    }

    #[test]
    fn the_first_non_finite_triangle_is_found_across_chunks() {
        let ok = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        for n in [0usize, 1, 4095, 4096, 4097, 9000] {
            let tris = vec![ok; n];
            assert_eq!(first_non_finite(&tris), None, "{n}");
            for bad in [0, 1, 4095, 4096, 4097, 8191, 8192, 8999] {
                if bad >= n {
                    continue;
                }
                for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    for c in [0, 4, 8] {
                        let mut t = tris.clone();
                        t[bad].v[c / 3][c % 3] = x;
                        // A later bad triangle too: the first is named.
                        if let Some(later) = t.get_mut(bad + 4100) {
                            later.v[0][0] = f32::NAN;
                        }
                        let want = t.iter().position(|t| !t.is_finite());
                        assert_eq!(want, Some(bad));
                        assert_eq!(first_non_finite(&t), want, "n {n}, at {bad}, {x}");
                    }
                }
            }
        }
    }
}
