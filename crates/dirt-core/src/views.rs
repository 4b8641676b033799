//! View selection: the view set both backends build over, and which views are
//! left out because no geometry reaches them.

use crate::{AdsParams, CoreError};
use dirt_math::clip::{clip_triangle_to_view, polygon_tile_range};
use dirt_math::view::Axis;
use dirt_math::{Aabb, Triangle, Vec3, ViewSet, ViewsKind};

/// Checks `params` and `tris` and makes the view set both backends build over.
///
/// Views that no triangle reaches (see [`views_reached`]) are left out: they
/// get no build passes and no memory, and rays skip them. That changes no hit.
pub fn views_for(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CoreError> {
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

/// [`Aabb::of_triangles`] on all threads: the union of the parts' bounds is
/// the sequential bounds exactly ([`Aabb::union`]).
pub fn bounds_of(tris: &[Triangle]) -> Aabb {
    use rayon::prelude::*;
    tris.par_chunks(4096)
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
    const CHUNK: usize = 4096;
    tris.par_chunks(CHUNK)
        .enumerate()
        .find_map_first(|(c, chunk)| {
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
        })
}

/// [`views_for`] without leaving out the views no triangle reaches: every
/// view whose frustum meets the scene bounds is built (the papers'
/// configuration; the baseline that leaving out is measured against).
pub fn views_for_all(tris: &[Triangle], params: &AdsParams) -> Result<ViewSet, CoreError> {
    params.validate()?;
    if let Some(index) = first_non_finite(tris) {
        return Err(CoreError::NonFiniteTriangle { index });
    }
    let mut bounds = bounds_of(tris);
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
        ViewsKind::Ortho | ViewsKind::OrthoSplit => {
            let axis = params
                .axis
                .unwrap_or_else(|| Axis::thinnest(bounds.extent()));
            let cut = (params.views == ViewsKind::OrthoSplit)
                .then(|| params.center.unwrap_or(bounds.center())[axis.index()]);
            ViewSet::ortho(axis, cut, &bounds, tiles)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
