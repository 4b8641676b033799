// The triangles (nine f32 each: three vertices), split across bindings so
// that no single binding limits a scene's size (dirt_gpu's triangle chunks):
// triangle `prim` is triangle `prim & mask` of chunk `prim >> shift`, each
// chunk 2^shift triangles. This file is the one-chunk module for the stages
// that read them; dirt_shaders::chunked_module writes it for more chunks, at
// bindings 24, 25, ...
@group(0) @binding(24) var<storage, read> tris0: array<f32>;

// Vertex `k` of triangle `prim`; the caller keeps `prim` below the count.
fn tri_load(prim: u32, k: u32, shift: u32) -> vec3<f32> {
    let b = prim * 9u + k * 3u;
    var p = vec3<f32>(0.0);
    p = vec3<f32>(tris0[b], tris0[b + 1u], tris0[b + 2u]);
    return p;
}
