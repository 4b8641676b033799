// The data of `fill_primitives`' prefix sum, in the chunks of offsets.wgsl
// (element `at` is word `at & mask` of chunk `at >> shift`): the counts,
// summed in place into offsets, or one level's block sums (in chunk 0, with a
// shift that keeps every index there). This file is the one-chunk module;
// dirt_shaders::chunked_module writes it for more chunks, at bindings 48, 49, ...
@group(0) @binding(48) var<storage, read_write> scan_data0: array<u32>;

// Element `at`; the caller keeps `at` below the count.
fn scan_load(at: u32, shift: u32) -> u32 {
    let i = at;
    var x = 0u;
    x = scan_data0[i];
    return x;
}

// Writes element `at`; the caller keeps `at` below the count.
fn scan_store(at: u32, shift: u32, x: u32) {
    let i = at;
    scan_data0[i] = x;
}
