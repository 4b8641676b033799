// Order-preserving f32 <-> u32 encoding, so depth bounds can be kept with
// integer atomic min/max (the GPU has no float atomics).
//
// Mirrors crates/dirt-math/src/encode.rs operation for operation: keep the two
// in step (a GPU test compares them bit for bit through selftest_encode.wgsl).

// Encoding of +inf: the identity of atomic min over depths.
const ORDERED_POS_INF: u32 = 0xff800000u;
// Encoding of -inf: the identity of atomic max over depths.
const ORDERED_NEG_INF: u32 = 0x007fffffu;

// Maps an f32 to a u32 whose unsigned order is the float order
// (-0.0 sorts just below +0.0; NaN is not expected).
fn f32_to_ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    if (b & 0x80000000u) != 0u {
        return ~b;
    } else {
        return b | 0x80000000u;
    }
}

// Inverse of f32_to_ordered.
fn ordered_to_f32(u: u32) -> f32 {
    var b: u32;
    if (u & 0x80000000u) != 0u {
        b = u & 0x7fffffffu;
    } else {
        b = ~u;
    }
    return bitcast<f32>(b);
}
