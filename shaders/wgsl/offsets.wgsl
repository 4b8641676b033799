// The list offsets (slots·tiles²·B + 1 u32: list `l` is ids offsets[l] ..
// offsets[l + 1]), split across bindings so that no single binding limits a
// structure's resolution or buckets (dirt_gpu's offset chunks): offset `at`
// is word `at & mask` of chunk `at >> shift`, each chunk 2^shift words. This
// file is the one-chunk module for the trace, which reads them;
// dirt_shaders::chunked_module writes it for more chunks, at bindings 40, 41, ...
@group(0) @binding(40) var<storage, read> offsets0: array<u32>;

// Offset `at`; the caller keeps `at` below the offsets' count.
fn offset_load(at: u32, shift: u32) -> u32 {
    let i = at;
    var o = 0u;
    o = offsets0[i];
    return o;
}
