// The Hi-Z pyramid (every level, the depth bounds first; two u32 per cell:
// enc(zmin), enc(zmax)), split across bindings so that no single binding
// limits a structure's resolution (dirt_gpu's Hi-Z chunks): cell `cell` is
// cell `cell & mask` of chunk `cell >> shift`, each chunk 2^shift cells.
// This file is the one-chunk module for the stages that read it;
// dirt_shaders::chunked_module writes it for more chunks, at bindings 32, 33, ...
@group(0) @binding(32) var<storage, read> hiz0: array<u32>;

// Cell `cell`: (enc(zmin), enc(zmax)); the caller keeps `cell` below the cells.
fn hiz_cell(cell: u32, shift: u32) -> vec2<u32> {
    let i = 2u * cell;
    var z = vec2<u32>(0u);
    z = vec2<u32>(hiz0[i], hiz0[i + 1u]);
    return z;
}
