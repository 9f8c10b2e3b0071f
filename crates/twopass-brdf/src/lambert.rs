//! Lambert: f = rho / pi (1/sr), rho the diffuse reflectance in [0, 1).
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `rho` | dimensionless, per channel | [0, 1) |
//!
//! Reciprocal, and its directional albedo is rho at every incidence.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use crate::frame::both_above;
use crate::interface::{Brdf, BrdfSample, SampleKind};
use crate::sample::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::{ParamError, Rgb, param};

/// The Lambertian BRDF rho / pi.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambert {
    rho: Rgb,
}

impl Lambert {
    /// A Lambertian BRDF of reflectance `rho` (per channel, in [0, 1)).
    pub fn new(rho: Rgb) -> Result<Self, ParamError> {
        param::check_diffuse(rho)?;
        Ok(Self { rho })
    }

    pub(crate) fn new_unchecked(rho: Rgb) -> Self {
        Self { rho }
    }

    /// The diffuse reflectance rho.
    pub fn rho(&self) -> Rgb {
        self.rho
    }
}

impl Brdf for Lambert {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if both_above(wo, wi) {
            self.rho * FRAC_1_PI
        } else {
            Rgb::ZERO
        }
    }

    fn sample(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
        if wo.z <= 0.0 || self.rho.max_element() <= 0.0 {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wi);
        (wi.z > 0.0 && pdf > 0.0).then_some(BrdfSample {
            wi,
            weight: self.rho,
            pdf,
            kind: SampleKind::Diffuse,
        })
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if both_above(wo, wi) && self.rho.max_element() > 0.0 {
            cosine_hemisphere_pdf(wi)
        } else {
            0.0
        }
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        if wo.z > 0.0 { self.rho } else { Rgb::ZERO }
    }
}
