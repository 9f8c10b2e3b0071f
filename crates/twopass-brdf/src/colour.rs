//! Colour: linear RGB ([`Rgb`], sRGB / Rec. 709 primaries) and its luminance, the one
//! home of the Rec. 709 weights in the workspace (ARCHITECTURE.md, "Where each idea lives").

use glam::{DVec3, Vec3};

/// Linear RGB triple, one value per channel (reflectance, radiance or power depending on use).
pub type Rgb = Vec3;

/// Rec. 709 luminance weights of linear RGB.
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The same weights in f64, for sums over many elements (the radiosity solvers' oracles).
pub const LUMINANCE_F64: DVec3 = DVec3::new(0.2126, 0.7152, 0.0722);

/// Relative luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of a linear RGB value (same unit as
/// the value).
#[inline]
pub fn luminance(rgb: Vec3) -> f32 {
    rgb.dot(LUMINANCE)
}

/// [`luminance`] in f64: `Y = 0.2126 R + 0.7152 G + 0.0722 B` (same unit as the value).
#[inline]
pub fn luminance_f64(rgb: DVec3) -> f64 {
    rgb.dot(LUMINANCE_F64)
}

/// The mean of the three channels (a lobe's weight when choosing which part to sample).
#[inline]
pub(crate) fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_has_unit_luminance_and_green_dominates() {
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
        assert_eq!(luminance(Vec3::new(0.0, 2.0, 0.0)), 2.0 * 0.7152);
    }
}
