// Stage `fill_primitives`: per (view, tile, bucket) lists of primitive ids,
// sized exactly by counting. Mirrors dirt_cpu::fill_primitives in three steps:
// `count` (raster, atomic add per list), `scan_blocks` + `scan_add` (exclusive
// prefix sum of the counts, in place) and `fill` (raster, atomic cursors).
#import types
#import encode
#import bucket
#import coverage
#import ids
#import hiz
// Counts while counting; cursors (a copy of the offsets) while filling.
#import lists
#import scan_data

// The bucket range of a covered fragment, as dirt_math::bucket::bucket_range.
fn bucket_span(c: Covered) -> vec3<u32> {
    let z = hiz_cell(c.tile, params.hiz_shift);
    let zmin = ordered_to_f32(z.x);
    let zmax = ordered_to_f32(z.y);
    if !(c.hi >= zmin && c.lo <= zmax) {
        return vec3<u32>(0u, 1u, 0u); // empty: x > ... flagged by z == 0
    }
    return vec3<u32>(bucket_of(c.lo, zmin, zmax, params.buckets), bucket_of(c.hi, zmin, zmax, params.buckets), 1u);
}

// The lists (first, last) a covered fragment's triangle belongs to; z == 0 when none.
fn fragment_lists(in: CoverOut) -> vec3<u32> {
    let c = covered(in);
    if !c.ok {
        return vec3<u32>(0u, 0u, 0u);
    }
    let b = bucket_span(c);
    let base = c.tile * params.buckets;
    return vec3<u32>(base + b.x, base + b.y, b.z);
}

@fragment
fn count(in: CoverOut) {
    let l = fragment_lists(in);
    if l.z == 0u {
        return;
    }
    for (var k = l.x; k <= l.y; k++) {
        list_add(k, params.offset_shift);
    }
}

@fragment
fn fill(in: CoverOut) {
    let l = fragment_lists(in);
    if l.z == 0u {
        return;
    }
    for (var k = l.x; k <= l.y; k++) {
        let at = list_add(k, params.offset_shift);
        // A build into ids sized ahead of the count (GpuAds::encode_build) may
        // find them too small: nothing is written past their end, and the
        // trace sees offsets' total above their capacity and reports every ray.
        id_store(at, params.id_shift, in.prim);
    }
}

// Exclusive prefix sum, 256 elements per workgroup, in place; each block's
// total goes to `scan_sums` for the next level. The data are the offsets'
// chunks, or one level's sums alone in chunk 0 (with a shift that keeps them there).
struct ScanParams {
    n: u32,
    shift: u32, // elements per data chunk: 2^shift (scan_data.wgsl)
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(7) var<storage, read_write> scan_sums: array<u32>;
@group(0) @binding(8) var<uniform> scan: ScanParams;

var<workgroup> scan_shared: array<u32, 256>;

@compute @workgroup_size(256)
fn scan_blocks(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let block = wid.x + wid.y * nwg.x;
    let i = block * 256u + lid.x;
    var x = 0u;
    if i < scan.n {
        x = scan_load(i, scan.shift);
    }
    scan_shared[lid.x] = x;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off = off * 2u) {
        var y = 0u;
        if lid.x >= off {
            y = scan_shared[lid.x - off];
        }
        workgroupBarrier();
        scan_shared[lid.x] += y;
        workgroupBarrier();
    }
    if i < scan.n {
        scan_store(i, scan.shift, scan_shared[lid.x] - x);
    }
    if lid.x == 255u {
        scan_sums[block] = scan_shared[255];
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let block = wid.x + wid.y * nwg.x;
    let i = block * 256u + lid.x;
    if i < scan.n {
        scan_store(i, scan.shift, scan_load(i, scan.shift) + scan_sums[block]);
    }
}
