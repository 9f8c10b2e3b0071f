//! Image bytes to a [`Texture`]: the format from the bytes' signature (PNG or JPEG), the size
//! checked from the header before anything is decoded, the sRGB values made linear.

use std::io::Cursor;

use twopass_brdf::Rgb;

use super::pyramid;
use super::raster::{MipLevel, Texture};

/// Most texels of one texture (an 8192 x 8192 image): its linear copy and pyramid take about
/// 1 GB. A larger image, such as a decompression bomb whose small file declares a huge
/// picture, is refused from its header's dimensions before it is decoded.
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 26;

/// Longest side of a texture, texels.
pub const MAX_TEXTURE_SIDE: u32 = 32768;

/// The sRGB transfer function inverted (IEC 61966-2-1): an encoded value in [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Decodes a PNG or JPEG image into a texture named `name`; the problem in words otherwise.
pub(crate) fn decode(bytes: &[u8], name: String) -> Result<Texture, String> {
    let format = image::guess_format(bytes).map_err(|_| {
        "not a PNG or JPEG image (its first bytes are neither signature)".to_owned()
    })?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(format!(
            "a {format:?} image; textures are read from PNG and JPEG only"
        ));
    }
    let reader = || image::io::Reader::with_format(Cursor::new(bytes), format);
    let (width, height) = reader()
        .into_dimensions()
        .map_err(|e| format!("not a readable {format:?} image: {e}"))?;
    let pixels = u64::from(width) * u64::from(height);
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE || pixels > MAX_TEXTURE_PIXELS {
        return Err(format!(
            "its header declares {width} x {height} pixels, more than the {MAX_TEXTURE_PIXELS} pixels ({MAX_TEXTURE_SIDE} on a side) read at most; not decoded"
        ));
    }
    if pixels == 0 {
        return Err(format!("its header declares {width} x {height} pixels"));
    }
    let mut limits = image::io::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    // Room for the decoded image at 16 bits per channel with alpha, and the decoder's own.
    limits.max_alloc = Some(pixels * 8 + (64 << 20));
    let mut r = reader();
    r.limits(limits);
    let img = r
        .decode()
        .map_err(|e| format!("not a readable {format:?} image: {e}"))?;
    let eight_bit = matches!(
        img.color(),
        image::ColorType::L8
            | image::ColorType::La8
            | image::ColorType::Rgb8
            | image::ColorType::Rgba8
    );
    let texels: Vec<Rgb> = if eight_bit {
        let table: Vec<f32> = (0..256u32)
            .map(|v| srgb_to_linear(v as f32 / 255.0))
            .collect();
        img.to_rgb8()
            .pixels()
            .map(|p| {
                Rgb::new(
                    table[p[0] as usize],
                    table[p[1] as usize],
                    table[p[2] as usize],
                )
            })
            .collect()
    } else {
        img.to_rgb32f()
            .pixels()
            .map(|p| {
                Rgb::new(
                    srgb_to_linear(p[0]),
                    srgb_to_linear(p[1]),
                    srgb_to_linear(p[2]),
                )
            })
            .collect()
    };
    let base = MipLevel {
        width,
        height,
        texels,
    };
    Ok(Texture {
        name,
        levels: pyramid::build(base),
    })
}
