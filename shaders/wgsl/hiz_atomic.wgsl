// The Hi-Z pyramid as `fill_depth` widens it: the chunks of hiz.wgsl (cell
// `cell & mask` of chunk `cell >> shift`), as atomics. This file is the
// one-chunk module; dirt_shaders::chunked_module writes it for more chunks,
// at bindings 32, 33, ...
@group(0) @binding(32) var<storage, read_write> hiz0: array<atomic<u32>>;

// Widens cell `cell` to hold [lo, hi] (encoded: atomic min and max); the
// caller keeps `cell` below the cells.
fn hiz_widen(cell: u32, shift: u32, lo: u32, hi: u32) {
    let i = 2u * cell;
    atomicMin(&hiz0[i], lo);
    atomicMax(&hiz0[i + 1u], hi);
}

// Sets cell `cell`; past the end of the chunks nothing is written.
fn hiz_set(cell: u32, shift: u32, z: vec2<u32>) {
    let i = 2u * cell;
    if i + 1u < arrayLength(&hiz0) {
        atomicStore(&hiz0[i], z.x);
        atomicStore(&hiz0[i + 1u], z.y);
    }
}
