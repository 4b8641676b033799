// Mirrors dirt_math::num: min/max/floor with one fixed meaning.

fn fmin(a: f32, b: f32) -> f32 {
    return select(a, b, b < a);
}

fn fmax(a: f32, b: f32) -> f32 {
    return select(a, b, b > a);
}

// floor(x) clamped to [0, last] as an index (NaN gives 0).
fn floor_index(x: f32, last: u32) -> u32 {
    let f = floor(x);
    if f >= f32(last) {
        return last;
    } else if f >= 0.0 {
        return u32(f);
    }
    return 0u;
}
