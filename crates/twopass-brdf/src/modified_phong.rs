//! Normalized modified Phong (Lafortune & Willems 1994):
//! f = rho / pi + k_s (n + 2) / (2 pi) cos^n(alpha), alpha between wi and the mirror direction
//! of wo (clamped at 0).
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `rho` (diffuse) | dimensionless, per channel | [0, 1) |
//! | `ks` (specular) | dimensionless, per channel | [0, 1], rho + ks <= 1 |
//! | `n` (exponent) | dimensionless | [0, 1e6] |
//!
//! Reciprocal (cos alpha is symmetric in wi and wo). The specular albedo is largest at normal
//! incidence where it equals k_s exactly, so rho + k_s <= 1 conserves energy.

use std::f32::consts::TAU;

use glam::Vec3;

use crate::interface::impl_brdf_via_glossy;
use crate::param::{check_diffuse, check_exponent, check_sum, check_unit};
use crate::phong::{MirrorLobe, lobe};
use crate::{ParamError, Rgb};

/// The normalized modified Phong BRDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModifiedPhong {
    rho: Rgb,
    ks: Rgb,
    n: f32,
}

impl ModifiedPhong {
    /// Diffuse `rho` in [0, 1), specular `ks` in [0, 1] with rho + ks <= 1, exponent `n` in
    /// [0, 1e6].
    pub fn new(rho: Rgb, ks: Rgb, n: f32) -> Result<Self, ParamError> {
        check_diffuse(rho)?;
        check_unit("specular", ks)?;
        check_exponent(n)?;
        check_sum(rho, ks)?;
        Ok(Self { rho, ks, n })
    }

    pub(crate) fn new_unchecked(rho: Rgb, ks: Rgb, n: f32) -> Self {
        Self { rho, ks, n }
    }
}

impl MirrorLobe for ModifiedPhong {
    fn ks_n(&self) -> (Rgb, f32) {
        (self.ks, self.n)
    }
    fn eval_lobe(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.ks * ((self.n + 2.0) / TAU * lobe(wo, wi, self.n))
    }
}

impl_brdf_via_glossy!(ModifiedPhong);
