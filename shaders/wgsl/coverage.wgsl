// Conservative coverage by rasterization without the hardware feature: the
// vertex shader draws, per (view, triangle), the pixel-aligned quad of the
// tile range `dirt_math::clip::polygon_tile_range` gives (one pixel = one
// tile); the fragment shader runs the exact tile test. Together they are
// dirt_math::clip::for_each_covered_tile, shared by fill_depth and fill_primitives.
#import types
#import view
#import clip
#import tris

// dirt_gpu::BuildParams
struct BuildParams {
    n_tris: u32,
    n_views: u32,
    tiles: u32,
    buckets: u32,
    id_shift: u32, // list ids per chunk: 2^id_shift (ids.wgsl)
    tri_shift: u32, // triangles per chunk: 2^tri_shift (tris.wgsl)
    hiz_shift: u32, // Hi-Z cells per chunk: 2^hiz_shift (hiz.wgsl)
    offset_shift: u32, // list offsets per chunk: 2^offset_shift (offsets.wgsl)
}

@group(0) @binding(1) var<uniform> views: array<View, 6>;
@group(0) @binding(2) var<uniform> params: BuildParams;

struct CoverOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) prim: u32,
    @location(1) @interpolate(flat) view: u32,
    // 1: every vertex lies in every half-space of the view, so clipping
    // keeps the triangle as it is (Sutherland-Hodgman keeps inside vertices,
    // in order) and the fragments skip it: the same polygon, to the bit.
    @location(2) @interpolate(flat) inside: u32,
    // The tile range (i0, i1, j0, j1): tile_depth_extent clips to the
    // planes inside it only.
    @location(3) @interpolate(flat) range: vec4<u32>,
}

fn tri_vertex(prim: u32, k: u32) -> vec3<f32> {
    return tri_load(prim, k, params.tri_shift);
}

// The triangle in view space, clipped to the view.
fn view_polygon(v: View, prim: u32) -> Polygon {
    return clip_triangle_to_view(v, to_view(v, tri_vertex(prim, 0u)), to_view(v, tri_vertex(prim, 1u)), to_view(v, tri_vertex(prim, 2u)));
}

// Whether clip_triangle_to_view would keep the triangle unchanged.
fn inside_view(v: View, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> bool {
    for (var k = 0u; k < 6u; k++) {
        let h = view_halfspace(v, k);
        if !(hs_eval(h, a, v.eps) >= 0.0 && hs_eval(h, b, v.eps) >= 0.0 && hs_eval(h, c, v.eps) >= 0.0) {
            return false;
        }
    }
    return true;
}

// The triangle in view space, clipped to the view; `inside` from the vertex shader.
fn fragment_polygon(v: View, prim: u32, inside: u32) -> Polygon {
    if inside == 1u {
        return polygon_triangle(to_view(v, tri_vertex(prim, 0u)), to_view(v, tri_vertex(prim, 1u)), to_view(v, tri_vertex(prim, 2u)));
    }
    return view_polygon(v, prim);
}

// Six vertices per triangle, one instance per view.
@vertex
fn cover_vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) view: u32) -> CoverOut {
    let prim = vi / 6u;
    let corner = vi % 6u;
    var out: CoverOut;
    out.prim = prim;
    out.view = view;
    // Outside the viewport: no fragments.
    out.pos = vec4<f32>(-2.0, -2.0, 0.0, 1.0);
    let v = views[view];
    if v.slot == NO_SLOT || prim >= params.n_tris {
        return out;
    }
    let a = to_view(v, tri_vertex(prim, 0u));
    let b = to_view(v, tri_vertex(prim, 1u));
    let c = to_view(v, tri_vertex(prim, 2u));
    let r = polygon_tile_range(v, clip_triangle_to_view(v, a, b, c));
    if !r.ok {
        return out;
    }
    out.inside = select(0u, 1u, inside_view(v, a, b, c));
    out.range = vec4<u32>(r.i0, r.i1, r.j0, r.j1);
    // Corners 0..5: (lo,lo) (hi,lo) (lo,hi) (hi,lo) (hi,hi) (lo,hi).
    let x_hi = corner == 1u || corner == 3u || corner == 4u;
    let y_hi = corner == 2u || corner == 4u || corner == 5u;
    let x = f32(select(r.i0, r.i1 + 1u, x_hi));
    let y = f32(select(r.j0, r.j1 + 1u, y_hi));
    let s = 2.0 / f32(v.tiles);
    // Framebuffer row y is tile row j.
    out.pos = vec4<f32>(x * s - 1.0, 1.0 - y * s, 0.0, 1.0);
    return out;
}

struct Covered {
    ok: bool,
    tile: u32,
    lo: f32,
    hi: f32,
}

// The fragment's tile and the triangle's depth extent there.
fn covered(in: CoverOut) -> Covered {
    let v = views[in.view];
    let i = u32(in.pos.x);
    let j = u32(in.pos.y);
    let e = tile_depth_extent(v, fragment_polygon(v, in.prim, in.inside), i, j, in.range);
    let tile = v.slot * tile_count(v) + j * v.tiles + i;
    return Covered(e.ok, tile, e.lo, e.hi);
}
