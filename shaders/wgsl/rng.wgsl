// Mirrors dirt_render::rng: random numbers as a pure function of (seed,
// pixel, sample, bounce, dimension). WGSL has no 64-bit integers, so a u64 is
// a (low, high) pair of u32 words; integer arithmetic only, so every number is
// the CPU's, bit for bit.

const DIM_PIXEL_X: u32 = 0u;
const DIM_PIXEL_Y: u32 = 1u;
const DIM_LIGHT_PICK: u32 = 2u;
const DIM_LIGHT_U: u32 = 3u;
const DIM_LIGHT_V: u32 = 4u;
const DIM_LOBE: u32 = 5u;
const DIM_DIR_U: u32 = 6u;
const DIM_DIR_V: u32 = 7u;
const DIM_ROULETTE: u32 = 8u;

// a >> n for 0 < n < 32.
fn u64_shr(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// The 64-bit product of two 32-bit words, from 16-bit halves.
fn mul_wide(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// a * b mod 2^64.
fn u64_mul(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = mul_wide(a.x, b.x);
    return vec2<u32>(lo.x, lo.y + a.x * b.y + a.y * b.x);
}

// SplitMix64's finaliser.
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = z0;
    z = u64_mul(z ^ u64_shr(z, 30u), vec2<u32>(0x1ce4e5b9u, 0xbf58476du));
    z = u64_mul(z ^ u64_shr(z, 27u), vec2<u32>(0x133111ebu, 0x94d049bbu));
    return z ^ u64_shr(z, 31u);
}

// Sampler::new(seed, pixel, sample), given mix64(seed ^ golden ratio).
fn sampler_key(seed_mix: vec2<u32>, pixel: u32, sample: u32) -> vec2<u32> {
    return mix64(seed_mix ^ vec2<u32>(sample, pixel));
}

// Sampler::get: uniform in [0, 1) with 24 random bits.
fn rng_get(key: vec2<u32>, bounce: u32, dim: u32) -> f32 {
    let h = mix64(key ^ mix64(vec2<u32>(dim, bounce)));
    return f32(h.y >> 8u) * (1.0 / 16777216.0);
}
