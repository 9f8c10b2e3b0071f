//! The HDR lightmap in an 8-bit PNG: RGBM, an RGB colour and a shared multiplier in alpha.
//!
//! **Decode.** With `R`, `G`, `B`, `A` the PNG's 8-bit values over 255, read as they are (no
//! sRGB decoding: the texture is linear data), and `M` the lightmap's range multiplier (the
//! largest channel of any texel, recorded in the `.glb`):
//!
//! `value = M * A * (R, G, B)`
//!
//! in the lightmap's unit (W/(m^2 sr): radiance, or irradiance over pi). Nothing clips: `M`
//! is the largest value, so every texel has `A <= 1`.
//!
//! **Encode.** Per texel, `m = max(r, g, b) / M`, `A = ceil(255 m) / 255` (at least the value,
//! so no channel needs more than 255), and each channel `round(255 c / (M A)) / 255`.
//!
//! **Error bound.** `A` is at most `m + 1/255`, and rounding a channel moves it by at most
//! half a step, `1/510`, of `M A`; so a decoded channel is within
//! `M A / 510 <= (max(r, g, b) + M / 255) / 510` of its value: about 0.2 % of the texel's
//! brightest channel, plus 1/130050 of the lightmap's largest value ([`rgbm_error_bound`]).
//! Bilinear filtering of an RGBM texture interpolates `A` and the colour separately, which
//! is exact within a texel of one multiplier and close elsewhere (the charts' texels change
//! slowly).

use twopass_composite::Image;

/// A lightmap as RGBM ([module docs](self)): the 8-bit RGBA texels and the range multiplier.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgbm {
    /// Range multiplier `M`: `value = M * A * (R, G, B)`; the largest channel of any texel
    /// (1 for a lightmap of zeros), in the lightmap's unit.
    pub multiplier: f32,
    /// The texels, row-major from the top row, `R, G, B, A` bytes each.
    pub rgba: Vec<u8>,
}

/// The decode formula, as the `.glb` and the PNG's `Description` record it.
pub const RGBM_FORMULA: &str = "value = multiplier * A * (R, G, B), with R, G, B, A the \
     PNG's 8-bit values / 255 read as linear (no sRGB decoding)";

/// The largest difference between a channel of `rgb` and its RGBM decode with multiplier
/// `multiplier` ([module docs](self)): `(max(r, g, b) + multiplier / 255) / 510`.
pub fn rgbm_error_bound(rgb: [f32; 3], multiplier: f32) -> f32 {
    (rgb[0].max(rgb[1]).max(rgb[2]) + multiplier / 255.0) / 510.0
}

/// Encodes `image` (finite, non-negative texels) as RGBM.
pub fn encode_rgbm(image: &Image) -> Rgbm {
    let largest = image
        .pixels()
        .iter()
        .map(|p| p.max_element())
        .fold(0.0f32, f32::max);
    let multiplier = if largest > 0.0 { largest } else { 1.0 };
    let mut rgba = Vec::with_capacity(image.pixels().len() * 4);
    for p in image.pixels() {
        let c = p.max(glam::Vec3::ZERO);
        let m = (c.max_element() / multiplier).clamp(0.0, 1.0);
        let a = (255.0 * m).ceil().clamp(0.0, 255.0);
        if a == 0.0 {
            rgba.extend_from_slice(&[0; 4]);
            continue;
        }
        let scale = multiplier * a / 255.0;
        for v in c.to_array() {
            rgba.push((255.0 * v / scale).round().clamp(0.0, 255.0) as u8);
        }
        rgba.push(a as u8);
    }
    Rgbm { multiplier, rgba }
}

/// The value of RGBA bytes `px` with multiplier `multiplier` ([`RGBM_FORMULA`]).
pub fn decode_rgbm(px: [u8; 4], multiplier: f32) -> [f32; 3] {
    let a = f32::from(px[3]) / 255.0;
    [0, 1, 2].map(|k| multiplier * a * (f32::from(px[k]) / 255.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn every_texel_decodes_within_the_bound_and_the_largest_is_kept() {
        // Values over five decades, a black texel, one channel alone and the largest value.
        #[rustfmt::skip]
        let values = [
            Vec3::new(40.0, 10.0, 2.5),
            Vec3::new(1.0, 0.5, 0.25),
            Vec3::new(0.013, 0.0004, 0.0),
            Vec3::ZERO,
            Vec3::new(0.0, 3.7, 0.0),
            Vec3::new(0.001, 0.001, 0.001),
        ];
        let image = Image::from_pixels(3, 2, values.to_vec()).unwrap();
        let rgbm = encode_rgbm(&image);
        assert_eq!(rgbm.multiplier, 40.0);
        for (i, v) in values.iter().enumerate() {
            let px: [u8; 4] = rgbm.rgba[4 * i..4 * i + 4].try_into().unwrap();
            let got = decode_rgbm(px, rgbm.multiplier);
            let bound = rgbm_error_bound(v.to_array(), rgbm.multiplier);
            for k in 0..3 {
                assert!(
                    (got[k] - v[k]).abs() <= bound * (1.0 + 1e-5),
                    "{v} -> {got:?}"
                );
            }
        }
        // The largest texel is stored with A = 1 and its largest channel exactly.
        assert_eq!(&rgbm.rgba[..4], &[255, 64, 16, 255]);
        assert_eq!(decode_rgbm([255, 64, 16, 255], 40.0)[0], 40.0);
        // A black lightmap has multiplier 1 and zero texels.
        let black = encode_rgbm(&Image::new(2, 1));
        assert_eq!(
            (black.multiplier, black.rgba.as_slice()),
            (1.0, &[0u8; 8][..])
        );
    }

    #[test]
    fn the_bound_is_reached_closely_so_it_is_not_loose() {
        // Over many values the worst error is more than half the bound: the bound is tight.
        let values: Vec<Vec3> = (1..=4000)
            .map(|i| Vec3::new(i as f32 * 0.01, (i % 97) as f32 * 0.003, 0.0))
            .collect();
        let n = values.len() as u32;
        let image = Image::from_pixels(n, 1, values.clone()).unwrap();
        let rgbm = encode_rgbm(&image);
        let mut worst = 0.0f32;
        for (i, v) in values.iter().enumerate() {
            let px: [u8; 4] = rgbm.rgba[4 * i..4 * i + 4].try_into().unwrap();
            let got = decode_rgbm(px, rgbm.multiplier);
            let bound = rgbm_error_bound(v.to_array(), rgbm.multiplier);
            for k in 0..3 {
                worst = worst.max((got[k] - v[k]).abs() / bound);
            }
        }
        assert!(worst <= 1.0 + 1e-5 && worst > 0.5, "{worst}");
    }
}
