// Correctly rounded f32 division with integer operations only.
//
// Vulkan allows 2.5 ulp of error for a float division on the GPU, while the
// CPU's `/` is correctly rounded (IEEE-754 binary32, round to nearest, ties to
// even). So the GPU calls div_cr wherever the CPU divides with `/`, and the
// two agree to the bit (DIRT.md §3).
//
// Mirrors crates/dirt-math/src/divide.rs line for line (same variables, same
// order): keep the two in step. Only u32/i32 arithmetic and bitcast; no float
// operation touches the operands.
//
// The algorithm: handle NaN, infinities and zeros first; unpack both operands
// to 24-bit mantissas with the hidden bit (subnormals normalised, their
// exponent lowered); pre-shift the dividend so the quotient lies in [1, 2);
// restoring long division produces 26 quotient bits (1 integer bit, 25
// fraction bits) and the remainder says whether more bits are nonzero
// (sticky); then one right shift (2 bits for a normal result, more for a
// subnormal one) and a single round to nearest, ties to even, whose carry may
// ripple into the exponent (and up to infinity).

// Canonical quiet NaN, the result of every NaN-producing division.
const DIV_QNAN: u32 = 0x7fc00000u;
// Bits of +inf (also the largest non-NaN magnitude).
const DIV_INF: u32 = 0x7f800000u;

// The canonical quiet NaN as a value: from a `let`, since a constant
// expression may not evaluate to NaN (Tint refuses the shader; see f32_inf).
fn div_qnan() -> f32 {
    let bits = DIV_QNAN;
    return bitcast<f32>(bits);
}

// a / b correctly rounded (round to nearest, ties to even) with gradual
// underflow, computed with integer operations only. Bit-identical to the CPU's
// a / b, except that every NaN result is the canonical quiet NaN.
fn div_cr(a: f32, b: f32) -> f32 {
    let ua = bitcast<u32>(a);
    let ub = bitcast<u32>(b);
    let sign = (ua ^ ub) & 0x80000000u;
    let abs_a = ua & 0x7fffffffu;
    let abs_b = ub & 0x7fffffffu;

    // Special operands: NaN, infinities, zeros.
    if (abs_a > DIV_INF) | (abs_b > DIV_INF) {
        return div_qnan();
    }
    if abs_a == DIV_INF {
        if abs_b == DIV_INF {
            return div_qnan(); // inf / inf
        }
        return bitcast<f32>(sign | DIV_INF); // inf / finite
    }
    if abs_b == DIV_INF {
        return bitcast<f32>(sign); // finite / inf = ±0
    }
    if abs_b == 0u {
        if abs_a == 0u {
            return div_qnan(); // 0 / 0
        }
        return bitcast<f32>(sign | DIV_INF); // x / 0
    }
    if abs_a == 0u {
        return bitcast<f32>(sign); // 0 / x
    }

    // Unpack to 24-bit mantissas in [2^23, 2^24) and unbiased-plus-127
    // exponents; a subnormal is shifted up and its exponent lowered below 1.
    var ea = i32(abs_a >> 23u);
    var ma = abs_a & 0x007fffffu;
    if ea == 0 {
        let sh = countLeadingZeros(ma) - 8u;
        ma <<= sh;
        ea = 1 - i32(sh);
    } else {
        ma |= 0x00800000u;
    }
    var eb = i32(abs_b >> 23u);
    var mb = abs_b & 0x007fffffu;
    if eb == 0 {
        let sh = countLeadingZeros(mb) - 8u;
        mb <<= sh;
        eb = 1 - i32(sh);
    } else {
        mb |= 0x00800000u;
    }

    // Biased exponent of the quotient; make ma / mb lie in [1, 2).
    var e = ea - eb + 127;
    if ma < mb {
        ma <<= 1u; // ma < 2^25
        e -= 1;
    }
    // At least 2^128 before rounding: overflow.
    if e >= 255 {
        return bitcast<f32>(sign | DIV_INF);
    }

    // Long division in integer steps, no loop (lavapipe caps the loop
    // iterations of a whole invocation): q = floor(ma / mb * 2^25) in
    // [2^25, 2^26). The remainder stays below mb < 2^24, so r << 8 fits.
    var q = ma / mb; // 1
    var r = ma % mb;
    r <<= 8u;
    q = (q << 8u) | (r / mb);
    r %= mb;
    r <<= 8u;
    q = (q << 8u) | (r / mb);
    r %= mb;
    r <<= 8u;
    q = (q << 8u) | (r / mb);
    r %= mb;
    r <<= 1u;
    q = (q << 1u) | (r / mb);
    r %= mb;
    let sticky = r != 0u; // bits below q's last are nonzero

    // Drop s bits: 2 for a normal result (e >= 1), 2 + (1 - e) for a
    // subnormal one. Clamped to 31 (any s >= 27 rounds q < 2^26 to 0), so
    // that WGSL never shifts by 32 or more.
    let s = u32(min(2 + max(1 - e, 0), 31));
    let mant = q >> s;
    let rem = q & ((1u << s) - 1u);
    let half = 1u << (s - 1u);
    // Round to nearest, ties to even (a tie with sticky bits is above half).
    let up: u32 = select(0u, 1u, (rem > half) | ((rem == half) & (sticky | ((mant & 1u) == 1u))));
    // The mantissa's hidden bit adds 1 to the exponent field, hence e - 1; a
    // subnormal has field 0 and no hidden bit. A rounding carry ripples into
    // the exponent (at the top, into +inf).
    let base = u32(max(e - 1, 0));
    let bits = (base << 23u) + mant + up;
    return bitcast<f32>(sign | bits);
}
