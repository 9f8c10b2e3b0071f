//! What the `.glb` files say about the lightmap texture engines take: the materials'
//! `extras.lightMap` entry and the encoding fields of `asset.extras.twopass`, the same in
//! the lightmap `.glb` and in the user's asset written back.
//!
//! `extras.lightMap` = `{ "index": <texture>, "texCoord": 1, "quantity": "irradiance" |
//! "radiance", "encoding": "rgbm" | "srgb", "intensity": <x>, "multiplier": <M> (rgbm),
//! "exposure": <e> (srgb) }`, named after three.js's `material.lightMap` and
//! `lightMapIntensity`. The decoded value is, per channel: RGBM, `M * A * (R, G, B)` with the
//! 8-bit values over 255 read linearly; sRGB, the sRGB-decoded value over `exposure` (clipped
//! at `1 / exposure`). `intensity` turns the decoded value into what three.js (r155 and later)
//! wants: pi for an irradiance lightmap (three.js takes irradiance E, the texel holds E / pi),
//! 1 for radiance; for the sRGB PNG it also carries the `1 / exposure`.

use serde_json::{Value, json};

use super::rgbm::RGBM_FORMULA;
use super::settings::{LightmapEncoding, LightmapQuantity, Resolved};
use crate::colour::ColorMapping;

/// The textures a bake encoded, as the `.glb` writers take them.
#[derive(Debug, Clone, Copy)]
pub(super) struct Encoded<'a> {
    /// The exposure-scaled sRGB PNG.
    pub(super) png: &'a [u8],
    /// The RGBM PNG and its multiplier, with [`LightmapEncoding::Rgbm`].
    pub(super) rgbm: Option<(&'a [u8], f32)>,
    /// The exposure of the sRGB PNG.
    pub(super) mapping: ColorMapping,
    /// The EXR's fingerprint.
    pub(super) exr_fingerprint: u64,
}

impl Encoded<'_> {
    /// The bytes of the texture engines take: the RGBM PNG when there is one, else the sRGB.
    pub(super) fn engine_png(&self) -> &[u8] {
        self.rgbm.map_or(self.png, |(png, _)| png)
    }

    /// The encoding of [`Encoded::engine_png`].
    pub(super) fn encoding(&self) -> LightmapEncoding {
        if self.rgbm.is_some() {
            LightmapEncoding::Rgbm
        } else {
            LightmapEncoding::Srgb
        }
    }

    /// three.js's `lightMapIntensity` for the decoded texture (module docs).
    pub(super) fn three_intensity(&self, s: &Resolved) -> f32 {
        let quantity = match s.quantity {
            LightmapQuantity::Irradiance => std::f32::consts::PI,
            LightmapQuantity::Radiance => 1.0,
        };
        match self.rgbm {
            Some(_) => quantity,
            None => quantity / self.mapping.exposure,
        }
    }

    /// A material's `extras.lightMap` naming texture `index`.
    pub(super) fn material_entry(&self, index: usize, s: &Resolved) -> Value {
        let mut entry = json!({
            "index": index,
            "texCoord": 1,
            "quantity": s.quantity.name(),
            "encoding": self.encoding().name(),
            "intensity": self.three_intensity(s),
        });
        match self.rgbm {
            Some((_, m)) => entry["multiplier"] = json!(m),
            None => entry["exposure"] = json!(self.mapping.exposure),
        }
        entry
    }

    /// The fields `asset.extras.twopass` adds about the engines' texture `index`.
    pub(super) fn record(&self, index: usize, s: &Resolved) -> Value {
        let decode = match self.rgbm {
            Some(_) => RGBM_FORMULA,
            None => s.quantity.png_formula(),
        };
        json!({
            "texture": index,
            "encoding": self.encoding().name(),
            "decode": decode,
            "rgbm_multiplier": self.rgbm.map(|(_, m)| m),
            "three_js": format!(
                "material.lightMap = texture {index} (channel 1), material.lightMapIntensity = \
                 {}{}",
                self.three_intensity(s),
                if self.rgbm.is_some() {
                    " x rgbm_multiplier, the lightmap texel read as texel.rgb * texel.a"
                } else {
                    ""
                }
            ),
        })
    }
}
