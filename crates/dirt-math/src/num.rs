//! Float helpers with one fixed meaning on every device. `f32::min`/`max`
//! may return either zero for `(-0.0, 0.0)` and WGSL's `min`/`max` leave NaN
//! handling to the implementation; these are plain comparisons that WGSL
//! writes as `select`, so both sides pick the same bits.

/// `b` if `b < a`, else `a`.
#[inline]
pub fn fmin(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// `b` if `b > a`, else `a`.
#[inline]
pub fn fmax(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

/// `floor(x)` clamped to `[0, last]` as an index (NaN gives 0), without
/// `floor` (the x86-64 baseline has no rounding instruction, so it is a
/// call): `floor(x) >= L` is `x >= L` for the integer `L = last as f32`, and
/// below it `floor` and truncation agree on `x >= 0`.
#[inline]
pub fn floor_index(x: f32, last: u32) -> u32 {
    if x >= 0.0 {
        if x >= last as f32 { last } else { x as u32 }
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition [`floor_index`] must equal.
    fn floor_plain(x: f32, last: u32) -> u32 {
        let f = x.floor();
        if f >= last as f32 {
            last
        } else if f >= 0.0 {
            f as u32
        } else {
            0
        }
    }

    #[test]
    fn floor_index_is_the_plain_one() {
        let last = [0u32, 1, 7, 127, 4095, (1 << 24) - 1, u32::MAX];
        let mut xs = vec![
            0.0f32,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            1e-45,
            -1e-45,
        ];
        for k in -300..300 {
            let x = k as f32 * 0.5;
            xs.extend([x, x.next_up(), x.next_down()]);
        }
        for e in 0..40 {
            let x = (2.0f32).powi(e);
            xs.extend([x, x.next_up(), x.next_down(), -x]);
        }
        for &x in &xs {
            for &l in &last {
                assert_eq!(
                    floor_index(x, l),
                    floor_plain(x, l),
                    "x = {x:e}, last = {l}"
                );
            }
        }
    }
}
