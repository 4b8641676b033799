//! Correctly rounded `f32` division with integer operations only.
//!
//! Vulkan allows 2.5 ulp of error for a float division on the GPU, while the
//! CPU's `/` is correctly rounded (IEEE-754 binary32, round to nearest, ties to
//! even). So the GPU calls `div_cr` wherever the CPU divides with `/`, and the
//! two agree to the bit (DIRT.md §3). [`div_cr`] is the executable
//! specification of `shaders/wgsl/divide.wgsl`, which mirrors it line for
//! line: same variables, same order, only `u32`/`i32` arithmetic and bit
//! reinterpretation (`to_bits`/`from_bits` here, `bitcast` there).
//!
//! The algorithm: handle NaN, infinities and zeros first; unpack both
//! operands to 24-bit mantissas with the hidden bit (subnormals normalised,
//! their exponent lowered); pre-shift the dividend so the quotient lies in
//! [1, 2); restoring long division produces 26 quotient bits (1 integer bit,
//! 25 fraction bits) and the remainder says whether more bits are nonzero
//! (sticky); then one right shift (2 bits for a normal result, more for a
//! subnormal one) and a single round to nearest, ties to even, whose carry may
//! ripple into the exponent (and up to infinity).

/// Canonical quiet NaN, the result of every NaN-producing division.
const DIV_QNAN: u32 = 0x7fc0_0000;
/// Bits of `+inf` (also the largest non-NaN magnitude).
const DIV_INF: u32 = 0x7f80_0000;

/// `a / b` correctly rounded (round to nearest, ties to even) with gradual
/// underflow, computed with integer operations only. Bit-identical to Rust's
/// `a / b`, except that every NaN result is the canonical quiet NaN.
#[inline]
pub fn div_cr(a: f32, b: f32) -> f32 {
    let ua = a.to_bits();
    let ub = b.to_bits();
    let sign = (ua ^ ub) & 0x8000_0000;
    let abs_a = ua & 0x7fff_ffff;
    let abs_b = ub & 0x7fff_ffff;

    // Special operands: NaN, infinities, zeros.
    if abs_a > DIV_INF || abs_b > DIV_INF {
        return f32::from_bits(DIV_QNAN);
    }
    if abs_a == DIV_INF {
        if abs_b == DIV_INF {
            return f32::from_bits(DIV_QNAN); // inf / inf
        }
        return f32::from_bits(sign | DIV_INF); // inf / finite
    }
    if abs_b == DIV_INF {
        return f32::from_bits(sign); // finite / inf = ±0
    }
    if abs_b == 0 {
        if abs_a == 0 {
            return f32::from_bits(DIV_QNAN); // 0 / 0
        }
        return f32::from_bits(sign | DIV_INF); // x / 0
    }
    if abs_a == 0 {
        return f32::from_bits(sign); // 0 / x
    }

    // Unpack to 24-bit mantissas in [2^23, 2^24) and unbiased-plus-127
    // exponents; a subnormal is shifted up and its exponent lowered below 1.
    let mut ea = (abs_a >> 23) as i32;
    let mut ma = abs_a & 0x007f_ffff;
    if ea == 0 {
        let sh = ma.leading_zeros() - 8;
        ma <<= sh;
        ea = 1 - sh as i32;
    } else {
        ma |= 0x0080_0000;
    }
    let mut eb = (abs_b >> 23) as i32;
    let mut mb = abs_b & 0x007f_ffff;
    if eb == 0 {
        let sh = mb.leading_zeros() - 8;
        mb <<= sh;
        eb = 1 - sh as i32;
    } else {
        mb |= 0x0080_0000;
    }

    // Biased exponent of the quotient; make ma / mb lie in [1, 2).
    let mut e = ea - eb + 127;
    if ma < mb {
        ma <<= 1; // ma < 2^25
        e -= 1;
    }
    // At least 2^128 before rounding: overflow.
    if e >= 255 {
        return f32::from_bits(sign | DIV_INF);
    }

    // Long division in integer steps, no loop (a software GPU caps the loop
    // iterations of a whole invocation): q = floor(ma / mb * 2^25) in
    // [2^25, 2^26). The remainder stays below mb < 2^24, so r << 8 fits.
    let mut q = ma / mb; // 1
    let mut r = ma % mb;
    r <<= 8;
    q = (q << 8) | (r / mb);
    r %= mb;
    r <<= 8;
    q = (q << 8) | (r / mb);
    r %= mb;
    r <<= 8;
    q = (q << 8) | (r / mb);
    r %= mb;
    r <<= 1;
    q = (q << 1) | (r / mb);
    r %= mb;
    let sticky = r != 0; // bits below q's last are nonzero

    // Drop s bits: 2 for a normal result (e >= 1), 2 + (1 - e) for a
    // subnormal one. Clamped to 31 (any s >= 27 rounds q < 2^26 to 0), so
    // that WGSL never shifts by 32 or more.
    let s = i32::min(2 + i32::max(1 - e, 0), 31) as u32;
    let mant = q >> s;
    let rem = q & ((1 << s) - 1);
    let half = 1 << (s - 1);
    // Round to nearest, ties to even (a tie with sticky bits is above half).
    let up: u32 = if rem > half || (rem == half && (sticky || (mant & 1) == 1)) {
        1
    } else {
        0
    };
    // The mantissa's hidden bit adds 1 to the exponent field, hence e - 1; a
    // subnormal has field 0 and no hidden bit. A rounding carry ripples into
    // the exponent (at the top, into +inf).
    let base = i32::max(e - 1, 0) as u32;
    let bits = (base << 23) + mant + up;
    f32::from_bits(sign | bits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Compares `div_cr(a, b)` with `a / b`: NaN-ness for NaN, bits otherwise.
    fn check(a: f32, b: f32) {
        let want = a / b;
        let got = div_cr(a, b);
        if want.is_nan() {
            assert!(
                got.is_nan(),
                "{a:e} ({:#010x}) / {b:e} ({:#010x}): want NaN, got {got:e} ({:#010x})",
                a.to_bits(),
                b.to_bits(),
                got.to_bits()
            );
            assert_eq!(got.to_bits(), DIV_QNAN, "NaN results are canonical");
        } else {
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "{a:e} ({:#010x}) / {b:e} ({:#010x}): want {want:e}, got {got:e}",
                a.to_bits(),
                b.to_bits()
            );
        }
    }

    /// Small deterministic PCG32 (O'Neill's pcg32, XSH RR output).
    struct Pcg32 {
        state: u64,
    }

    impl Pcg32 {
        fn new(seed: u64) -> Self {
            let mut g = Pcg32 { state: 0 };
            g.next_u32();
            g.state = g.state.wrapping_add(seed);
            g.next_u32();
            g
        }

        fn next_u32(&mut self) -> u32 {
            let old = self.state;
            self.state = old
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
            let rot = (old >> 59) as u32;
            xorshifted.rotate_right(rot)
        }

        /// Uniform in `lo..=hi` (slightly biased; fine for tests).
        fn range(&mut self, lo: i32, hi: i32) -> i32 {
            lo + (self.next_u32() % (hi - lo + 1) as u32) as i32
        }
    }

    const SPECIALS: [u32; 8] = [
        0x0000_0000, // 0
        0x0000_0001, // min subnormal
        0x007f_ffff, // max subnormal
        0x0080_0000, // min normal
        0x3f80_0000, // 1
        0x7f7f_ffff, // max finite
        0x7f80_0000, // inf
        0x7fc0_0000, // NaN
    ];

    #[test]
    fn special_values_pairwise() {
        let mut vals = Vec::new();
        for s in SPECIALS {
            vals.push(s);
            vals.push(s | 0x8000_0000);
        }
        // A few neighbours of the specials and other edge operands too.
        vals.extend([
            0x0000_0002,
            0x0040_0000,
            0x0040_0001,
            0x007f_fffe,
            0x0080_0001,
            0x3f7f_ffff,
            0x3f80_0001,
            0x4000_0000,
            0x3f00_0000,
            0x4040_0000,
            0x7f7f_fffe,
            0x7f00_0000,
            0x0100_0000,
            0x7f80_0001, // signalling NaN
            0xffc0_0000,
            0xffff_ffff,
        ]);
        let mut n = 0;
        for &x in &vals {
            for &y in &vals {
                check(f32::from_bits(x), f32::from_bits(y));
                n += 1;
            }
        }
        assert_eq!(n, vals.len() * vals.len());
        // Spot checks of the contract itself.
        assert!(div_cr(0.0, 0.0).is_nan());
        assert!(div_cr(f32::INFINITY, f32::NEG_INFINITY).is_nan());
        assert_eq!(div_cr(-1.0, 0.0), f32::NEG_INFINITY);
        assert_eq!(div_cr(1.0, -0.0), f32::NEG_INFINITY);
        assert_eq!(div_cr(-1.0, f32::INFINITY).to_bits(), 0x8000_0000);
        assert_eq!(div_cr(f32::MAX, 0.5), f32::INFINITY);
        assert_eq!(div_cr(1.0, 3.0), 1.0 / 3.0);
    }

    #[test]
    fn random_bit_patterns() {
        let mut g = Pcg32::new(0x5eed_d1f1);
        for _ in 0..2_000_000 {
            let a = f32::from_bits(g.next_u32());
            let b = f32::from_bits(g.next_u32());
            check(a, b);
        }
    }

    /// Random operands whose quotient's exponent lies near the bottom
    /// (subnormal results, underflow to zero) or the top (overflow) of the
    /// range; subnormal operands included (exponent field 0).
    #[test]
    fn random_subnormal_and_overflow_results() {
        let mut g = Pcg32::new(0xd1f1_0000_0002);
        let (mut subnormal, mut zero, mut inf, mut n) = (0, 0, 0, 0);
        while n < 1_000_000 {
            let eb = g.range(0, 254);
            // Biased exponent of the quotient: -30..=3 (subnormal), or
            // 250..=258 (overflow).
            let eq = if g.next_u32() & 1 == 0 {
                g.range(-30, 3)
            } else {
                g.range(250, 258)
            };
            let ea = eq + eb - 127;
            if !(0..=254).contains(&ea) {
                continue;
            }
            let ua = (g.next_u32() & 0x8000_0000) | ((ea as u32) << 23) | (g.next_u32() >> 9);
            let ub = (g.next_u32() & 0x8000_0000) | ((eb as u32) << 23) | (g.next_u32() >> 9);
            let (a, b) = (f32::from_bits(ua), f32::from_bits(ub));
            check(a, b);
            let want = a / b;
            subnormal += usize::from(want.is_subnormal());
            zero += usize::from(want == 0.0);
            inf += usize::from(want.is_infinite());
            n += 1;
        }
        // The bias works: plenty of each kind of result.
        assert!(subnormal > 200_000, "subnormal results: {subnormal}");
        assert!(zero > 20_000, "zero results: {zero}");
        assert!(inf > 100_000, "infinite results: {inf}");
    }

    /// Exact ties occur only for subnormal results: divisors that are powers
    /// of two (and small multiples of them) make them common.
    #[test]
    fn ties_in_subnormal_results() {
        let mut g = Pcg32::new(77);
        for k in 0..=254u32 {
            for m in [0u32, 0x0040_0000, 0x0020_0000, 0x0060_0000] {
                let b = f32::from_bits((k << 23) | m);
                for _ in 0..500 {
                    // Small-exponent dividends, subnormal ones included.
                    let ua = (g.next_u32() & 0x8000_0000) | (g.next_u32() & 0x0fff_ffff);
                    check(f32::from_bits(ua), b);
                    check(f32::from_bits(ua), -b);
                }
            }
        }
        assert_eq!(div_cr(f32::from_bits(1), 2.0).to_bits(), 0); // tie to even: 0
        assert_eq!(div_cr(f32::from_bits(3), 2.0).to_bits(), 2); // tie to even: 2
        assert_eq!(div_cr(f32::from_bits(3), 4.0).to_bits(), 1); // 0.75 rounds up
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        #[test]
        fn matches_hardware_division(ua in any::<u32>(), ub in any::<u32>()) {
            let (a, b) = (f32::from_bits(ua), f32::from_bits(ub));
            let want = a / b;
            let got = div_cr(a, b);
            if want.is_nan() {
                prop_assert!(got.is_nan());
            } else {
                prop_assert_eq!(got.to_bits(), want.to_bits());
            }
        }
    }
}
