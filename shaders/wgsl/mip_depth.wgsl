// Stage `mip_depth`: one Hi-Z level from the one below (min of mins, max of
// maxes per 2x2 block, cut at the grid's edge). Mirrors dirt_cpu::mip_depth.
#import hiz_out

// dirt_gpu::MipParams
struct MipParams {
    src_base: u32,
    dst_base: u32,
    src_w: u32,
    dst_w: u32,
    shift: u32, // Hi-Z cells per chunk: 2^shift (hiz.wgsl)
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(1) var<uniform> mip: MipParams;

@compute @workgroup_size(8, 8)
fn mip_depth(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let j = gid.y;
    let slot = gid.z; // views with content only: one block each
    let w = mip.dst_w;
    let sw = mip.src_w;
    if i >= w || j >= w {
        return;
    }
    var lo = 0xff800000u;
    var hi = 0x007fffffu;
    for (var k = 0u; k < 4u; k++) {
        let si = 2u * i + (k & 1u);
        let sj = 2u * j + (k >> 1u);
        if si < sw && sj < sw {
            let s = mip.src_base + slot * sw * sw + sj * sw + si;
            let z = hiz_cell(s, mip.shift);
            lo = min(lo, z.x);
            hi = max(hi, z.y);
        }
    }
    let d = mip.dst_base + slot * w * w + j * w + i;
    hiz_store(d, mip.shift, vec2<u32>(lo, hi));
}
