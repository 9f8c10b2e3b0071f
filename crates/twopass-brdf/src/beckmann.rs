//! The Beckmann microfacet distribution of RMS slope m:
//! D(h) = exp(-tan^2(theta_h) / m^2) / (pi m^2 cos^4(theta_h))  (1/sr).
//!
//! The 1/pi that the illumination-models text drops is needed: with it the projected facet
//! area, the integral of D(h) cos(theta_h) over the hemisphere, is 1 (tested), and
//! D at the normal is 1 / (pi m^2).
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `m` (roughness) | dimensionless (RMS slope) | finite, > 0 (useful 1e-4 to 2) |

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::ParamError;
use crate::frame::{azimuth01, sin2_theta, spherical_direction, tan2_theta};

/// The Beckmann distribution of microfacet normals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beckmann {
    m: f32,
}

impl Beckmann {
    /// A distribution of RMS slope `m`, finite and > 0.
    pub fn new(m: f32) -> Result<Self, ParamError> {
        if m.is_finite() && m > 0.0 {
            Ok(Self { m })
        } else {
            Err(ParamError::new("roughness", m.into(), "finite and > 0"))
        }
    }

    pub(crate) fn new_unchecked(m: f32) -> Self {
        Self { m }
    }

    /// The RMS slope m.
    pub fn roughness(&self) -> f32 {
        self.m
    }

    /// D(h) (1/sr) for a unit microfacet normal `h` in the local frame; zero for h.z <= 0.
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let c2 = h.z * h.z;
        let m2 = self.m * self.m;
        let e = (-(sin2_theta(h) / c2) / m2).exp();
        if e == 0.0 {
            return 0.0;
        }
        let d = e / (PI * m2 * c2 * c2);
        if d.is_finite() { d } else { 0.0 }
    }

    /// A microfacet normal distributed as D(h) cos(theta_h), from `u` in [0, 1)^2:
    /// tan^2 theta = -m^2 ln(1 - u.x), phi = 2 pi u.y.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let m = self.m;
        let t2 = -m * m * (-u.x.clamp(0.0, 1.0)).ln_1p();
        let (sin, cos) = if t2.is_finite() {
            let inv = 1.0 / (1.0 + t2).sqrt();
            ((t2 / (1.0 + t2)).sqrt(), inv)
        } else {
            (1.0, 0.0)
        };
        spherical_direction(sin, cos, TAU * u.y)
    }

    /// Density (1/sr) of [`Beckmann::sample`]: D(h) cos(theta_h).
    pub fn pdf(&self, h: Vec3) -> f32 {
        self.d(h) * h.z.max(0.0)
    }

    /// The inverse of [`Beckmann::sample`]: the `u` that gives the normal `h`.
    pub fn sample_inverse(&self, h: Vec3) -> Vec2 {
        let t2 = tan2_theta(h);
        Vec2::new(-(-t2 / (self.m * self.m)).exp_m1(), azimuth01(h))
    }
}
