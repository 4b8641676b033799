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

/// `floor(x)` clamped to `[0, last]` as an index (NaN gives 0).
#[inline]
pub fn floor_index(x: f32, last: u32) -> u32 {
    let f = x.floor();
    if f >= last as f32 {
        last
    } else if f >= 0.0 {
        f as u32
    } else {
        0
    }
}
