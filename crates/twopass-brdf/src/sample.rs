//! Warps from the unit square to directions, their densities and their inverses.
//!
//! Every warp takes `u` in [0, 1)^2 and returns a unit direction in the local frame (+z up);
//! densities are per unit solid angle (1/sr). The inverses map a direction back to the `u` that
//! produces it, which the tests use to prove each warp is a bijection. The warp of a microfacet
//! distribution lives with the distribution ([`crate::beckmann::Beckmann::sample`]).

use std::f32::consts::{FRAC_1_PI, PI, TAU};

use glam::{Vec2, Vec3};

use crate::frame::{azimuth01, spherical_direction};

/// Cosine-weighted hemisphere (density cos theta / pi): sin^2 theta = u.x, phi = 2 pi u.y.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let s2 = u.x.clamp(0.0, 1.0);
    spherical_direction(s2.sqrt(), (1.0 - s2).sqrt(), TAU * u.y)
}

/// Density of [`square_to_cosine_hemisphere`] (1/sr), zero below the horizon.
pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    w.z.max(0.0) * FRAC_1_PI
}

/// Inverse of [`square_to_cosine_hemisphere`].
pub fn cosine_hemisphere_to_square(w: Vec3) -> Vec2 {
    Vec2::new((w.x * w.x + w.y * w.y).min(1.0), azimuth01(w))
}

/// The Phong lobe around +z, density (n + 1)/(2 pi) cos^n alpha on the upper hemisphere:
/// cos alpha = u.x^(1/(n+1)), phi = 2 pi u.y. Exponent `n` >= 0 (dimensionless).
pub fn square_to_phong_lobe(u: Vec2, n: f32) -> Vec3 {
    // cos = exp(ln(u) / (n + 1)); 1 - cos from expm1 keeps sin accurate for huge n.
    let l = u.x.clamp(0.0, 1.0).ln() / (n + 1.0);
    let cos = l.exp();
    let one_minus = -l.exp_m1();
    let sin = (one_minus * (1.0 + cos)).max(0.0).sqrt();
    spherical_direction(sin.min(1.0), cos, TAU * u.y)
}

/// Density of [`square_to_phong_lobe`] (1/sr) at a direction of cosine `cos_alpha` to the axis.
pub fn phong_lobe_pdf(cos_alpha: f32, n: f32) -> f32 {
    (n + 1.0) / TAU * crate::frame::pow_lobe(cos_alpha, n)
}

/// Inverse of [`square_to_phong_lobe`].
pub fn phong_lobe_to_square(w: Vec3, n: f32) -> Vec2 {
    Vec2::new(crate::frame::pow_lobe(w.z, n + 1.0), azimuth01(w))
}

/// Uniform density over the hemisphere, 1 / (2 pi) (1/sr).
pub const UNIFORM_HEMISPHERE_PDF: f32 = 0.5 / PI;
