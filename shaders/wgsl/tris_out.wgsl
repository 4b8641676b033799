// The triangles as `gather` writes them: `tris.wgsl`'s chunks, writable.
// This file is the one-chunk module; dirt_shaders::chunked_module writes it
// for more chunks, at bindings 24, 25, ...
@group(0) @binding(24) var<storage, read_write> tris0: array<f32>;

// Writes vertex `k` of triangle `prim`; past the end of the chunks nothing is written.
fn tri_store(prim: u32, k: u32, shift: u32, p: vec3<f32>) {
    let b = prim * 9u + k * 3u;
    if b + 2u < arrayLength(&tris0) {
        tris0[b] = p.x;
        tris0[b + 1u] = p.y;
        tris0[b + 2u] = p.z;
    }
}
