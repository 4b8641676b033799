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

// Before a build recorded into an encoder: every cell of every Hi-Z level
// empty, [enc(+inf), enc(-inf)] (what dirt_cpu::fill_depth starts from).
@compute @workgroup_size(64)
fn clear_depth(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let cell = gid.x + gid.y * nwg.x * 64u;
    if 2u * cell + 1u < arrayLength(&depth) {
        atomicStore(&depth[2u * cell], ORDERED_POS_INF);
        atomicStore(&depth[2u * cell + 1u], ORDERED_NEG_INF);
    }
}
