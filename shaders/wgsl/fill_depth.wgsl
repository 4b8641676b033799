// Stage `fill_depth`: per view and tile, the conservative depth bounds of
// every triangle part inside the tile. Mirrors dirt_cpu::fill_depth: atomic
// min/max of order-preserving encodings, [enc(zmin), enc(zmax)] per tile.
#import types
#import encode
#import coverage

@group(0) @binding(3) var<storage, read_write> depth: array<atomic<u32>>;

@fragment
fn fill_depth(in: CoverOut) {
    let c = covered(in);
    if c.ok {
        atomicMin(&depth[2u * c.tile], f32_to_ordered(c.lo));
        atomicMax(&depth[2u * c.tile + 1u], f32_to_ordered(c.hi));
    }
}
