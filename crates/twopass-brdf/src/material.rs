//! Materials: a diffuse part (what radiosity reads), an optional non-diffuse lobe (what the ray
//! tracer adds) and the ambient coefficient of the Phong shading form.

use glam::{Vec2, Vec3};

use crate::blinn_phong::BlinnPhong;
use crate::cook_torrance::CookTorrance;
use crate::delta::DeltaLobe;
use crate::fresnel::FresnelModel;
use crate::interface::{Brdf, BrdfSample};
use crate::lambert::Lambert;
use crate::model::BrdfModel;
use crate::modified_phong::ModifiedPhong;
use crate::param::{check_diffuse, check_exponent, check_sum, check_unit};
use crate::phong::Phong;
use crate::phong::PhongShading;
use crate::{ComplexIor, ParamError, Rgb};

/// Parameters of a Phong material (Phong 1975), as published or normalized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhongParams {
    /// Diffuse reflectance rho per channel, in [0, 1). The Phong k_d (1/sr) is rho / pi.
    pub diffuse: Rgb,
    /// Specular coefficient k_s per channel, in [0, 1].
    pub specular: Rgb,
    /// Phong exponent n (dimensionless), in [0, 1e6].
    pub exponent: f32,
    /// Ambient coefficient k_a per channel, in [0, 1], used by the Whitted ambient term.
    pub ambient: Rgb,
    /// `false`: the published model, k_s cos^n(alpha) / cos(theta_i) (not reciprocal, not
    /// energy conserving). `true`: normalized modified Phong (Lafortune & Willems 1994).
    pub normalized: bool,
}

/// Parameters of a Blinn-Phong material (Blinn 1977), classic or normalized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlinnPhongParams {
    /// Diffuse reflectance rho per channel, in [0, 1).
    pub diffuse: Rgb,
    /// Specular coefficient k_s per channel, in [0, 1].
    pub specular: Rgb,
    /// Exponent n' of (N.H)^n' (dimensionless), in [0, 1e6].
    pub exponent: f32,
    /// `false`: the classic shading form; `true`: the normalized, reciprocal form.
    pub normalized: bool,
}

/// Parameters of a Cook-Torrance material (Cook & Torrance 1981).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CookTorranceParams {
    /// Diffuse reflectance rho per channel, in [0, 1).
    pub diffuse: Rgb,
    /// Weight s of the specular lobe per channel, in [0, 1].
    pub specular: Rgb,
    /// Beckmann RMS facet slope m (dimensionless), finite and > 0 (useful range 1e-4 to 2).
    pub roughness: f32,
    /// Complex relative index of refraction of the surface.
    pub ior: ComplexIor,
    /// Exact or Schlick Fresnel.
    pub fresnel: FresnelModel,
}

/// The non-diffuse part of a material: a glossy lobe evaluated against emitters, or a delta
/// lobe followed by the Whitted tracer.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Lobe {
    /// Phong specular lobe, published or normalized.
    Phong {
        /// Specular coefficient k_s per channel.
        specular: Rgb,
        /// Exponent n.
        exponent: f32,
        /// Normalized modified Phong instead of the published form.
        normalized: bool,
    },
    /// Blinn-Phong specular lobe around the half vector.
    BlinnPhong {
        /// Specular coefficient k_s per channel.
        specular: Rgb,
        /// Exponent n'.
        exponent: f32,
        /// Normalized form instead of the classic one.
        normalized: bool,
    },
    /// Cook-Torrance microfacet lobe.
    CookTorrance {
        /// Lobe weight s per channel.
        specular: Rgb,
        /// Beckmann RMS slope m.
        roughness: f32,
        /// Complex index of refraction.
        ior: ComplexIor,
        /// Fresnel evaluation.
        fresnel: FresnelModel,
    },
    /// Perfect mirror with a per-channel reflectance.
    Mirror {
        /// Reflectance per channel, in [0, 1].
        reflectance: Rgb,
    },
    /// Smooth dielectric interface (reflection and refraction, exact Fresnel).
    Dielectric {
        /// Real relative index of refraction, inside over outside.
        ior: f32,
    },
    /// Smooth conductor: a mirror whose reflectance is the exact Fresnel of a complex index.
    Conductor {
        /// Complex index of refraction.
        ior: ComplexIor,
    },
}

/// A validated material: diffuse reflectance, optional non-diffuse lobe, ambient coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    diffuse: Rgb,
    ambient: Rgb,
    lobe: Option<Lobe>,
}

impl Material {
    /// A Lambertian material of diffuse reflectance `diffuse` in [0, 1).
    pub fn lambert(diffuse: Rgb) -> Result<Self, ParamError> {
        check_diffuse(diffuse)?;
        Ok(Self {
            diffuse,
            ambient: diffuse,
            lobe: None,
        })
    }

    /// A Phong material. The published form accepts any k_s in [0, 1]; the normalized form also
    /// requires diffuse + specular <= 1.
    pub fn phong(p: PhongParams) -> Result<Self, ParamError> {
        let lobe = (p.specular, p.exponent, p.normalized);
        Self::exponent_lobe(Form::Phong, p.diffuse, Some(p.ambient), lobe)
    }

    /// A Blinn-Phong material; the normalized form requires diffuse + specular <= 1.
    pub fn blinn_phong(p: BlinnPhongParams) -> Result<Self, ParamError> {
        let lobe = (p.specular, p.exponent, p.normalized);
        Self::exponent_lobe(Form::BlinnPhong, p.diffuse, None, lobe)
    }

    /// A material whose lobe has a Phong-style exponent, `form`, with (specular, exponent,
    /// normalized); `ambient` is Phong's own term (the diffuse reflectance otherwise).
    /// Validated in the order errors are reported: diffuse, specular, the ambient term, the
    /// exponent, and for the normalized forms diffuse + specular <= 1.
    fn exponent_lobe(
        form: Form,
        diffuse: Rgb,
        ambient: Option<Rgb>,
        (specular, exponent, normalized): (Rgb, f32, bool),
    ) -> Result<Self, ParamError> {
        check_diffuse(diffuse)?;
        check_unit("specular", specular)?;
        if let Some(ambient) = ambient {
            check_unit("ambient", ambient)?;
        }
        check_exponent(exponent)?;
        if normalized {
            check_sum(diffuse, specular)?;
        }
        let lobe = match form {
            Form::Phong => Lobe::Phong {
                specular,
                exponent,
                normalized,
            },
            Form::BlinnPhong => Lobe::BlinnPhong {
                specular,
                exponent,
                normalized,
            },
        };
        let ambient = ambient.unwrap_or(diffuse);
        Ok(Self::glossy(diffuse, ambient, specular, lobe))
    }

    /// A Cook-Torrance material; requires roughness > 0 and diffuse + specular <= 1.
    pub fn cook_torrance(p: CookTorranceParams) -> Result<Self, ParamError> {
        check_diffuse(p.diffuse)?;
        check_unit("specular", p.specular)?;
        check_sum(p.diffuse, p.specular)?;
        if !(p.roughness.is_finite() && p.roughness > 0.0) {
            return Err(ParamError::new(
                "roughness",
                p.roughness.into(),
                "finite and > 0",
            ));
        }
        let ior = ComplexIor::new(p.ior.n, p.ior.k)?;
        let lobe = Lobe::CookTorrance {
            specular: p.specular,
            roughness: p.roughness,
            ior,
            fresnel: p.fresnel,
        };
        Ok(Self::glossy(p.diffuse, p.diffuse, p.specular, lobe))
    }

    /// A perfect mirror of per-channel `reflectance` in [0, 1].
    pub fn mirror(reflectance: Rgb) -> Result<Self, ParamError> {
        check_unit("reflectance", reflectance)?;
        Ok(Self::with_delta(Lobe::Mirror { reflectance }))
    }

    /// A smooth dielectric of real relative index `ior` (finite, > 0).
    pub fn dielectric(ior: f32) -> Result<Self, ParamError> {
        ComplexIor::dielectric(ior)?;
        Ok(Self::with_delta(Lobe::Dielectric { ior }))
    }

    /// A smooth conductor of complex index `ior`.
    pub fn conductor(ior: ComplexIor) -> Result<Self, ParamError> {
        let ior = ComplexIor::new(ior.n, ior.k)?;
        Ok(Self::with_delta(Lobe::Conductor { ior }))
    }

    /// A diffuse part with a glossy `lobe` of reflectance `specular`; no lobe at all when
    /// `specular` is zero in every channel.
    fn glossy(diffuse: Rgb, ambient: Rgb, specular: Rgb, lobe: Lobe) -> Self {
        Self {
            diffuse,
            ambient,
            lobe: nonzero(specular).then_some(lobe),
        }
    }

    fn with_delta(lobe: Lobe) -> Self {
        Self {
            diffuse: Rgb::ZERO,
            ambient: Rgb::ZERO,
            lobe: Some(lobe),
        }
    }

    /// The material with its diffuse reflectance and ambient coefficient multiplied per
    /// channel by `tint` (each channel clamped to [0, 1]): a base colour texture's value where a
    /// surface is shaded, the material's own reflectance being the texture's factor. Scaling
    /// the diffuse part down keeps every constructor's bound (rho < 1, diffuse + specular <= 1);
    /// the non-diffuse lobe is unchanged.
    pub fn tinted(&self, tint: Rgb) -> Self {
        let t = Rgb::from_array(
            tint.to_array()
                .map(|c| if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) }),
        );
        Self {
            diffuse: self.diffuse * t,
            ambient: self.ambient * t,
            lobe: self.lobe,
        }
    }

    /// The Lambertian reflectance rho per channel, in [0, 1): what radiosity reads.
    pub fn diffuse_albedo(&self) -> Rgb {
        self.diffuse
    }

    /// The ambient coefficient k_a per channel of the Phong shading form (equal to the diffuse
    /// reflectance for models that do not name one).
    pub fn ambient(&self) -> Rgb {
        self.ambient
    }

    /// The non-diffuse lobe, if any.
    pub fn lobe(&self) -> Option<&Lobe> {
        self.lobe.as_ref()
    }

    /// Whether the material has any non-diffuse term: what the planner reads to skip the
    /// specular pass.
    pub fn has_non_diffuse(&self) -> bool {
        self.lobe.is_some()
    }

    /// Whether the material reflects any light diffusely (any channel of rho above 0).
    pub fn reflects_diffusely(&self) -> bool {
        nonzero(self.diffuse)
    }
}

/// The two lobes with a Phong-style exponent, as [`Material::exponent_lobe`] builds them.
#[derive(Clone, Copy)]
enum Form {
    /// Around the mirror direction ([`Lobe::Phong`]).
    Phong,
    /// Around the normal, of the half vector ([`Lobe::BlinnPhong`]).
    BlinnPhong,
}

fn nonzero(v: Rgb) -> bool {
    v.max_element() > 0.0
}

impl Lobe {
    /// Whether the lobe is a delta lobe (mirror, smooth dielectric, smooth conductor), followed
    /// by the Whitted tracer rather than evaluated against emitters.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Lobe::Mirror { .. } | Lobe::Dielectric { .. } | Lobe::Conductor { .. }
        )
    }

    /// The glossy lobe alone as a BRDF (no diffuse part), or `None` for a delta lobe.
    pub fn glossy(&self) -> Option<BrdfModel> {
        self.model_with(Rgb::ZERO)
    }

    /// The delta lobe, or `None` for a glossy lobe.
    pub fn delta(&self) -> Option<DeltaLobe> {
        match *self {
            Lobe::Mirror { reflectance } => Some(DeltaLobe::Mirror { reflectance }),
            Lobe::Dielectric { ior } => Some(DeltaLobe::Dielectric { eta: ior }),
            Lobe::Conductor { ior } => Some(DeltaLobe::Conductor { ior }),
            _ => None,
        }
    }

    /// The lobe plus a Lambertian part of reflectance `rho` as one BRDF (parameters were
    /// validated by the material constructors).
    fn model_with(&self, rho: Rgb) -> Option<BrdfModel> {
        Some(match *self {
            Lobe::Phong {
                specular,
                exponent,
                normalized: false,
            } => BrdfModel::Phong(Phong::new_unchecked(rho, specular, exponent)),
            Lobe::Phong {
                specular,
                exponent,
                normalized: true,
            } => BrdfModel::ModifiedPhong(ModifiedPhong::new_unchecked(rho, specular, exponent)),
            Lobe::BlinnPhong {
                specular,
                exponent,
                normalized,
            } => BrdfModel::BlinnPhong(BlinnPhong::new_unchecked(
                rho, specular, exponent, normalized,
            )),
            Lobe::CookTorrance {
                specular,
                roughness,
                ior,
                fresnel,
            } => BrdfModel::CookTorrance(CookTorrance::new_unchecked(
                rho, specular, roughness, ior, fresnel,
            )),
            Lobe::Mirror { .. } | Lobe::Dielectric { .. } | Lobe::Conductor { .. } => return None,
        })
    }
}

/// Rendering with a material. Directions are local (+z = normal); values in 1/sr without the
/// cosine, as for [`Brdf`]. The hybrid renderer adds only [`Material::eval_non_diffuse`] on top
/// of radiosity, which already holds [`Material::eval_diffuse`]; a path tracer uses
/// [`Material::sample`] and [`Material::eval`] for the whole material.
impl Material {
    /// The whole non-delta BRDF (diffuse part plus glossy lobe), or `None` for a material whose
    /// lobe is a delta lobe.
    pub fn model(&self) -> Option<BrdfModel> {
        match &self.lobe {
            None => Some(BrdfModel::Lambert(Lambert::new_unchecked(self.diffuse))),
            Some(l) => l.model_with(self.diffuse),
        }
    }

    /// The delta lobe, if the material has one.
    pub fn delta(&self) -> Option<DeltaLobe> {
        self.lobe.as_ref().and_then(Lobe::delta)
    }

    /// Whether the material is a smooth dielectric: it refracts, and is seen from both sides.
    pub fn is_dielectric(&self) -> bool {
        matches!(self.lobe, Some(Lobe::Dielectric { .. }))
    }

    /// The diffuse part rho / pi (1/sr); zero below the horizon.
    pub fn eval_diffuse(&self, wo: Vec3, wi: Vec3) -> Rgb {
        Lambert::new_unchecked(self.diffuse).eval(wo, wi)
    }

    /// The non-diffuse glossy part (1/sr): the lobe without the diffuse term; zero for Lambert
    /// and for delta lobes (which are followed with [`Material::delta`], not evaluated).
    pub fn eval_non_diffuse(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self.lobe.as_ref().and_then(Lobe::glossy) {
            Some(m) => m.eval(wo, wi),
            None => Rgb::ZERO,
        }
    }

    /// The whole BRDF value, diffuse plus glossy (1/sr); delta lobes contribute nothing here.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self.model() {
            Some(m) => m.eval(wo, wi),
            None => self.eval_diffuse(wo, wi),
        }
    }

    /// Samples the whole material: the diffuse/glossy mixture, or the delta lobe (whose sample
    /// `pdf` is a branch probability, see [`crate::SampleKind::is_delta`]).
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
        match self.delta() {
            Some(d) => d.sample(wo, u),
            None => self.model()?.sample(wo, u),
        }
    }

    /// Solid-angle density of [`Material::sample`] for non-delta materials (1/sr); zero for
    /// delta materials, whose directions have no density.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.model() {
            Some(m) if self.delta().is_none() => m.pdf(wo, wi),
            _ => 0.0,
        }
    }
}

// Read from a material here, beside `Material`, as the material builds every model: the models'
// files then need not know the material type (no import circle between them).
impl PhongShading {
    /// The shading terms of a material: its k_a, rho / pi, and for a Phong lobe (published or
    /// normalized) its k_s and n as written; for other materials k_s = 0.
    pub fn from_material(m: &Material) -> Self {
        let (specular, exponent) = match m.lobe() {
            Some(Lobe::Phong {
                specular, exponent, ..
            }) => (*specular, *exponent),
            _ => (Rgb::ZERO, 0.0),
        };
        Self {
            ambient: m.ambient(),
            diffuse: m.diffuse_albedo() * std::f32::consts::FRAC_1_PI,
            specular,
            exponent,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tint scales the diffuse part and the ambient coefficient channel by channel, clamps
    /// out-of-range channels, and leaves the lobe alone.
    #[test]
    fn tint_scales_the_diffuse_part_only() {
        let m = Material::blinn_phong(BlinnPhongParams {
            diffuse: Rgb::new(0.5, 0.4, 0.2),
            specular: Rgb::splat(0.3),
            exponent: 20.0,
            normalized: false,
        })
        .expect("valid");
        let t = m.tinted(Rgb::new(0.5, 2.0, f32::NAN));
        assert_eq!(t.diffuse_albedo(), Rgb::new(0.25, 0.4, 0.0));
        assert_eq!(t.ambient(), Rgb::new(0.25, 0.4, 0.0));
        assert_eq!(t.lobe(), m.lobe());
    }

    /// A material with two bad parameters reports the first in the validators' order: diffuse,
    /// specular, Phong's ambient term, the exponent, then the normalized sum.
    #[test]
    fn two_bad_parameters_report_the_first_in_order() {
        let (rho, bad) = (Rgb::splat(0.5), Rgb::splat(2.0));
        let phong = |specular, ambient, exponent, normalized| {
            Material::phong(PhongParams {
                diffuse: rho,
                specular,
                exponent,
                ambient,
                normalized,
            })
        };
        let blinn = |specular, exponent, normalized| {
            Material::blinn_phong(BlinnPhongParams {
                diffuse: rho,
                specular,
                exponent,
                normalized,
            })
        };
        let sum = "such that diffuse + specular <= 1 on every channel";
        let cases = [
            (phong(bad, bad, 10.0, false), "specular", "in [0, 1]"),
            (phong(rho, bad, -1.0, false), "ambient", "in [0, 1]"),
            (
                phong(Rgb::splat(0.9), rho, -1.0, true),
                "exponent",
                "in [0, 1e6]",
            ),
            (
                phong(Rgb::splat(0.9), bad, 10.0, true),
                "ambient",
                "in [0, 1]",
            ),
            (phong(Rgb::splat(0.9), rho, 10.0, true), "specular", sum),
            (blinn(bad, -1.0, false), "specular", "in [0, 1]"),
            (
                blinn(Rgb::splat(0.9), -1.0, true),
                "exponent",
                "in [0, 1e6]",
            ),
            (blinn(Rgb::splat(0.9), 10.0, true), "specular", sum),
        ];
        for (i, (result, parameter, expected)) in cases.into_iter().enumerate() {
            let e = result.expect_err("two bad parameters");
            assert_eq!((e.parameter, e.expected), (parameter, expected), "case {i}");
        }
    }
}
