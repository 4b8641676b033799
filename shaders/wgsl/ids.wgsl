// The list ids, split across bindings so that no single binding limits how
// many a structure holds (dirt_gpu's id chunks): entry `at` is word
// `at & mask` of chunk `at >> shift`, each chunk 2^shift words. This file is
// the one-chunk module; dirt_shaders::chunked_module writes it for more
// chunks, at bindings 16, 17, ...
@group(0) @binding(16) var<storage, read_write> ids0: array<u32>;

// Entry `at`; the caller keeps `at` below the ids' capacity.
fn id_load(at: u32, shift: u32) -> u32 {
    let i = at;
    var id = 0u;
    id = ids0[i];
    return id;
}

// Writes entry `at`; past the end of the chunks nothing is written.
fn id_store(at: u32, shift: u32, id: u32) {
    let i = at;
    if i < arrayLength(&ids0) {
        ids0[i] = id;
    }
}
