// Per-list atomic counters in the chunks of offsets.wgsl (counter `at` is
// word `at & mask` of chunk `at >> shift`): the counts of `fill_primitives`'
// `count`, then the cursors of its `fill`. This file is the one-chunk module;
// dirt_shaders::chunked_module writes it for more chunks, at bindings 40, 41, ...
@group(0) @binding(40) var<storage, read_write> lists0: array<atomic<u32>>;

// Adds one to counter `at` and returns what it held; the caller keeps `at`
// below the counters' count.
fn list_add(at: u32, shift: u32) -> u32 {
    let i = at;
    var old = 0u;
    old = atomicAdd(&lists0[i], 1u);
    return old;
}
