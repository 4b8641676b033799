// Stage `gather`: an application's mesh (vertex buffer with a stride and a
// position offset, optional u16/u32 index buffer, optional affine transform)
// into dirt's triangle buffer (dirt_math::Triangle, nine f32 each), one
// thread per triangle. Mirrors dirt_core::gather.
//
// A vertex index past the end of the vertex buffer gives NaN positions: the
// `bounds` entry of views.wgsl reports the triangle as non-finite, so a bad
// index is an error of the build, never a read out of bounds.
#import tris_out

// dirt_gpu::GatherParams
struct GatherParams {
    // The first triangle written in the output.
    first_tri: u32,
    n_tris: u32,
    // Vertex stride and position offset, in 4-byte words.
    stride: u32,
    offset: u32,
    // 0: no index buffer (vertex 3·t + k), 1: u16 indices, 2: u32 indices.
    index_format: u32,
    // The first index read, in indices.
    first_index: u32,
    // 1: apply `rows` (a 3×4 affine transform, row-major).
    has_transform: u32,
    // Triangles per output chunk: 2^tri_shift (tris.wgsl).
    tri_shift: u32,
    rows: array<vec4<f32>, 3>,
}

@group(0) @binding(0) var<storage, read> vertices: array<u32>;
@group(0) @binding(1) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<uniform> gp: GatherParams;

fn vertex_index(i: u32) -> u32 {
    let at = gp.first_index + i;
    if gp.index_format == 1u {
        let word = indices[at / 2u];
        return select(word & 0xffffu, word >> 16u, (at & 1u) == 1u);
    } else if gp.index_format == 2u {
        return indices[at];
    }
    return i;
}

// Row r of the transform applied to p, left to right with no fused operation
// (dirt_core::gather::transform_point).
fn row(r: u32, p: vec3<f32>) -> f32 {
    let m = gp.rows[r];
    let a = m[0] * p[0];
    let b = m[1] * p[1];
    let c = m[2] * p[2];
    return ((a + b) + c) + m[3];
}

@compute @workgroup_size(64)
fn gather(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = gid.x + gid.y * nwg.x * 64u;
    if t >= gp.n_tris {
        return;
    }
    for (var k = 0u; k < 3u; k++) {
        let v = vertex_index(3u * t + k);
        let base = v * gp.stride + gp.offset;
        // NaN from a `let`: a constant NaN is refused by Tint (see f32_inf).
        let nan_bits = 0x7fc00000u;
        var p = vec3<f32>(bitcast<f32>(nan_bits));
        // Within the buffer (and no overflow of the address): read it.
        if v < 0x40000000u / max(gp.stride, 1u) && base + 3u <= arrayLength(&vertices) {
            p = vec3<f32>(bitcast<f32>(vertices[base]), bitcast<f32>(vertices[base + 1u]), bitcast<f32>(vertices[base + 2u]));
        }
        if gp.has_transform == 1u {
            p = vec3<f32>(row(0u, p), row(1u, p), row(2u, p));
        }
        tri_store(gp.first_tri + t, k, gp.tri_shift, p);
    }
}
