//! Delta lobes for the Whitted tracer: the perfect mirror, the smooth dielectric (Snell
//! refraction, exact Fresnel, total internal reflection) and the smooth conductor.
//!
//! A delta lobe has no finite value to evaluate: it returns the rays to follow
//! ([`DeltaRay`]: direction and weight) and can be sampled by a path tracer. Weights are
//! dimensionless, per channel. The smooth dielectric also accepts `wo` below the surface (inside
//! the medium); the others return nothing for `wo.z <= 0`.

use glam::{Vec2, Vec3};

use crate::frame::reflect;
use crate::interface::{BrdfSample, SampleKind};
use crate::{ComplexIor, Rgb, fresnel};

/// A ray a delta lobe sends: the direction to trace (unit, local frame) and what the radiance
/// found there is multiplied by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeltaRay {
    /// Direction to trace, local frame.
    pub wi: Vec3,
    /// Per-channel factor on the radiance arriving from `wi` (dimensionless).
    pub weight: Rgb,
}

/// A delta lobe of a material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DeltaLobe {
    /// Perfect mirror of per-channel reflectance (dimensionless, [0, 1]).
    Mirror {
        /// Reflectance per channel.
        reflectance: Rgb,
    },
    /// Smooth dielectric of real relative index (inside over outside, > 0).
    Dielectric {
        /// Relative index of refraction eta.
        eta: f32,
    },
    /// Smooth conductor: a mirror of reflectance F(cos theta) for the complex index.
    Conductor {
        /// Complex relative index of refraction.
        ior: ComplexIor,
    },
}

impl DeltaLobe {
    /// The specular reflection of `wo`, weighted by the reflectance (Fresnel for the
    /// dielectric and the conductor). `None` when nothing is reflected.
    pub fn reflection(&self, wo: Vec3) -> Option<DeltaRay> {
        let weight = match *self {
            DeltaLobe::Mirror { reflectance } if wo.z > 0.0 => reflectance,
            DeltaLobe::Conductor { ior } if wo.z > 0.0 => fresnel::complex_rgb(wo.z, &ior),
            DeltaLobe::Dielectric { eta } if wo.z != 0.0 => {
                Rgb::splat(fresnel::dielectric(wo.z, eta))
            }
            _ => return None,
        };
        (weight.max_element() > 0.0).then_some(DeltaRay {
            wi: reflect(wo),
            weight,
        })
    }

    /// The refraction of `wo` through a smooth dielectric: direction on the other side and weight
    /// (1 - F) / eta_rel^2, where eta_rel = eta_t / eta_i, the radiance compression of
    /// transport across the interface (pbrt's radiance mode). `None` for other lobes and under
    /// total internal reflection.
    pub fn refraction(&self, wo: Vec3) -> Option<DeltaRay> {
        let DeltaLobe::Dielectric { eta } = *self else {
            return None;
        };
        let f = fresnel::dielectric(wo.z, eta);
        let (wt, eta_rel) = fresnel::refract(wo, eta)?;
        let t = (1.0 - f) / (eta_rel * eta_rel);
        (t > 0.0).then_some(DeltaRay {
            wi: wt,
            weight: Rgb::splat(t),
        })
    }

    /// One-sample choice between reflection and refraction for a path tracer: the dielectric
    /// picks reflection with probability F (`u.x < F`). The sample's `pdf` is the discrete
    /// branch probability and `weight` the ray weight divided by it.
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
        self.sample_as(wo, u, true)
    }

    /// [`DeltaLobe::sample`] for light carried from the emitters (flux, or importance
    /// transport): `wo` is the direction the light arrives from and the sample's `wi` the one
    /// it leaves in. The same branch choice and directions, but a refraction carries the power
    /// (1 - F) of the light crossing the interface, without the radiance compression
    /// 1 / eta_rel^2 (Veach 1997, section 5.2: power is conserved across a refraction, radiance
    /// is not), so the weight of a dielectric sample is 1 either way.
    pub fn sample_flux(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
        self.sample_as(wo, u, false)
    }

    fn sample_as(&self, wo: Vec3, u: Vec2, radiance: bool) -> Option<BrdfSample> {
        match *self {
            DeltaLobe::Dielectric { eta } => {
                if wo.z == 0.0 {
                    return None;
                }
                let f = fresnel::dielectric(wo.z, eta);
                if u.x < f {
                    Some(BrdfSample {
                        wi: reflect(wo),
                        weight: Rgb::ONE,
                        pdf: f,
                        kind: SampleKind::SpecularReflection,
                    })
                } else {
                    let (wt, eta_rel) = fresnel::refract(wo, eta)?;
                    Some(BrdfSample {
                        wi: wt,
                        weight: Rgb::splat(if radiance {
                            1.0 / (eta_rel * eta_rel)
                        } else {
                            1.0
                        }),
                        pdf: 1.0 - f,
                        kind: SampleKind::SpecularTransmission,
                    })
                }
            }
            _ => self.reflection(wo).map(|r| BrdfSample {
                wi: r.wi,
                weight: r.weight,
                pdf: 1.0,
                kind: SampleKind::SpecularReflection,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flux_samples_conserve_power_across_a_dielectric() {
        // Light arriving from outside and from inside a glass interface: the branch
        // probabilities are F and 1 - F and both flux weights are 1, so the expected flux
        // leaving is exactly the flux arriving; the radiance weight of the refraction is the
        // flux weight divided by eta_rel^2 = (eta_t / eta_i)^2.
        let lobe = DeltaLobe::Dielectric { eta: 1.5 };
        for wo in [
            Vec3::new(0.3, 0.1, 0.9).normalize(),
            Vec3::new(-0.2, 0.4, -0.8).normalize(),
        ] {
            let f = fresnel::dielectric(wo.z, 1.5);
            let reflect = lobe.sample_flux(wo, Vec2::new(0.0, 0.5)).unwrap();
            let refract = lobe.sample_flux(wo, Vec2::new(0.999, 0.5)).unwrap();
            assert_eq!(reflect.kind, SampleKind::SpecularReflection);
            assert_eq!(refract.kind, SampleKind::SpecularTransmission);
            assert!((reflect.pdf - f).abs() < 1e-6 && (refract.pdf - (1.0 - f)).abs() < 1e-6);
            assert_eq!(reflect.weight, Rgb::ONE);
            assert_eq!(refract.weight, Rgb::ONE);
            let (wt, eta_rel) = fresnel::refract(wo, 1.5).unwrap();
            let radiance = lobe.sample(wo, Vec2::new(0.999, 0.5)).unwrap();
            assert_eq!(radiance.wi, wt);
            assert_eq!(refract.wi, wt);
            let expected = 1.0 / (eta_rel * eta_rel);
            assert!((radiance.weight.x - expected).abs() < 1e-6);
        }
        // Mirrors and conductors weigh flux and radiance alike: their reflectance.
        let mirror = DeltaLobe::Mirror {
            reflectance: Rgb::new(0.9, 0.5, 0.2),
        };
        let wo = Vec3::new(0.1, 0.2, 0.97).normalize();
        assert_eq!(
            mirror.sample_flux(wo, Vec2::ZERO),
            mirror.sample(wo, Vec2::ZERO)
        );
    }
}
