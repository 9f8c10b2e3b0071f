//! Blinn-Phong (Blinn 1977): the specular term uses the half vector H = (V + L) / |V + L|.
//!
//! - Classic form, the shading form k_s (N.H)^n' written as a BRDF the same way as the published
//!   Phong: f = rho / pi + k_s (N.H)^n' / cos(theta_i). Not reciprocal, not energy conserving.
//! - Normalized form: f = rho / pi + k_s c(n') (N.H)^n' with
//!   c(n') = (n' + 2)(n' + 4) / (8 pi (2^(-n'/2) + n')), the exact factor that makes the specular
//!   albedo at normal incidence equal k_s (Giesen 2009, "The Blinn-Phong normalization zoo").
//!   The popular (n' + 8) / (8 pi) is *not* used: it exceeds this factor for every n' > 0 (by 2.4%
//!   at n' = 1, 7.5% at n' = 10), so a surface with k_s = 1 would reflect more than it receives.
//!   Reciprocal (N.H is symmetric); the tests verify albedo <= k_s at every incidence.
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `rho` (diffuse) | dimensionless, per channel | [0, 1) |
//! | `ks` (specular) | dimensionless, per channel | [0, 1] (normalized: rho + ks <= 1) |
//! | `n` (exponent n') | dimensionless | [0, 1e6] |
//!
//! A Blinn-Phong highlight matches a Phong highlight of exponent n for n' = 4 n
//! ([`exponent_matching_phong`]): near the peak, cos^n(alpha) ~ exp(-n alpha^2 / 2) and, at
//! normal incidence, theta_h = alpha / 2 so (N.H)^4n ~ exp(-n alpha^2 / 2).

use glam::{Vec2, Vec3};

use crate::colour::mean;
use crate::frame::{COS_FLOOR, half_sin2, pow_one_minus, reflect_about_half, reflected_pdf};
use crate::interface::{Glossy, impl_brdf_via_glossy};
use crate::param::{check_diffuse, check_exponent, check_sum, check_unit};
use crate::sample::square_to_phong_lobe;
use crate::{ParamError, Rgb};

/// The Blinn-Phong exponent n' = 4 n whose highlight matches a Phong highlight of exponent `n`
/// at normal incidence (dimensionless). The mismatch away from normal incidence is measured in
/// the crate README.
pub fn exponent_matching_phong(n: f32) -> f32 {
    4.0 * n
}

/// The normalization c(n') (1/sr) of the normalized form: the inverse of the specular albedo
/// of (N.H)^n' at normal incidence, 8 pi (n' + 2^(-n'/2)) / ((n' + 2)(n' + 4)).
pub fn normalization(n: f32) -> f32 {
    let n = f64::from(n);
    ((n + 2.0) * (n + 4.0) / (8.0 * std::f64::consts::PI * ((-n / 2.0).exp2() + n))) as f32
}

/// The Blinn-Phong BRDF, classic or normalized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlinnPhong {
    rho: Rgb,
    ks: Rgb,
    n: f32,
    normalized: bool,
    norm: f32,
}

impl BlinnPhong {
    /// Diffuse `rho` in [0, 1), specular `ks` in [0, 1], exponent `n` in [0, 1e6]; the
    /// normalized form also requires rho + ks <= 1.
    pub fn new(rho: Rgb, ks: Rgb, n: f32, normalized: bool) -> Result<Self, ParamError> {
        check_diffuse(rho)?;
        check_unit("specular", ks)?;
        check_exponent(n)?;
        if normalized {
            check_sum(rho, ks)?;
        }
        Ok(Self::new_unchecked(rho, ks, n, normalized))
    }

    pub(crate) fn new_unchecked(rho: Rgb, ks: Rgb, n: f32, normalized: bool) -> Self {
        Self {
            rho,
            ks,
            n,
            normalized,
            norm: normalization(n),
        }
    }

    /// Whether this is the normalized (plausible) form.
    pub fn normalized(&self) -> bool {
        self.normalized
    }
}

impl Glossy for BlinnPhong {
    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(s2) = half_sin2(wo, wi) else {
            return Rgb::ZERO;
        };
        // (N.H)^n = (1 - sin^2 theta_h)^(n/2), accurate where N.H rounds to 1.
        let lobe = pow_one_minus(s2, 0.5 * self.n);
        if self.normalized {
            self.ks * (self.norm * lobe)
        } else {
            self.ks * (lobe / wi.z.max(COS_FLOOR))
        }
    }
    fn sample_glossy(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        reflect_about_half(wo, square_to_phong_lobe(u, self.n))
    }
    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        reflected_pdf(wo, wi, |_| {
            half_sin2(wo, wi).map_or(0.0, |s2| {
                (self.n + 1.0) / std::f32::consts::TAU * pow_one_minus(s2, 0.5 * self.n)
            })
        })
    }
    fn glossy_weight(&self, _wo: Vec3) -> f32 {
        mean(self.ks)
    }
}

impl_brdf_via_glossy!(BlinnPhong);
