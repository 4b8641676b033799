//! Order-preserving `f32` <-> `u32` encoding, so depth bounds can be kept with
//! integer atomic min/max (the GPU has no float atomics).

/// Maps an `f32` to a `u32` whose unsigned order is the float order
/// (`-0.0` sorts just below `+0.0`; NaN is not expected).
#[inline]
pub fn f32_to_ordered(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Inverse of [`f32_to_ordered`].
#[inline]
pub fn ordered_to_f32(u: u32) -> f32 {
    let b = if u & 0x8000_0000 != 0 {
        u & 0x7fff_ffff
    } else {
        !u
    };
    f32::from_bits(b)
}

/// Encoding of `+inf`: the identity of atomic min over depths.
pub const ORDERED_POS_INF: u32 = 0xff80_0000;
/// Encoding of `-inf`: the identity of atomic max over depths.
pub const ORDERED_NEG_INF: u32 = 0x007f_ffff;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn constants() {
        assert_eq!(f32_to_ordered(f32::INFINITY), ORDERED_POS_INF);
        assert_eq!(f32_to_ordered(f32::NEG_INFINITY), ORDERED_NEG_INF);
        assert!(f32_to_ordered(-0.0) < f32_to_ordered(0.0));
        assert!(f32_to_ordered(-f32::MIN_POSITIVE) < f32_to_ordered(-0.0));
    }

    fn finite() -> impl Strategy<Value = f32> {
        any::<u32>()
            .prop_map(f32::from_bits)
            .prop_filter("finite", |f| f.is_finite())
    }

    proptest! {
        #[test]
        fn monotonic_over_all_finite_floats(a in finite(), b in finite()) {
            if a < b {
                prop_assert!(f32_to_ordered(a) < f32_to_ordered(b));
            }
            if a == b && a.to_bits() == b.to_bits() {
                prop_assert_eq!(f32_to_ordered(a), f32_to_ordered(b));
            }
        }

        #[test]
        fn round_trips(bits in any::<u32>()) {
            let f = f32::from_bits(bits);
            prop_assume!(!f.is_nan());
            prop_assert_eq!(ordered_to_f32(f32_to_ordered(f)).to_bits(), bits);
        }

        #[test]
        fn neighbours_stay_ordered(a in finite()) {
            // The next float up always encodes to the next-or-later integer.
            let up = f32::from_bits(if a >= 0.0 { a.to_bits() + 1 } else { a.to_bits() - 1 });
            prop_assume!(up.is_finite() && a != 0.0);
            prop_assert!(f32_to_ordered(up) > f32_to_ordered(a));
        }
    }
}
