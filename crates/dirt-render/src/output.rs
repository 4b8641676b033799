//! The rendered image: linear RGB floats, written as a tone-mapped sRGB PNG
//! or a linear EXR.

use crate::RenderError;
use std::path::Path;

/// Linear RGB radiance per pixel, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// The ACES filmic curve (Narkowicz's fit): keeps highlights from clipping hard.
fn aces(x: f32) -> f32 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Option<[f32; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.pixels
            .get(y as usize * self.width as usize + x as usize)
            .copied()
    }

    /// Every channel's bits, to compare images exactly.
    pub fn bits(&self) -> Vec<u32> {
        self.pixels.iter().flatten().map(|c| c.to_bits()).collect()
    }

    /// 8-bit sRGB after exposure `2^stops` and the ACES curve.
    pub fn to_srgb8(&self, stops: f32) -> Vec<u8> {
        let k = stops.exp2();
        self.pixels
            .iter()
            .flatten()
            .map(|&c| {
                let v = if c.is_finite() { c } else { 0.0 };
                (linear_to_srgb(aces(v * k)) * 255.0 + 0.5).clamp(0.0, 255.0) as u8
            })
            .collect()
    }

    /// [`Image::to_srgb8`] with an opaque alpha byte: what a canvas or a
    /// texture takes.
    pub fn to_rgba8(&self, stops: f32) -> Vec<u8> {
        self.to_srgb8(stops)
            .chunks_exact(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect()
    }

    /// Writes a tone-mapped PNG.
    pub fn write_png(&self, path: &Path, stops: f32) -> Result<(), RenderError> {
        let buf = image::RgbImage::from_raw(self.width, self.height, self.to_srgb8(stops))
            .ok_or_else(|| write_error(path, "pixel buffer does not match the size"))?;
        buf.save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| write_error(path, &e.to_string()))
    }

    /// Writes the linear radiance as a 32-bit float EXR.
    pub fn write_exr(&self, path: &Path) -> Result<(), RenderError> {
        let data: Vec<f32> = self.pixels.iter().flatten().copied().collect();
        let buf = image::Rgb32FImage::from_raw(self.width, self.height, data)
            .ok_or_else(|| write_error(path, "pixel buffer does not match the size"))?;
        image::DynamicImage::ImageRgb32F(buf)
            .save_with_format(path, image::ImageFormat::OpenExr)
            .map_err(|e| write_error(path, &e.to_string()))
    }

    /// Reads a linear EXR written by [`write_exr`](Self::write_exr).
    pub fn read_exr(path: &Path) -> Result<Self, RenderError> {
        let img = image::open(path).map_err(|e| RenderError::Read {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let rgb = img.to_rgb32f();
        Ok(Self {
            width: rgb.width(),
            height: rgb.height(),
            pixels: rgb.pixels().map(|p| p.0).collect(),
        })
    }
}

fn write_error(path: &Path, message: &str) -> RenderError {
    RenderError::Write {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}
