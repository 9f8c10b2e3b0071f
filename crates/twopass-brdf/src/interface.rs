//! The BRDF interface ([`Brdf`], [`BrdfSample`], [`SampleKind`]), its two directional albedos
//! ([`incident_albedo`], [`outgoing_albedo`], by the quadrature of [`crate::quadrature`]) and
//! the diffuse-plus-glossy mixture every glossy model shares (`Glossy`, implemented into [`Brdf`] by one macro). The
//! closed set of models is [`crate::model::BrdfModel`].
//!
//! # Conventions
//! - Directions are unit vectors in the local shading frame (+z = normal), both pointing away
//!   from the surface: `wo` towards the viewer (outgoing), `wi` towards the light (incident).
//! - [`Brdf::eval`] returns f_r(wo, wi) in 1/sr **without** the cosine factor; an integrator
//!   multiplies by cos theta_i itself.
//! - Every method returns zero (or `None`) when `wo.z <= 0`, `wi.z <= 0`, or the sample has zero
//!   density, and never returns NaN or infinity for any input direction.
//! - A sample carries `weight = f cos theta_i / pdf`, the factor a path tracer multiplies its
//!   throughput by.

use glam::{Vec2, Vec3};

use crate::Rgb;
use crate::colour::mean;
use crate::frame::reflect;
use crate::quadrature::{Quadrature, integrate_dvec3};
use crate::sample::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};

/// Which lobe produced a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleKind {
    /// The Lambertian part (cosine-weighted hemisphere).
    Diffuse,
    /// A glossy lobe (Phong, Blinn-Phong, Cook-Torrance); `pdf` is a solid-angle density.
    Glossy,
    /// A delta reflection (mirror, smooth conductor or dielectric); `pdf` is the discrete
    /// probability of having chosen this branch, not a density.
    SpecularReflection,
    /// A delta refraction through a smooth dielectric; `pdf` is the discrete branch probability.
    SpecularTransmission,
}

impl SampleKind {
    /// Whether the sample comes from a delta lobe (its `pdf` is a probability, not a density).
    pub fn is_delta(self) -> bool {
        matches!(
            self,
            SampleKind::SpecularReflection | SampleKind::SpecularTransmission
        )
    }
}

/// A sampled incident direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfSample {
    /// The sampled direction `wi` (unit, local frame).
    pub wi: Vec3,
    /// f cos theta_i / pdf per channel (dimensionless): the throughput factor.
    pub weight: Rgb,
    /// Solid-angle density of `wi` (1/sr) for glossy and diffuse samples; the discrete branch
    /// probability for delta samples.
    pub pdf: f32,
    /// Which lobe produced it.
    pub kind: SampleKind,
}

/// A reflection model in the local frame. See the module documentation for the conventions
/// (cosine excluded from `eval`, zero below the horizon, total evaluation).
pub trait Brdf {
    /// f_r(wo, wi) in 1/sr per channel, without the cosine factor.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb;

    /// Samples `wi` for the given `wo` from `u` in [0, 1)^2; `None` when the sample falls below
    /// the horizon or has zero density.
    fn sample(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample>;

    /// Solid-angle density (1/sr) with which [`Brdf::sample`] produces `wi`. It integrates to
    /// the probability that `sample` succeeds (1 when no lobe mass falls below the horizon).
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;

    /// Hemispherical-directional reflectance seen from `wo`, the integral over `wi` of
    /// f(wo, wi) cos theta_i (dimensionless): the mean sample weight. For reciprocal models it
    /// equals the energy albedo [`incident_albedo`]; for the published Phong it does not.
    /// The default is deterministic quadrature ([`outgoing_albedo`]).
    fn albedo(&self, wo: Vec3) -> Rgb {
        outgoing_albedo(self, wo, Quadrature::default())
    }
}

/// Energy albedo for light arriving from `wi`: the integral over `wo` of f(wo, wi) cos theta_o
/// (dimensionless, per channel). At most 1 for an energy-conserving model.
pub fn incident_albedo<B: Brdf + ?Sized>(brdf: &B, wi: Vec3, q: Quadrature) -> Rgb {
    if wi.z <= 0.0 {
        return Rgb::ZERO;
    }
    integrate_dvec3(reflect(wi), q, |wo| (brdf.eval(wo, wi) * wo.z).as_dvec3()).as_vec3()
}

/// Hemispherical-directional reflectance seen from `wo`: the integral over `wi` of
/// f(wo, wi) cos theta_i (dimensionless, per channel); the default of [`Brdf::albedo`].
pub fn outgoing_albedo<B: Brdf + ?Sized>(brdf: &B, wo: Vec3, q: Quadrature) -> Rgb {
    if wo.z <= 0.0 {
        return Rgb::ZERO;
    }
    integrate_dvec3(reflect(wo), q, |wi| (brdf.eval(wo, wi) * wi.z).as_dvec3()).as_vec3()
}

/// The Lambertian part of a diffuse-plus-glossy mixture; [`impl_brdf_via_glossy`] implements
/// it from the model's `rho` field.
pub(crate) trait Diffuse {
    /// Diffuse reflectance rho.
    fn rho(&self) -> Rgb;
}

/// A BRDF made of a Lambertian part of reflectance rho ([`Diffuse`]) plus one glossy lobe,
/// sampled as a one-sample mixture of the cosine hemisphere and the lobe's own warp.
pub(crate) trait Glossy: Diffuse {
    /// The glossy term alone, for directions both above the horizon.
    fn eval_glossy(&self, wo: Vec3, wi: Vec3) -> Rgb;
    /// A direction from the lobe's warp (may be below the horizon: rejected by the caller).
    fn sample_glossy(&self, wo: Vec3, u: Vec2) -> Option<Vec3>;
    /// Density of [`Glossy::sample_glossy`] for directions both above the horizon.
    fn pdf_glossy(&self, wo: Vec3, wi: Vec3) -> f32;
    /// Relative weight of the lobe when choosing which part to sample (>= 0).
    fn glossy_weight(&self, wo: Vec3) -> f32;
}

/// Probability of sampling the diffuse part.
fn diffuse_probability<G: Glossy>(g: &G, wo: Vec3) -> f32 {
    let d = mean(g.rho()).max(0.0);
    let s = g.glossy_weight(wo).max(0.0);
    if d + s > 0.0 { d / (d + s) } else { 0.0 }
}

pub(crate) fn mix_eval<G: Glossy>(g: &G, wo: Vec3, wi: Vec3) -> Rgb {
    if !crate::frame::both_above(wo, wi) {
        return Rgb::ZERO;
    }
    let f = g.rho() * std::f32::consts::FRAC_1_PI + g.eval_glossy(wo, wi);
    f.max(Rgb::ZERO)
}

pub(crate) fn mix_pdf<G: Glossy>(g: &G, wo: Vec3, wi: Vec3) -> f32 {
    if !crate::frame::both_above(wo, wi) {
        return 0.0;
    }
    let pd = diffuse_probability(g, wo);
    let mut pdf = 0.0;
    if pd > 0.0 {
        pdf += pd * cosine_hemisphere_pdf(wi);
    }
    if pd < 1.0 && g.glossy_weight(wo) > 0.0 {
        pdf += (1.0 - pd) * g.pdf_glossy(wo, wi);
    }
    if pdf.is_finite() { pdf } else { 0.0 }
}

pub(crate) fn mix_sample<G: Glossy>(g: &G, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let pd = diffuse_probability(g, wo);
    let glossy = g.glossy_weight(wo) > 0.0;
    if pd <= 0.0 && !glossy {
        return None;
    }
    const ONE_MINUS: f32 = 1.0 - f32::EPSILON / 2.0;
    let (wi, kind) = if u.x < pd {
        let ux = (u.x / pd).min(ONE_MINUS);
        (
            square_to_cosine_hemisphere(Vec2::new(ux, u.y)),
            SampleKind::Diffuse,
        )
    } else {
        let ux = ((u.x - pd) / (1.0 - pd)).clamp(0.0, ONE_MINUS);
        (g.sample_glossy(wo, Vec2::new(ux, u.y))?, SampleKind::Glossy)
    };
    if wi.z <= 0.0 {
        return None;
    }
    let pdf = mix_pdf(g, wo, wi);
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    let weight = mix_eval(g, wo, wi) * (wi.z / pdf);
    weight.is_finite().then_some(BrdfSample {
        wi,
        weight,
        pdf,
        kind,
    })
}

/// Implements [`Brdf`] for a [`Glossy`] model through the mixture helpers.
macro_rules! impl_brdf_via_glossy {
    ($t:ty) => {
        impl $crate::interface::Diffuse for $t {
            fn rho(&self) -> $crate::Rgb {
                self.rho
            }
        }
        impl $crate::interface::Brdf for $t {
            fn eval(&self, wo: glam::Vec3, wi: glam::Vec3) -> $crate::Rgb {
                $crate::interface::mix_eval(self, wo, wi)
            }
            fn sample(
                &self,
                wo: glam::Vec3,
                u: glam::Vec2,
            ) -> Option<$crate::interface::BrdfSample> {
                $crate::interface::mix_sample(self, wo, u)
            }
            fn pdf(&self, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
                $crate::interface::mix_pdf(self, wo, wi)
            }
        }
    };
}
pub(crate) use impl_brdf_via_glossy;
