//! Images and materials: decoded glTF images converted to RGBA8 textures,
//! glTF materials converted to [`Material`]s.

use crate::builder::SceneBuilder;
use crate::model::{Material, Texture};

/// Converts any pixel format `gltf` decodes to RGBA8. Luminance formats
/// (`R8`, `R8G8` = luma + alpha) are expanded to grey; 16-bit channels are
/// rounded to 8 bits; float channels are clamped to `[0, 1]`.
pub(crate) fn convert_image(img: &gltf::image::Data) -> Result<Texture, String> {
    use gltf::image::Format;
    let (channels, bytes_per_channel) = match img.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let pixels = (img.width as usize)
        .checked_mul(img.height as usize)
        .ok_or_else(|| format!("{}x{} is too large", img.width, img.height))?;
    let expected = pixels * channels * bytes_per_channel;
    if img.pixels.len() != expected {
        return Err(format!(
            "{}x{} {:?} image has {} bytes of pixel data, expected {expected}",
            img.width,
            img.height,
            img.format,
            img.pixels.len()
        ));
    }
    let channel = |c: &[u8]| -> u8 {
        match *c {
            [v] => v,
            [a, b] => ((u16::from_ne_bytes([a, b]) as u32 * 255 + 32767) / 65535) as u8,
            [a, b, c, d] => {
                let f = f32::from_ne_bytes([a, b, c, d]);
                if f.is_nan() {
                    0
                } else {
                    (f.clamp(0.0, 1.0) * 255.0).round() as u8
                }
            }
            _ => 0,
        }
    };
    let mut rgba8 = Vec::with_capacity(pixels * 4);
    for px in img.pixels.chunks_exact(channels * bytes_per_channel) {
        let mut ch = px.chunks_exact(bytes_per_channel).map(channel);
        let mut next = || ch.next().unwrap_or(0);
        let rgba = match channels {
            1 => {
                let l = next();
                [l, l, l, 255]
            }
            2 => {
                let l = next();
                [l, l, l, next()]
            }
            3 => [next(), next(), next(), 255],
            _ => [next(), next(), next(), next()],
        };
        rgba8.extend_from_slice(&rgba);
    }
    Ok(Texture {
        width: img.width,
        height: img.height,
        rgba8,
    })
}

pub(super) fn convert_material(m: &gltf::Material, b: &mut SceneBuilder) -> Material {
    let index = m.index().unwrap_or(0);
    let pbr = m.pbr_metallic_roughness();
    let base_color_texture = pbr.base_color_texture().map(|info| {
        if info.tex_coord() != 0 {
            b.warn(format!(
                "material {index}: base colour texture uses TEXCOORD_{}; only TEXCOORD_0 is loaded",
                info.tex_coord()
            ));
        }
        info.texture().source().index() as u32
    });
    let strength = m.emissive_strength().unwrap_or(1.0);
    Material {
        name: m.name().unwrap_or_default().to_string(),
        base_color: pbr.base_color_factor(),
        base_color_texture,
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        emissive: m.emissive_factor().map(|e| e * strength),
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use gltf::image::{Data, Format};

    fn img(format: Format, pixels: Vec<u8>) -> Data {
        Data {
            pixels,
            format,
            width: 2,
            height: 1,
        }
    }

    #[test]
    fn every_image_format_becomes_rgba8() {
        let cases: Vec<(Data, [u8; 8])> = vec![
            (
                img(Format::R8, vec![10, 20]),
                [10, 10, 10, 255, 20, 20, 20, 255],
            ),
            (
                img(Format::R8G8, vec![10, 1, 20, 2]),
                [10, 10, 10, 1, 20, 20, 20, 2],
            ),
            (
                img(Format::R8G8B8, vec![1, 2, 3, 4, 5, 6]),
                [1, 2, 3, 255, 4, 5, 6, 255],
            ),
            (
                img(Format::R8G8B8A8, vec![1, 2, 3, 4, 5, 6, 7, 8]),
                [1, 2, 3, 4, 5, 6, 7, 8],
            ),
            (
                img(
                    Format::R16,
                    [0u16, 65535].iter().flat_map(|v| v.to_ne_bytes()).collect(),
                ),
                [0, 0, 0, 255, 255, 255, 255, 255],
            ),
            (
                img(
                    Format::R16G16,
                    [257u16, 0, 32896, 65535]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [1, 1, 1, 0, 128, 128, 128, 255],
            ),
            (
                img(
                    Format::R16G16B16,
                    [0u16, 257, 514, 65535, 65535, 0]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 1, 2, 255, 255, 255, 0, 255],
            ),
            (
                img(
                    Format::R16G16B16A16,
                    [0u16, 257, 514, 771, 1, 2, 3, 4]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 1, 2, 3, 0, 0, 0, 0],
            ),
            (
                img(
                    Format::R32G32B32FLOAT,
                    [0.0f32, 0.5, 1.0, -1.0, 2.0, f32::NAN]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [0, 128, 255, 255, 0, 255, 0, 255],
            ),
            (
                img(
                    Format::R32G32B32A32FLOAT,
                    [1.0f32, 0.0, 0.0, 0.25, 0.0, 1.0, 0.0, 1.0]
                        .iter()
                        .flat_map(|v| v.to_ne_bytes())
                        .collect(),
                ),
                [255, 0, 0, 64, 0, 255, 0, 255],
            ),
        ];
        for (data, want) in cases {
            let t = convert_image(&data).unwrap();
            assert_eq!((t.width, t.height), (2, 1));
            assert_eq!(t.rgba8, want, "{:?}", data.format);
        }
        // Wrong byte count.
        assert!(convert_image(&img(Format::R8G8B8, vec![1, 2, 3])).is_err());
    }
}
