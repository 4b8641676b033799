// Stage `mip_depth`: one Hi-Z level from the one below (min of mins, max of
// maxes per 2x2 block, cut at the grid's edge). Mirrors dirt_cpu::mip_depth.

// dirt_gpu::MipParams
struct MipParams {
    src_base: u32,
    dst_base: u32,
    src_w: u32,
    dst_w: u32,
}

@group(0) @binding(0) var<storage, read_write> hiz: array<u32>;
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
            lo = min(lo, hiz[2u * s]);
            hi = max(hi, hiz[2u * s + 1u]);
        }
    }
    let d = mip.dst_base + slot * w * w + j * w + i;
    hiz[2u * d] = lo;
    hiz[2u * d + 1u] = hi;
}
