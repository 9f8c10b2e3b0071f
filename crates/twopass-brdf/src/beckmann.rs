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

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::ParamError;
use crate::frame::sin2_theta;
use crate::sample::{beckmann_pdf, square_to_beckmann};

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

    /// A microfacet normal distributed as D(h) cos(theta_h).
    pub fn sample(&self, u: Vec2) -> Vec3 {
        square_to_beckmann(u, self.m)
    }

    /// Density (1/sr) of [`Beckmann::sample`]: D(h) cos(theta_h).
    pub fn pdf(&self, h: Vec3) -> f32 {
        beckmann_pdf(h, self.m)
    }
}
