//! Progressive accumulation (the viewer's and the web page's): one sample pass at a time is added up; the mean
//! is what `dirt render` of as many samples per pixel gives (the same sums in
//! the same order, the same `1 / n` scale), tone-mapped as its PNG is.

use crate::Image;
use dirt_math::Vec3;

use crate::RenderError;

/// The running sum of sample passes at one resolution.
#[derive(Clone, Debug)]
pub struct Accumulator {
    pub width: u32,
    pub height: u32,
    sum: Vec<Vec3>,
    /// Passes added since the last reset: the next pass's sample number.
    pub samples: u32,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sum: vec![Vec3::ZERO; width as usize * height as usize],
            samples: 0,
        }
    }

    /// Forgets every pass (the camera or the scene moved).
    pub fn reset(&mut self) {
        self.sum.fill(Vec3::ZERO);
        self.samples = 0;
    }

    /// Adds one pass of radiance, rows top to bottom.
    pub fn add(&mut self, radiance: &[Vec3]) -> Result<(), RenderError> {
        if radiance.len() != self.sum.len() {
            return Err(RenderError::PassSize {
                pixels: radiance.len(),
                width: self.width,
                height: self.height,
            });
        }
        for (acc, r) in self.sum.iter_mut().zip(radiance) {
            *acc += *r;
        }
        self.samples += 1;
        Ok(())
    }

    /// The mean radiance (black before the first pass).
    pub fn mean(&self) -> Image {
        let inv = if self.samples == 0 {
            0.0
        } else {
            1.0 / self.samples as f32
        };
        Image {
            width: self.width,
            height: self.height,
            pixels: self.sum.iter().map(|v| (*v * inv).to_array()).collect(),
        }
    }

    /// The mean as 8-bit sRGB RGBA (opaque), exposure `2^stops`: the bytes
    /// `dirt render` writes to its PNG.
    pub fn rgba8(&self, stops: f32) -> Vec<u8> {
        self.mean().to_rgba8(stops)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_of_passes_and_a_reset() {
        let mut a = Accumulator::new(2, 1);
        assert_eq!(a.rgba8(0.0), vec![0, 0, 0, 255, 0, 0, 0, 255]);
        a.add(&[Vec3::splat(1.0), Vec3::ZERO]).expect("add");
        a.add(&[Vec3::splat(3.0), Vec3::splat(2.0)]).expect("add");
        assert_eq!(a.samples, 2);
        assert_eq!(a.mean().pixels, vec![[2.0; 3], [1.0; 3]]);
        let rgba = a.rgba8(0.0);
        assert_eq!(rgba.len(), 8);
        assert_eq!(&rgba[..3], &a.mean().to_srgb8(0.0)[..3]);
        assert!(a.add(&[Vec3::ZERO]).is_err());
        a.reset();
        assert_eq!(a.samples, 0);
        assert_eq!(a.mean().pixels, vec![[0.0; 3]; 2]);
    }
}
