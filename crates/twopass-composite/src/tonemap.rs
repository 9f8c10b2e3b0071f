//! Tone mapping for display: exposure, an optional filmic curve, the sRGB transfer function and
//! 8-bit quantization, in that order.
//!
//! Linear RGB `c` becomes `q(srgb(curve(c * 2^stops)))` per channel, where `curve` is a clip to
//! [0, 1] or a filmic curve (which ends in a clip), `srgb` is the exact piecewise sRGB transfer
//! (IEC 61966-2-1) and `q(v) = round(255 v)`. Panels of one sheet must share one [`ToneMap`]
//! (usually [`ToneMap::auto`] on the reference) so that they are comparable.

use glam::Vec3;

use crate::error::{CompositeError, Result};
use crate::image::{Image, Rgb8Image, luminance};

/// The sRGB transfer function (linear to encoded), exact piecewise form of IEC 61966-2-1:
/// `12.92 x` for `x <= 0.0031308`, else `1.055 x^(1/2.4) - 0.055`. Input is clamped to [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_encode`]: `v / 12.92` for `v <= 0.04045`, else
/// `((v + 0.055) / 1.055)^2.4`. Input is clamped to [0, 1].
pub fn srgb_decode(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// 8-bit quantization of an encoded value in [0, 1]: `round(255 v)`, clamped (NaN gives 0).
pub fn quantize(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The curve applied after exposure and before the sRGB transfer, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Curve {
    /// Linear, clipped to [0, 1]: comparisons see the radiance as it is.
    #[default]
    Clip,
    /// Krzysztof Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone Mapping Curve",
    /// 2016): `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, clipped to [0, 1]. Narkowicz
    /// scales the input by 0.6 first to match ACES; do that through the exposure if wanted.
    AcesNarkowicz,
    /// John Hable's Uncharted 2 curve ("Filmic Tonemapping Operators", 2010):
    /// `f(x) = (x (A x + C B) + D E) / (x (A x + B) + D F) - E / F` with A = 0.15, B = 0.50,
    /// C = 0.10, D = 0.20, E = 0.02, F = 0.30, normalised by `f(W)` with white point W = 11.2.
    Hable,
}

impl Curve {
    /// The curve at `x` (linear, after exposure), in [0, 1].
    pub fn apply(self, x: f32) -> f32 {
        let x = x.max(0.0);
        let y = match self {
            Curve::Clip => x,
            Curve::AcesNarkowicz => x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14),
            Curve::Hable => hable(x) / hable(11.2),
        };
        y.clamp(0.0, 1.0)
    }

    /// A short name for captions.
    pub fn name(self) -> &'static str {
        match self {
            Curve::Clip => "clip",
            Curve::AcesNarkowicz => "ACES (Narkowicz fit)",
            Curve::Hable => "Hable filmic",
        }
    }
}

fn hable(x: f32) -> f32 {
    const A: f32 = 0.15;
    const B: f32 = 0.50;
    const C: f32 = 0.10;
    const D: f32 = 0.20;
    const E: f32 = 0.02;
    const F: f32 = 0.30;
    (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F
}

/// Exposure and curve: everything needed to turn linear RGB into display values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    scale: f32,
    curve: Curve,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self {
            scale: 1.0,
            curve: Curve::Clip,
        }
    }
}

impl ToneMap {
    /// Exposure `stops` (EV; +1 doubles the radiance) with the [`Curve::Clip`] curve.
    pub fn from_stops(stops: f32) -> Result<Self> {
        if !stops.is_finite() || stops.abs() > 64.0 {
            return Err(CompositeError::Parameter {
                name: "exposure stops",
                value: f64::from(stops),
                reason: "must be finite and within +-64",
            });
        }
        Ok(Self {
            scale: stops.exp2(),
            curve: Curve::Clip,
        })
    }

    /// Exposure as a linear `scale` (> 0, finite) with the [`Curve::Clip`] curve.
    pub fn from_scale(scale: f32) -> Result<Self> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(CompositeError::Parameter {
                name: "exposure scale",
                value: f64::from(scale),
                reason: "must be finite and > 0",
            });
        }
        Ok(Self {
            scale,
            curve: Curve::Clip,
        })
    }

    /// The same exposure with another curve.
    pub fn with_curve(self, curve: Curve) -> Self {
        Self { curve, ..self }
    }

    /// Chooses the exposure that maps the `percentile` (in [0, 1], nearest rank) of `image`'s
    /// luminance to the linear display value `target` (in (0, 1]), with the [`Curve::Clip`]
    /// curve. Use it on the reference (or first) panel and apply the result to every panel of a
    /// sheet. A black image gives exposure 0 EV. Non-finite pixels are an error.
    pub fn auto(image: &Image, percentile: f32, target: f32) -> Result<Self> {
        if !(0.0..=1.0).contains(&percentile) {
            return Err(CompositeError::Parameter {
                name: "percentile",
                value: f64::from(percentile),
                reason: "must be in [0, 1]",
            });
        }
        if !(target > 0.0 && target <= 1.0) {
            return Err(CompositeError::Parameter {
                name: "target",
                value: f64::from(target),
                reason: "must be in (0, 1]",
            });
        }
        image.check_finite("auto-exposure input")?;
        let mut y = image.luminance();
        if y.is_empty() {
            return Err(CompositeError::Empty {
                what: "auto-exposure input".into(),
            });
        }
        let rank = ((percentile * y.len() as f32).ceil() as usize).clamp(1, y.len()) - 1;
        let (_, &mut yp, _) = y.select_nth_unstable_by(rank, f32::total_cmp);
        if yp > 0.0 {
            Self::from_scale(target / yp)
        } else {
            Ok(Self::default())
        }
    }

    /// [`ToneMap::auto`] with the defaults: the 95th percentile of luminance maps to 0.8
    /// (so a small bright emitter may clip while the lit walls keep their detail).
    pub fn auto_default(image: &Image) -> Result<Self> {
        Self::auto(image, 0.95, 0.8)
    }

    /// The linear exposure scale.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// The exposure in stops (EV), `log2(scale)`.
    pub fn stops(&self) -> f32 {
        self.scale.log2()
    }

    /// The curve.
    pub fn curve(&self) -> Curve {
        self.curve
    }

    /// Linear display value in [0, 1]: exposure then curve.
    pub fn display(&self, rgb: Vec3) -> Vec3 {
        let c = rgb * self.scale;
        Vec3::new(
            self.curve.apply(c.x),
            self.curve.apply(c.y),
            self.curve.apply(c.z),
        )
    }

    /// sRGB-encoded value in [0, 1]: exposure, curve, then the sRGB transfer.
    pub fn encode(&self, rgb: Vec3) -> Vec3 {
        let d = self.display(rgb);
        Vec3::new(srgb_encode(d.x), srgb_encode(d.y), srgb_encode(d.z))
    }

    /// 8-bit sRGB: exposure, curve, sRGB transfer, quantization.
    pub fn to_rgb8(&self, rgb: Vec3) -> [u8; 3] {
        let e = self.encode(rgb);
        [quantize(e.x), quantize(e.y), quantize(e.z)]
    }

    /// The whole image as 8-bit sRGB.
    pub fn apply(&self, image: &Image) -> Rgb8Image {
        Rgb8Image::from_fn(image.width(), image.height(), |x, y| {
            self.to_rgb8(image.get(x, y))
        })
    }

    /// One line saying what was done, for PNG text chunks and sheet footers.
    pub fn describe(&self) -> String {
        format!(
            "tone mapped: exposure {:+.2} EV (x{:.4}), curve {}, then sRGB transfer, 8 bit",
            self.stops(),
            self.scale,
            self.curve.name()
        )
    }
}

/// The luminance of a pixel after the tone map's exposure and curve, sRGB-encoded (in [0, 1]);
/// the perceptual metric works on this.
pub fn display_luma(map: &ToneMap, rgb: Vec3) -> f32 {
    srgb_encode(luminance(map.display(rgb)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_known_points() {
        // At the breakpoint both branches agree: 12.92 * 0.0031308 = 0.040449936, and
        // 1.055 * 0.0031308^(1/2.4) - 0.055 = 0.0404499075 (they differ by 3e-8).
        assert!((srgb_encode(0.003_130_8) - 0.040_449_936).abs() < 1e-7);
        let upper = 1.055 * 0.003_130_8f64.powf(1.0 / 2.4) - 0.055;
        assert!((upper - 0.040_449_936).abs() < 1e-6);
        // 0.5: 1.055 * 0.5^(1/2.4) - 0.055 = 1.055 * 0.7491535 - 0.055 = 0.7353569.
        assert!((srgb_encode(0.5) - 0.735_356_9).abs() < 1e-6);
        // 1.0: 1.055 * 1 - 0.055 = 1 (up to f32 rounding of 1.055 and 0.055).
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert_eq!(quantize(srgb_encode(1.0)), 255);
        assert_eq!(srgb_encode(0.0), 0.0);
        assert_eq!(quantize(srgb_encode(0.5)), 188); // 0.7353569 * 255 = 187.52
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-6);
        }
    }

    #[test]
    fn exposure_doubling() {
        let one = ToneMap::from_stops(1.0).unwrap();
        assert_eq!(one.scale(), 2.0);
        let base = ToneMap::default();
        let c = Vec3::new(0.1, 0.2, 0.3);
        assert_eq!(one.display(c), base.display(2.0 * c));
        assert_eq!(ToneMap::from_scale(4.0).unwrap().stops(), 2.0);
        assert!(ToneMap::from_stops(f32::NAN).is_err());
        assert!(ToneMap::from_scale(0.0).is_err());
    }

    #[test]
    fn filmic_curves_are_monotone_in_unit_range() {
        for curve in [Curve::Clip, Curve::AcesNarkowicz, Curve::Hable] {
            assert_eq!(curve.apply(0.0).max(0.0), curve.apply(0.0));
            let mut prev = -1.0;
            for i in 0..1000 {
                let v = curve.apply(i as f32 * 0.02);
                assert!((0.0..=1.0).contains(&v) && v >= prev, "{curve:?}");
                prev = v;
            }
        }
        // Hable is normalised so that the white point maps to 1.
        assert!((Curve::Hable.apply(11.2) - 1.0).abs() < 1e-6);
        // ACES fit at 1: 2.54 / 3.16 = 0.803797.
        assert!((Curve::AcesNarkowicz.apply(1.0) - 0.803_797).abs() < 1e-6);
    }

    #[test]
    fn auto_exposure_maps_the_percentile_to_the_target() {
        // Luminances 1..=100 (grey pixels); the 95th percentile by nearest rank is 95.
        let img = Image::from_fn(10, 10, |x, y| {
            let v = (y * 10 + x + 1) as f32;
            [v, v, v]
        });
        let t = ToneMap::auto(&img, 0.95, 0.8).unwrap();
        assert!((t.scale() - 0.8 / 95.0).abs() < 1e-6 * t.scale());
        assert_eq!(
            ToneMap::auto(&Image::new(3, 3), 0.95, 0.8).unwrap(),
            ToneMap::default()
        );
        let mut bad = Image::new(2, 2);
        bad.set(1, 1, Vec3::new(f32::NAN, 0.0, 0.0));
        assert!(matches!(
            ToneMap::auto(&bad, 0.5, 0.5),
            Err(CompositeError::NonFinite { .. })
        ));
    }
}
