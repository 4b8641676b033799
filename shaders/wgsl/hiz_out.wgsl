// The Hi-Z pyramid as `mip_depth` reads and writes it: the chunks of hiz.wgsl
// (cell `cell & mask` of chunk `cell >> shift`), read-write. This file is the
// one-chunk module; dirt_shaders::chunked_module writes it for more chunks,
// at bindings 32, 33, ...
@group(0) @binding(32) var<storage, read_write> hiz0: array<u32>;

// Cell `cell`: (enc(zmin), enc(zmax)); the caller keeps `cell` below the cells.
fn hiz_cell(cell: u32, shift: u32) -> vec2<u32> {
    let i = 2u * cell;
    var z = vec2<u32>(0u);
    z = vec2<u32>(hiz0[i], hiz0[i + 1u]);
    return z;
}

// Writes cell `cell`; the caller keeps `cell` below the cells.
fn hiz_store(cell: u32, shift: u32, z: vec2<u32>) {
    let i = 2u * cell;
    hiz0[i] = z.x;
    hiz0[i + 1u] = z.y;
}
