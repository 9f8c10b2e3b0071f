//! Cook-Torrance (1981): f = rho / pi + s F(wo.h) G(wo, wi, h) D(h) / (4 cos(theta_o) cos(theta_i))
//! with Beckmann D ([`crate::beckmann`]), V-cavity G ([`crate::v_cavity`]) and the exact
//! unpolarized Fresnel of a complex index, or Schlick's approximation ([`crate::fresnel`]).
//!
//! | parameter | unit | range |
//! | --- | --- | --- |
//! | `rho` (diffuse) | dimensionless, per channel | [0, 1) |
//! | `s` (specular weight) | dimensionless, per channel | [0, 1], rho + s <= 1 |
//! | `m` (roughness) | dimensionless RMS slope | finite, > 0 (useful 1e-4 to 2) |
//! | `ior` | n + i k per channel | n > 0, k >= 0 |
//!
//! Reciprocal; energy is lost at high roughness because single-scattering microfacet models drop
//! the light that bounces more than once between facets (measured in the crate README).
//! Sampling draws h from D(h) cos(theta_h) and reflects wo about it.

use glam::{Vec2, Vec3};

use crate::beckmann::Beckmann;
use crate::colour::mean;
use crate::frame::{COS_FLOOR, half_vector, reflect_about_half, reflected_pdf, symmetric_dot};
use crate::fresnel::{self, FresnelModel};
use crate::interface::{Glossy, impl_brdf_via_glossy};
use crate::param::{check_diffuse, check_sum, check_unit};
use crate::{ComplexIor, ParamError, Rgb, v_cavity};

/// The Cook-Torrance BRDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CookTorrance {
    rho: Rgb,
    s: Rgb,
    d: Beckmann,
    ior: ComplexIor,
    fresnel: FresnelModel,
}

impl CookTorrance {
    /// Diffuse `rho` in [0, 1), specular weight `s` in [0, 1] with rho + s <= 1, Beckmann
    /// roughness `m` > 0, complex index `ior`, and the Fresnel evaluation.
    pub fn new(
        rho: Rgb,
        s: Rgb,
        m: f32,
        ior: ComplexIor,
        fresnel: FresnelModel,
    ) -> Result<Self, ParamError> {
        check_diffuse(rho)?;
        check_unit("specular", s)?;
        check_sum(rho, s)?;
        let d = Beckmann::new(m)?;
        let ior = ComplexIor::new(ior.n, ior.k)?;
        Ok(Self {
            rho,
            s,
            d,
            ior,
            fresnel,
        })
    }

    pub(crate) fn new_unchecked(
        rho: Rgb,
        s: Rgb,
        m: f32,
        ior: ComplexIor,
        fresnel: FresnelModel,
    ) -> Self {
        Self {
            rho,
            s,
            d: Beckmann::new_unchecked(m),
            ior,
            fresnel,
        }
    }

    /// Fresnel reflectance per channel at `cos` against the half vector.
    pub fn fresnel(&self, cos: f32) -> Rgb {
        match self.fresnel {
            FresnelModel::Exact => fresnel::complex_rgb(cos, &self.ior),
            FresnelModel::Schlick => fresnel::schlick_rgb(cos, &self.ior),
        }
    }

    /// The microfacet distribution.
    pub fn distribution(&self) -> &Beckmann {
        &self.d
    }
}

impl Glossy for CookTorrance {
    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(h) = half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let d = self.d.d(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = v_cavity::g(wo, wi, h);
        let vh = symmetric_dot(wo, wi, h);
        let scale = d * g / (4.0 * wo.z.max(COS_FLOOR) * wi.z.max(COS_FLOOR));
        self.s * self.fresnel(vh) * scale
    }
    fn sample_glossy(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        reflect_about_half(wo, self.d.sample(u))
    }
    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32 {
        reflected_pdf(wo, wi, |h| self.d.pdf(h))
    }
    fn glossy_weight(&self, wo: Vec3) -> f32 {
        mean(self.s * self.fresnel(wo.z))
    }
}

impl_brdf_via_glossy!(CookTorrance);
