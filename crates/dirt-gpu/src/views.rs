//! Pass `views` (`views.wgsl`): the view set of `dirt_core::views_for`,
//! computed on the GPU from the triangles for builds recorded into an
//! encoder — scene bounds by an atomic reduction (`bounds`), each view fitted
//! to them (`views_from_bounds`), which views a triangle reaches (`reach`),
//! and the others left out (`leave_out`). The same views as the CPU's, to the
//! bit, except that slots are sparse (a view's slot is its index): the host
//! does not wait to learn which views have content, so every view's block is
//! allocated.

use crate::chunked::{Chunked, Split};
use crate::fill_primitives::grid;
use crate::{Gpu, bind_buffers, record_dispatch, with};
use dirt_math::view::Axis;
use dirt_math::{Aabb, Vec3, ViewGpu, ViewSet, ViewsKind};

/// The views buffer before the first build: each view's axes, tan, tiles,
/// step and (for the cube) adjacency, which do not depend on the scene. The
/// `views` stage fills in the rest every build.
pub(crate) fn template(kind: ViewsKind, tiles: u32) -> [ViewGpu; 6] {
    let unit = Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::splat(1.0),
    };
    // The orthographic views' axes, image and step depend on the bounds:
    // the stage sets them; the template gives their count, tiles and kind.
    let set = match kind {
        ViewsKind::Cube => ViewSet::cube(Vec3::ZERO, &unit, tiles),
        ViewsKind::Single => ViewSet::single(None, &unit, tiles),
        ViewsKind::Ortho => ViewSet::ortho(Axis::Z, None, &unit, tiles),
        ViewsKind::OrthoSplit => ViewSet::ortho(Axis::Z, Some(0.0), &unit, tiles),
    };
    crate::views_gpu(&set)
}

/// Records the four entries over `n_tris` triangles in `tris`: `state` must
/// be zero (cleared in the same encoder) and `params` written; `pipelines`
/// are [`Gpu::pipelines_for`]`(split)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record(
    gpu: &Gpu,
    pipelines: &crate::Pipelines,
    split: Split,
    enc: &mut wgpu::CommandEncoder,
    tris: &Chunked,
    views: &wgpu::Buffer,
    state: &wgpu::Buffer,
    params: &wgpu::Buffer,
    n_tris: u32,
    n_views: u32,
) {
    let [bounds, from_bounds, reach, leave_out] = &pipelines.views;
    let bind = bind_buffers(
        gpu,
        "views",
        &bounds.get_bind_group_layout(0),
        &with(
            &[(1, views), (2, state), (3, params)],
            [tris.bindings(gpu, split)],
        ),
    );
    let (x, y) = grid(gpu, (n_tris as u64).div_ceil(64));
    // (pipeline, workgroups, one thread per triangle): those have nothing to do without triangles.
    let steps = [
        (bounds, [x, y, 1], true),
        (from_bounds, [1, 1, 1], false),
        (reach, [x, y, n_views], true),
        (leave_out, [1, 1, 1], false),
    ];
    for (pipeline, groups, per_triangle) in steps {
        if !(per_triangle && n_tris == 0) {
            record_dispatch(enc, "views", pipeline, &bind, groups);
        }
    }
}
