//! Random numbers as a pure function of (seed, pixel, sample, bounce,
//! dimension): no generator state, so the result never depends on the order
//! in which threads handle pixels, and two tracers see the same numbers.

/// Dimensions used within one bounce.
pub mod dim {
    pub const PIXEL_X: u32 = 0;
    pub const PIXEL_Y: u32 = 1;
    pub const LIGHT_PICK: u32 = 2;
    pub const LIGHT_U: u32 = 3;
    pub const LIGHT_V: u32 = 4;
    pub const LOBE: u32 = 5;
    pub const DIR_U: u32 = 6;
    pub const DIR_V: u32 = 7;
    pub const ROULETTE: u32 = 8;
}

/// SplitMix64's finaliser: a bijective 64-bit mix with good avalanche.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The first step of [`Sampler::new`], shared by every pixel and sample of
/// a render (the GPU renderer computes it once on the host).
pub fn seed_mix(seed: u64) -> u64 {
    mix64(seed ^ 0x9e37_79b9_7f4a_7c15)
}

/// The random numbers of one sample of one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    key: u64,
}

impl Sampler {
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        let a = seed_mix(seed);
        Self {
            key: mix64(a ^ ((u64::from(pixel) << 32) | u64::from(sample))),
        }
    }

    /// Uniform in `[0, 1)` with 24 random bits (every value exact in f32).
    #[inline]
    pub fn get(&self, bounce: u32, dim: u32) -> f32 {
        let h = mix64(self.key ^ mix64((u64::from(bounce) << 32) | u64::from(dim)));
        (h >> 40) as f32 * (1.0 / 16_777_216.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pure_and_uniform() {
        let s = Sampler::new(7, 12, 3);
        assert_eq!(s.get(2, 5), Sampler::new(7, 12, 3).get(2, 5));
        assert_ne!(s.get(2, 5), Sampler::new(8, 12, 3).get(2, 5));
        let n = 100_000u32;
        let mut sum = 0.0f64;
        let mut buckets = [0u32; 10];
        for p in 0..n {
            let x = Sampler::new(1, p, 0).get(0, 0);
            assert!((0.0..1.0).contains(&x));
            sum += f64::from(x);
            buckets[(x * 10.0) as usize] += 1;
        }
        assert!((sum / f64::from(n) - 0.5).abs() < 0.01);
        for b in buckets {
            assert!((9_000..11_000).contains(&b), "{buckets:?}");
        }
    }
}
