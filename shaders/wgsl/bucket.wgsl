// Mirrors dirt_math::bucket: depth buckets of a tile (001 eq. 1).
#import divide
#import work

fn bucket_of(z: f32, zmin: f32, zmax: f32, buckets: u32) -> u32 {
    if buckets <= 1u {
        return 0u;
    }
    let range = zmax - zmin;
    let x = (z - zmin) * f32(buckets);
    if !(range > 0.0) | !(x > 0.0) {
        return 0u;
    }
    let last = buckets - 1u;
    // Only an estimate: the loops below make the result exact whatever it is.
    let est = div_cr(x, range);
    var k = 0u;
    if est >= f32(last) {
        k = last;
    } else if est >= 0.0 {
        k = u32(est);
    }
    while k > 0u && f32(k) * range > x && work() {
        k -= 1u;
    }
    while k < last && f32(k + 1u) * range <= x && work() {
        k += 1u;
    }
    return k;
}

fn bucket_floor_depth(k: u32, zmin: f32, zmax: f32, buckets: u32) -> f32 {
    if (k == 0u) | (buckets <= 1u) {
        // From a `let`: a constant -inf is refused by Tint (see f32_inf).
        let bits = 0xff800000u;
        return bitcast<f32>(bits);
    }
    let range = zmax - zmin;
    return zmin + range * div_cr(f32(k), f32(buckets)) - range * 0.0009765625;
}

fn bucket_ceil_depth(k: u32, zmin: f32, zmax: f32, buckets: u32) -> f32 {
    if k + 1u >= buckets {
        let bits = 0x7f800000u;
        return bitcast<f32>(bits);
    }
    let range = zmax - zmin;
    return zmin + range * div_cr(f32(k + 1u), f32(buckets)) + range * 0.0009765625;
}
