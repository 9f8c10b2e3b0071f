//! Phong as published (Phong 1975), kept exactly, flaws included.
//!
//! Shading form: I = I_amb k_a + I_in (k_d (L.N) + k_s (R_L.V)^n), R_L = 2 (L.N) N - L.
//! As a BRDF: f(wo, wi) = k_d + k_s cos^n(alpha) / cos(theta_i), with cos alpha = R_L . V
//! (clamped at 0), k_d = rho / pi.
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `rho` (diffuse) | dimensionless, per channel | [0, 1) |
//! | `ks` (specular) | dimensionless, per channel | [0, 1] |
//! | `n` (exponent) | dimensionless | [0, 1e6] |
//!
//! **Not reciprocal**: the 1/cos(theta_i) changes when wi and wo swap. **Not energy
//! conserving**: at normal incidence the specular albedo is k_s 2 pi / (n + 2) (pi k_s for
//! n = 0), and it grows without bound towards grazing incidence. Use
//! [`crate::modified_phong`] for a plausible Phong.

use glam::{Vec2, Vec3};

use crate::colour::mean;
use crate::frame::{COS_FLOOR, Frame, both_above, pow_one_minus, reflect};
use crate::interface::{Glossy, impl_brdf_via_glossy};
use crate::param::{check_diffuse, check_exponent, check_unit};
use crate::sample::square_to_phong_lobe;
use crate::{ParamError, Rgb};

/// 1 - cos alpha = |wi - R(wo)|^2 / 2, without cancellation near the mirror direction and
/// bit-identical under swapping the arguments.
#[inline]
pub(crate) fn one_minus_cos_alpha(wo: Vec3, wi: Vec3) -> f32 {
    let (x, y, z) = (wo.x + wi.x, wo.y + wi.y, wo.z - wi.z);
    0.5 * (x * x + y * y + z * z)
}

/// cos^n(alpha) (clamped at 0), accurate for exponents up to 1e6.
#[inline]
pub(crate) fn lobe(wo: Vec3, wi: Vec3, n: f32) -> f32 {
    pow_one_minus(one_minus_cos_alpha(wo, wi), n)
}

/// Samples the Phong lobe of exponent `n` around the mirror direction of `wo`.
pub(crate) fn sample_lobe_around_mirror(wo: Vec3, u: Vec2, n: f32) -> Option<Vec3> {
    let w = Frame::from_normal(reflect(wo)).to_world(square_to_phong_lobe(u, n));
    w.try_normalize()
}

/// Density of [`sample_lobe_around_mirror`] (1/sr).
pub(crate) fn lobe_around_mirror_pdf(wo: Vec3, wi: Vec3, n: f32) -> f32 {
    (n + 1.0) / std::f32::consts::TAU * lobe(wo, wi, n)
}

/// The glossy lobe of the Phong models (published and modified): k_s times a function of
/// cos^n(alpha) around the mirror direction, sampled with [`sample_lobe_around_mirror`] and
/// weighted by mean k_s in the mixture. Each model gives its k_s, n and lobe value; the
/// sampling and the weight are theirs in common (the [`Glossy`] impl below).
pub(crate) trait MirrorLobe {
    /// (k_s per channel, exponent n).
    fn ks_n(&self) -> (Rgb, f32);
    /// The lobe's BRDF value for directions both above the horizon (1/sr).
    fn eval_lobe(&self, wo: Vec3, wi: Vec3) -> Rgb;
}

impl<T: MirrorLobe + crate::interface::Diffuse> Glossy for T {
    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_lobe(wo, wi)
    }
    fn sample_glossy(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        sample_lobe_around_mirror(wo, u, self.ks_n().1)
    }
    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        lobe_around_mirror_pdf(wo, wi, self.ks_n().1)
    }
    fn glossy_weight(&self, _wo: Vec3) -> f32 {
        mean(self.ks_n().0)
    }
}

/// The published Phong BRDF k_d + k_s cos^n(alpha) / cos(theta_i).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phong {
    rho: Rgb,
    ks: Rgb,
    n: f32,
}

impl Phong {
    /// A published Phong BRDF: diffuse reflectance `rho` in [0, 1), specular `ks` in [0, 1],
    /// exponent `n` in [0, 1e6].
    pub fn new(rho: Rgb, ks: Rgb, n: f32) -> Result<Self, ParamError> {
        check_diffuse(rho)?;
        check_unit("specular", ks)?;
        check_exponent(n)?;
        Ok(Self { rho, ks, n })
    }

    pub(crate) fn new_unchecked(rho: Rgb, ks: Rgb, n: f32) -> Self {
        Self { rho, ks, n }
    }

    /// The specular term alone, k_s cos^n(alpha) / cos(theta_i) (1/sr).
    pub fn specular(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !both_above(wo, wi) {
            return Rgb::ZERO;
        }
        self.ks * (lobe(wo, wi, self.n) / wi.z.max(COS_FLOOR))
    }
}

impl MirrorLobe for Phong {
    fn ks_n(&self) -> (Rgb, f32) {
        (self.ks, self.n)
    }
    fn eval_lobe(&self, wo: Vec3, wi: Vec3) -> Rgb {
        self.specular(wo, wi)
    }
}

impl_brdf_via_glossy!(Phong);

/// The Phong shading form for the Whitted tracer:
/// I = I_amb k_a + sum over lights of I_in (k_d (L.N) + k_s (R_L.V)^n).
///
/// Units: with `ambient` = k_a = rho (dimensionless), `I_amb` an ambient radiance
/// (W/(m^2 sr)), `diffuse` = k_d = rho / pi (1/sr), and `I_in` the irradiance a light delivers
/// on a surface facing it (W/m^2), the result is a radiance (W/(m^2 sr)); each light's term is
/// exactly `I_in f_Phong(V, L) (L.N)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhongShading {
    /// k_a per channel (dimensionless).
    pub ambient: Rgb,
    /// k_d per channel (1/sr), rho / pi.
    pub diffuse: Rgb,
    /// k_s per channel (dimensionless).
    pub specular: Rgb,
    /// Exponent n (dimensionless).
    pub exponent: f32,
}

impl PhongShading {
    /// The ambient term I_amb k_a.
    pub fn ambient_term(&self, i_amb: Rgb) -> Rgb {
        i_amb * self.ambient
    }

    /// One light's term I_in (k_d (L.N) + k_s (R_L.V)^n) for local directions `wo` = V and
    /// `wi` = L; zero when either is below the horizon.
    pub fn light_term(&self, i_in: Rgb, wo: Vec3, wi: Vec3) -> Rgb {
        if !both_above(wo, wi) {
            return Rgb::ZERO;
        }
        i_in * (self.diffuse * wi.z + self.specular * lobe(wo, wi, self.exponent))
    }

    /// The whole shading form: ambient plus the sum over `lights` of (I_in, L).
    pub fn shade(&self, i_amb: Rgb, lights: &[(Rgb, Vec3)], wo: Vec3) -> Rgb {
        lights
            .iter()
            .fold(self.ambient_term(i_amb), |acc, &(i_in, wi)| {
                acc + self.light_term(i_in, wo, wi)
            })
    }
}
