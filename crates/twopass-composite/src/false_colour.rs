//! False-colour difference images: a per-pixel error against the reference, mapped through a
//! perceptual colour map on a stated scale.
//!
//! Per pixel, over the three channels (linear RGB, radiance units):
//! - [`ErrorKind::Absolute`]: `mean_c |x_c - r_c|`, in radiance units;
//! - [`ErrorKind::Relative`]: `sqrt(mean_c (x_c - r_c)^2 / (r_c^2 + 0.01))`, unitless, the
//!   per-pixel form of the relative RMS error in [`crate::metric`].
//!
//! The colour maps are the matplotlib perceptually uniform maps (van der Walt and Smith, 2015)
//! as tabulated by the `colorous` crate. Values below the scale's minimum take the first colour
//! and values above its maximum the last; give every difference panel of a sheet the same
//! [`Scale`] so their colours compare.

use crate::error::{CompositeError, Result};
use crate::image::{Image, Rgb8Image};
use crate::metric::{REL_EPSILON, check_pair};

/// Which per-pixel error to show.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// `mean_c |x_c - r_c|`, radiance units.
    Absolute,
    /// `sqrt(mean_c (x_c - r_c)^2 / (r_c^2 + 0.01))`, unitless.
    Relative,
}

impl ErrorKind {
    /// A caption, e.g. for the colour bar.
    pub fn label(self) -> &'static str {
        match self {
            ErrorKind::Absolute => "absolute error",
            ErrorKind::Relative => "relative error",
        }
    }
}

/// A per-pixel scalar error image, row-major, (0, 0) at the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorMap {
    width: u32,
    height: u32,
    kind: ErrorKind,
    values: Vec<f32>,
}

impl ErrorMap {
    /// The error of `image` against `reference`. Sizes must match and pixels be finite.
    pub fn new(image: &Image, reference: &Image, kind: ErrorKind) -> Result<Self> {
        check_pair(image, reference)?;
        let values = image
            .pixels()
            .iter()
            .zip(reference.pixels())
            .map(|(x, r)| {
                let mut s = 0.0f64;
                for c in 0..3 {
                    let (xv, rv) = (f64::from(x[c]), f64::from(r[c]));
                    s += match kind {
                        ErrorKind::Absolute => (xv - rv).abs(),
                        ErrorKind::Relative => (xv - rv).powi(2) / (rv * rv + REL_EPSILON),
                    };
                }
                let m = s / 3.0;
                (if kind == ErrorKind::Relative {
                    m.sqrt()
                } else {
                    m
                }) as f32
            })
            .collect();
        Ok(Self {
            width: reference.width(),
            height: reference.height(),
            kind,
            values,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The kind of error held.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The values, row-major.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The value at pixel (x, y). Panics when out of range.
    pub fn get(&self, x: u32, y: u32) -> f32 {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside"
        );
        self.values[y as usize * self.width as usize + x as usize]
    }

    /// The `p`-th percentile (nearest rank, `p` in [0, 1]) of the values; 0 for an empty map.
    pub fn percentile(&self, p: f32) -> f32 {
        let mut v = self.values.clone();
        if v.is_empty() {
            return 0.0;
        }
        let rank = ((p.clamp(0.0, 1.0) * v.len() as f32).ceil() as usize).clamp(1, v.len()) - 1;
        *v.select_nth_unstable_by(rank, f32::total_cmp).1
    }
}

/// A perceptual colour map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Palette {
    /// matplotlib's viridis (dark blue to yellow).
    #[default]
    Viridis,
    /// matplotlib's magma (black to light yellow through purple).
    Magma,
    /// matplotlib's inferno (black to light yellow through red).
    Inferno,
}

impl Palette {
    /// The colour at `t` in [0, 1] (clamped), 8-bit sRGB.
    pub fn colour(self, t: f64) -> [u8; 3] {
        let g = match self {
            Palette::Viridis => colorous::VIRIDIS,
            Palette::Magma => colorous::MAGMA,
            Palette::Inferno => colorous::INFERNO,
        };
        let c = g.eval_continuous(if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) });
        [c.r, c.g, c.b]
    }
}

/// A linear colour scale: `min` maps to the palette's first colour, `max` to its last.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    min: f32,
    max: f32,
    palette: Palette,
    kind: ErrorKind,
}

impl Scale {
    /// A scale from `min` to `max` (finite, `min < max`) for errors of `kind`.
    pub fn new(min: f32, max: f32, palette: Palette, kind: ErrorKind) -> Result<Self> {
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(CompositeError::Parameter {
                name: "colour scale max",
                value: f64::from(max),
                reason: "min and max must be finite with min < max",
            });
        }
        Ok(Self {
            min,
            max,
            palette,
            kind,
        })
    }

    /// A scale from 0 to the largest `percentile` (in [0, 1]) over all `maps` (all of one
    /// kind), so that one scale serves every difference panel of a sheet; 0.99 keeps a few
    /// outlier pixels from washing out the rest. Falls back to a maximum of 1e-6 when every
    /// error is 0.
    pub fn shared(maps: &[&ErrorMap], percentile: f32, palette: Palette) -> Result<Self> {
        let Some(first) = maps.first() else {
            return Err(CompositeError::Empty {
                what: "error map list".into(),
            });
        };
        let max = maps
            .iter()
            .map(|m| m.percentile(percentile))
            .fold(0.0f32, f32::max);
        Self::new(0.0, max.max(1e-6), palette, first.kind())
    }

    /// The value at the bottom of the scale.
    pub fn min(&self) -> f32 {
        self.min
    }

    /// The value at the top of the scale.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The palette.
    pub fn palette(&self) -> Palette {
        self.palette
    }

    /// The kind of error the scale is for.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The colour of `value`, clamped to the scale.
    pub fn colour(&self, value: f32) -> [u8; 3] {
        let t =
            (f64::from(value) - f64::from(self.min)) / (f64::from(self.max) - f64::from(self.min));
        self.palette.colour(t)
    }

    /// The error map in false colour.
    pub fn apply(&self, map: &ErrorMap) -> Rgb8Image {
        Rgb8Image::from_fn(map.width(), map.height(), |x, y| self.colour(map.get(x, y)))
    }

    /// A vertical colour bar `width` x `height` pixels, `max` at the top row and `min` at the
    /// bottom row (the labels are drawn by the sheet).
    pub fn bar(&self, width: u32, height: u32) -> Rgb8Image {
        let d = height.saturating_sub(1).max(1) as f64;
        Rgb8Image::from_fn(width, height, |_, y| {
            self.palette.colour(1.0 - f64::from(y) / d)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn endpoints_of_the_maps() {
        // matplotlib's tables: viridis #440154 .. #fde725, magma #000004 .. #fcfdbf.
        assert_eq!(Palette::Viridis.colour(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(Palette::Viridis.colour(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(Palette::Magma.colour(0.0), [0x00, 0x00, 0x04]);
        assert_eq!(Palette::Magma.colour(1.0), [0xfc, 0xfd, 0xbf]);
        let s = Scale::new(0.5, 2.5, Palette::Viridis, ErrorKind::Absolute).unwrap();
        assert_eq!(s.colour(0.5), Palette::Viridis.colour(0.0));
        assert_eq!(s.colour(-3.0), Palette::Viridis.colour(0.0));
        assert_eq!(s.colour(2.5), Palette::Viridis.colour(1.0));
        assert_eq!(s.colour(99.0), Palette::Viridis.colour(1.0));
        assert_eq!(s.colour(1.5), Palette::Viridis.colour(0.5));
        let bar = s.bar(3, 11);
        assert_eq!(bar.get(0, 0), Palette::Viridis.colour(1.0));
        assert_eq!(bar.get(2, 10), Palette::Viridis.colour(0.0));
        assert!(Scale::new(1.0, 1.0, Palette::Viridis, ErrorKind::Absolute).is_err());
    }

    #[test]
    fn error_maps_by_hand() {
        let r = Image::from_fn(2, 1, |x, _| {
            if x == 0 {
                [1.0, 1.0, 1.0]
            } else {
                [0.0, 0.0, 0.0]
            }
        });
        let i = Image::from_fn(2, 1, |x, _| {
            if x == 0 {
                [1.3, 1.0, 0.7]
            } else {
                [0.1, 0.0, 0.0]
            }
        });
        let a = ErrorMap::new(&i, &r, ErrorKind::Absolute).unwrap();
        // (0.3 + 0 + 0.3) / 3 = 0.2 and (0.1 + 0 + 0) / 3 = 0.0333
        assert!((a.get(0, 0) - 0.2).abs() < 1e-6);
        assert!((a.get(1, 0) - 0.1 / 3.0).abs() < 1e-6);
        let rel = ErrorMap::new(&i, &r, ErrorKind::Relative).unwrap();
        // sqrt((0.09 / 1.01 * 2) / 3) = 0.243733; sqrt((0.01 / 0.01) / 3) = 0.577350
        assert!((rel.get(0, 0) - (0.18f32 / 1.01 / 3.0).sqrt()).abs() < 1e-6);
        assert!((rel.get(1, 0) - (1.0f32 / 3.0).sqrt()).abs() < 1e-5);
        let s = Scale::shared(&[&a, &rel], 1.0, Palette::Magma).unwrap();
        assert!((s.max() - rel.get(1, 0)).abs() < 1e-6);
        let mut bad = r.clone();
        bad.set(1, 0, Vec3::NAN);
        assert!(matches!(
            ErrorMap::new(&i, &bad, ErrorKind::Absolute),
            Err(CompositeError::NonFinite { .. })
        ));
    }
}
