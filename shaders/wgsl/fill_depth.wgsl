// Stage `fill_depth`: per view and tile, the conservative depth bounds of
// every triangle part inside the tile. Mirrors dirt_cpu::fill_depth: atomic
// min/max of order-preserving encodings, [enc(zmin), enc(zmax)] per tile.
#import types
#import encode
#import coverage
#import hiz_atomic

@fragment
fn fill_depth(in: CoverOut) {
    let c = covered(in);
    if c.ok {
        hiz_widen(c.tile, params.hiz_shift, f32_to_ordered(c.lo), f32_to_ordered(c.hi));
    }
}

// Before a build recorded into an encoder: every cell of every Hi-Z level
// empty, [enc(+inf), enc(-inf)] (what dirt_cpu::fill_depth starts from);
// cells past the pyramid's chunks are not written.
@compute @workgroup_size(64)
fn clear_depth(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let cell = gid.x + gid.y * nwg.x * 64u;
    hiz_set(cell, params.hiz_shift, vec2<u32>(ORDERED_POS_INF, ORDERED_NEG_INF));
}
