//! Depth buckets of a tile (001 eq. 1): `b = floor(B * (z - zmin) / (zmax - zmin))`,
//! clamped to `[0, B-1]`.
//!
//! The division is only an estimate; the bucket is then fixed up with
//! multiplications and comparisons, which every Vulkan implementation rounds
//! correctly. The result is exactly `max { k in 0..B : fl(k * range) <= fl((z - zmin) * B) }`,
//! so the CPU and a GPU get the same bucket for the same bits, and the map is
//! monotonic in `z` (both sides of the comparison are monotonic roundings).
//! For up to [`COUNTED`] buckets the CPU counts those `k` instead (the set is
//! `0..=K`, as `fl(k * range)` does not fall as `k` grows): the same bucket,
//! without a division or a data-dependent branch.

/// Bucket of depth `z` in a tile with depth bounds `[zmin, zmax]` and `buckets` buckets.
#[inline]
pub fn bucket_of(z: f32, zmin: f32, zmax: f32, buckets: u32) -> u32 {
    if buckets <= 1 {
        return 0;
    }
    let range = zmax - zmin;
    let x = (z - zmin) * buckets as f32;
    if !(range > 0.0) || !(x > 0.0) {
        return 0;
    }
    if buckets <= COUNTED {
        return counted(x, range, buckets);
    }
    estimated(x, range, buckets)
}

/// Most buckets [`bucket_of`] counts ([`counted`]) rather than estimates:
/// `B − 1` products and comparisons cost less than a division and its
/// fix-up (the deforming grid's build at B = 2: `fill_primitives` 1.26 ->
/// 1.11 ms on 1 thread; cornell's trace at B = 8: 603 -> 591 ns a ray).
pub const COUNTED: u32 = 16;

/// `#{ k in 1..B : fl(k * range) <= x }`, which is [`bucket_of`]'s bucket
/// for `x = fl((z − zmin)·B) > 0` and `range > 0`.
#[inline]
fn counted(x: f32, range: f32, buckets: u32) -> u32 {
    let mut k = 0;
    for j in 1..buckets {
        k += u32::from(j as f32 * range <= x);
    }
    k
}

/// [`bucket_of`]'s bucket from the division's estimate, fixed up (what the
/// WGSL passes compute for any `B`).
#[inline]
fn estimated(x: f32, range: f32, buckets: u32) -> u32 {
    let last = buckets - 1;
    let est = x / range;
    let mut k = if est >= last as f32 {
        last
    } else if est >= 0.0 {
        est as u32
    } else {
        0
    };
    while k > 0 && k as f32 * range > x {
        k -= 1;
    }
    while k < last && (k + 1) as f32 * range <= x {
        k += 1;
    }
    k
}

/// `(bucket_of(lo, ..), bucket_of(hi, ..))`, the same two buckets. For up to
/// [`COUNTED`] buckets both ends are counted together as lanes, the products
/// `fl(j·range)` computed once for both (a walk takes a tile's bucket range
/// so at every tile it searches).
#[inline]
pub fn bucket_pair(lo: f32, hi: f32, zmin: f32, zmax: f32, buckets: u32) -> (u32, u32) {
    if buckets <= 1 {
        return (0, 0);
    }
    if buckets > COUNTED {
        return (
            bucket_of(lo, zmin, zmax, buckets),
            bucket_of(hi, zmin, zmax, buckets),
        );
    }
    let range = zmax - zmin;
    if !(range > 0.0) {
        return (0, 0);
    }
    let b = buckets as f32;
    let (x0, x1) = ((lo - zmin) * b, (hi - zmin) * b);
    // `bucket_of` returns 0 for `x <= 0` and NaN without counting; counted,
    // such an `x` is below every `fl(j·range) > 0` and compares false, so
    // the count is 0 all the same. As few lanes as the count needs: with
    // one for two buckets, not eight, the deforming grid's build (single
    // r128 B2, 1 thread) took 51.8 M -> 47.4 M instructions.
    match buckets {
        2 => counted_pair::<1>(x0, x1, range, buckets),
        3..=4 => counted_pair::<4>(x0, x1, range, buckets),
        5..=8 => counted_pair::<8>(x0, x1, range, buckets),
        _ => counted_pair::<{ COUNTED as usize }>(x0, x1, range, buckets),
    }
}

/// [`counted`] of `x0` and of `x1` (`buckets <= N`), over `N` lanes: lane
/// `q` compares `fl((q + 1)·range)`, the same product as `counted`'s
/// `j as f32 * range` for `j = q + 1` (an exact `f32`), and lanes from
/// `buckets − 1` on count nothing.
#[inline(always)]
fn counted_pair<const N: usize>(x0: f32, x1: f32, range: f32, buckets: u32) -> (u32, u32) {
    // Plain loops over `N`, unrolled: `array::from_fn` was left out of
    // line once `bucket_pair` had several `N`.
    let (mut c0, mut c1) = (0, 0);
    for q in 0..N {
        let p = (q + 1) as f32 * range;
        let live = (q as u32) < buckets - 1;
        c0 += u32::from(live & (p <= x0));
        c1 += u32::from(live & (p <= x1));
    }
    (c0, c1)
}

/// Inclusive bucket range covered by the depth interval `[z0, z1]` (`z0 <= z1`),
/// or `None` when it misses `[zmin, zmax]`.
#[inline]
pub fn bucket_range(z0: f32, z1: f32, zmin: f32, zmax: f32, buckets: u32) -> Option<(u32, u32)> {
    if !(z1 >= zmin && z0 <= zmax) {
        return None;
    }
    Some(bucket_pair(z0, z1, zmin, zmax, buckets))
}

/// A depth no larger than any depth whose bucket is `>= k`: where the ray enters
/// bucket `k` when it moves to larger depths. Rounded down generously so that the
/// early exit built on it can never skip a closer hit.
#[inline]
pub fn bucket_floor_depth(k: u32, zmin: f32, zmax: f32, buckets: u32) -> f32 {
    if k == 0 || buckets <= 1 {
        return f32::NEG_INFINITY;
    }
    let range = zmax - zmin;
    // True boundary is zmin + k*range/B; every rounding on the way is far below 2^-10 of range.
    zmin + range * (k as f32 / buckets as f32) - range * (1.0 / 1024.0)
}

/// A depth no smaller than any depth whose bucket is `<= k`: where the ray enters
/// bucket `k` when it moves to smaller depths.
#[inline]
pub fn bucket_ceil_depth(k: u32, zmin: f32, zmax: f32, buckets: u32) -> f32 {
    if k + 1 >= buckets {
        return f32::INFINITY;
    }
    let range = zmax - zmin;
    zmin + range * ((k + 1) as f32 / buckets as f32) + range * (1.0 / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn ends_and_clamps() {
        assert_eq!(bucket_of(0.0, 0.0, 1.0, 8), 0);
        assert_eq!(bucket_of(1.0, 0.0, 1.0, 8), 7);
        assert_eq!(bucket_of(0.5, 0.0, 1.0, 8), 4);
        assert_eq!(bucket_of(-5.0, 0.0, 1.0, 8), 0);
        assert_eq!(bucket_of(5.0, 0.0, 1.0, 8), 7);
        assert_eq!(bucket_of(3.0, 3.0, 3.0, 8), 0);
        assert_eq!(bucket_range(2.0, 3.0, 0.0, 1.0, 8), None);
        assert_eq!(bucket_range(-1.0, 0.3, 0.0, 1.0, 4), Some((0, 1)));
    }

    proptest! {
        #[test]
        fn monotonic_and_in_range(zmin in -1e4f32..1e4, span in 0.0f32..1e4, a in 0.0f32..1.0, b in 0.0f32..1.0, buckets in 1u32..64) {
            let zmax = zmin + span;
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let z0 = zmin - span * 0.1 + lo * span * 1.2;
            let z1 = zmin - span * 0.1 + hi * span * 1.2;
            let b0 = bucket_of(z0, zmin, zmax, buckets);
            let b1 = bucket_of(z1, zmin, zmax, buckets);
            prop_assert!(b0 <= b1);
            prop_assert!(b1 < buckets);
        }

        #[test]
        fn matches_the_formula_away_from_boundaries(zmin in -100.0f32..100.0, span in 0.01f32..100.0, f in 0.0f32..1.0, buckets in 1u32..64) {
            let zmax = zmin + span;
            let z = zmin + f * span;
            let exact = ((z as f64 - zmin as f64) * buckets as f64 / (zmax as f64 - zmin as f64)).floor();
            let frac = (z as f64 - zmin as f64) * buckets as f64 / (zmax as f64 - zmin as f64) - exact;
            prop_assume!(frac > 1e-4 && frac < 1.0 - 1e-4);
            let expect = (exact as i64).clamp(0, buckets as i64 - 1) as u32;
            prop_assert_eq!(bucket_of(z, zmin, zmax, buckets), expect);
        }

        /// Counting and the estimate agree wherever [`bucket_of`] counts,
        /// on any bits: depths near bucket boundaries, tiny and huge ranges,
        /// infinities.
        #[test]
        fn counting_is_the_estimate(x in prop_oneof![
            4 => 0.0f32..64.0,
            1 => any::<f32>().prop_filter("positive", |x| *x > 0.0),
            1 => Just(f32::INFINITY),
        ], range in prop_oneof![
            4 => 0.0f32..8.0,
            1 => any::<f32>().prop_filter("positive", |r| *r > 0.0 && r.is_finite()),
            1 => Just(f32::MIN_POSITIVE),
            1 => Just(f32::MAX),
        ], k in 0u32..17, nudge in -2i32..3, buckets in 2u32..=COUNTED) {
            prop_assume!(x > 0.0 && range > 0.0);
            // x on or next to a boundary k·range, where rounding decides.
            let edge = k as f32 * range;
            let x = if k > 0 && edge.is_finite() && edge > 0.0 {
                f32::from_bits((edge.to_bits() as i32 + nudge) as u32)
            } else {
                x
            };
            prop_assume!(x > 0.0);
            prop_assert_eq!(counted(x, range, buckets), estimated(x, range, buckets));
        }

        /// Both ends at once are each end's own bucket, on any bits:
        /// depths at and beside bucket boundaries, outside the bounds,
        /// infinities and NaN, empty and flat bounds, every bucket count
        /// either way of [`COUNTED`].
        #[test]
        fn a_pair_is_each_ends_bucket(zmin in prop_oneof![
            4 => -100.0f32..100.0,
            1 => any::<f32>(),
        ], span in prop_oneof![
            4 => 0.0f32..100.0,
            1 => any::<f32>(),
            1 => Just(f32::MIN_POSITIVE),
        ], f in prop::array::uniform2(prop_oneof![
            4 => -0.2f32..1.2,
            1 => any::<f32>(),
            1 => Just(f32::INFINITY),
            1 => Just(f32::NEG_INFINITY),
        ]), k in prop::array::uniform2(0u32..34), nudge in prop::array::uniform2(-2i32..3), buckets in 0u32..34) {
            let zmax = zmin + span;
            let nb = buckets.max(1) as f32;
            // Each end either anywhere or on or beside a boundary zmin + k·span/B.
            let at = |c: usize| {
                if k[c] <= buckets {
                    let edge = zmin + k[c] as f32 * (span / nb);
                    f32::from_bits((edge.to_bits() as i32).wrapping_add(nudge[c]) as u32)
                } else {
                    zmin + f[c] * span
                }
            };
            let (lo, hi) = (at(0), at(1));
            prop_assert_eq!(
                bucket_pair(lo, hi, zmin, zmax, buckets),
                (bucket_of(lo, zmin, zmax, buckets), bucket_of(hi, zmin, zmax, buckets))
            );
        }

        #[test]
        fn boundary_depths_are_conservative(zmin in -100.0f32..100.0, span in 0.001f32..100.0, f in 0.0f32..1.0, buckets in 2u32..64) {
            let zmax = zmin + span;
            let z = zmin + f * span;
            let k = bucket_of(z, zmin, zmax, buckets);
            prop_assert!(bucket_floor_depth(k, zmin, zmax, buckets) <= z);
            prop_assert!(bucket_ceil_depth(k, zmin, zmax, buckets) >= z);
        }
    }
}
