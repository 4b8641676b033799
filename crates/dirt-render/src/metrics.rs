//! Error metrics between images.

use crate::RenderError;
use crate::output::Image;

/// Root-mean-square difference over every channel of every pixel (linear
/// radiance), in f64.
pub fn rmse(a: &Image, b: &Image) -> Result<f64, RenderError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(RenderError::SizeMismatch {
            a: (a.width, a.height),
            b: (b.width, b.height),
        });
    }
    let n = a.pixels.len() * 3;
    if n == 0 {
        return Ok(0.0);
    }
    let sum: f64 = a
        .pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(&x, &y)| {
            let d = f64::from(x) - f64::from(y);
            d * d
        })
        .sum();
    Ok((sum / n as f64).sqrt())
}

/// Mean of every channel of every pixel.
pub fn mean(a: &Image) -> f64 {
    let n = a.pixels.len() * 3;
    if n == 0 {
        return 0.0;
    }
    a.pixels
        .iter()
        .flatten()
        .map(|&x| f64::from(x))
        .sum::<f64>()
        / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmse_of_known_images() {
        let mut a = Image::new(2, 1);
        let b = Image::new(2, 1);
        assert_eq!(rmse(&a, &b).expect("same size"), 0.0);
        a.pixels[0] = [1.0, 1.0, 1.0];
        // Three of six channels differ by 1.
        assert!((rmse(&a, &b).expect("same size") - 0.5f64.sqrt()).abs() < 1e-12);
        assert!(rmse(&a, &Image::new(1, 2)).is_err());
    }
}
