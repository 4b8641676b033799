// Self-test kernel used by the GPU tests: runs encode.wgsl's f32_to_ordered
// over a buffer so its output can be compared bit for bit with
// dirt_math::encode::f32_to_ordered. Not a pipeline stage.
//
// Entry point `main`, workgroup size 64, one invocation per element:
//   @group(0) @binding(0) selftest_in:  array<f32>, read-only storage
//   @group(0) @binding(1) selftest_out: array<u32>, read-write storage
// Elements past the shorter of the two arrays are left alone.

#import encode

@group(0) @binding(0) var<storage, read> selftest_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> selftest_out: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < arrayLength(&selftest_in) && i < arrayLength(&selftest_out) {
        selftest_out[i] = f32_to_ordered(selftest_in[i]);
    }
}
