//! The extremes of issue 3: no NaN or infinity, values >= 0, for grazing and below-horizon
//! directions and the parameter range limits; then property tests over random inputs.

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use twopass_brdf::delta::DeltaLobe;
use twopass_brdf::interface::incident_albedo;
use twopass_brdf::quadrature::Quadrature;
use twopass_brdf::{Brdf, BrdfModel, ComplexIor, FresnelModel, Rgb};

use crate::{blinn, cook, dielectric, lambert, phong};

fn directions() -> Vec<Vec3> {
    let mut v = Vec::new();
    for z in [1.0f32, 0.5, 1e-3, 1e-7, 1e-30, 0.0, -1e-7, -0.5, -1.0] {
        for phi in [0.0f32, 1.0, 3.0] {
            let s = (1.0 - z * z).max(0.0).sqrt();
            v.push(Vec3::new(s * phi.cos(), s * phi.sin(), z));
        }
    }
    v
}

fn extreme_models() -> Vec<BrdfModel> {
    let mut v = vec![lambert(0.0), lambert(0.999_999)];
    for n in [0.0f32, 1e-3, 1.0, 1e3, 1e6] {
        for rho in [0.0f32, 0.999_999] {
            v.push(phong(rho, 1.0, n, false));
            v.push(blinn(rho, 1.0, n, false));
        }
        v.push(phong(0.0, 1.0, n, true));
        v.push(phong(0.999_999, 0.0, n, true));
        v.push(blinn(0.0, 1.0, n, true));
    }
    let iors = [
        dielectric(1.0),
        dielectric(0.5),
        ComplexIor::dielectric(1e3).unwrap(),
        ComplexIor::new(Rgb::splat(1.5), Rgb::splat(1e3)).unwrap(),
        ComplexIor::new(Rgb::splat(1e3), Rgb::splat(1e3)).unwrap(),
        ComplexIor::new(Rgb::splat(0.01), Rgb::ZERO).unwrap(),
    ];
    for ior in iors {
        for m in [1e-4f32, 1e-2, 1.0, 2.0] {
            for f in [FresnelModel::Exact, FresnelModel::Schlick] {
                v.push(cook(0.0, 1.0, m, ior, f));
                v.push(cook(0.5, 0.5, m, ior, f));
            }
        }
    }
    v
}

fn assert_sane(m: &BrdfModel, wo: Vec3, wi: Vec3) {
    let f = m.eval(wo, wi);
    assert!(
        f.is_finite() && f.min_element() >= 0.0,
        "{} f({wo}, {wi}) = {f}",
        m.name()
    );
    if wo.z <= 0.0 || wi.z <= 0.0 {
        assert_eq!(f, Rgb::ZERO, "{} below the horizon", m.name());
    }
    let p = m.pdf(wo, wi);
    assert!(p.is_finite() && p >= 0.0, "{} pdf = {p}", m.name());
}

#[test]
fn extremes_stay_finite_and_non_negative() {
    let dirs = directions();
    for m in extreme_models() {
        for &wo in &dirs {
            for &wi in &dirs {
                assert_sane(&m, wo, wi);
            }
            for u in [
                Vec2::ZERO,
                Vec2::new(0.999_999_9, 0.5),
                Vec2::new(0.5, 0.999_999_9),
            ] {
                if let Some(s) = m.sample(wo, u) {
                    assert!(s.wi.is_finite() && s.wi.z > 0.0, "{}", m.name());
                    assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
                    assert!(s.pdf.is_finite() && s.pdf > 0.0);
                } else if wo.z > 0.0 && m.name() == "lambert" && u == Vec2::ZERO {
                    // Lambert with rho = 0 has nothing to sample; otherwise must succeed.
                }
            }
        }
        let q = Quadrature {
            n_theta: 64,
            n_phi: 32,
        };
        for wi in [Vec3::Z, Vec3::new(1.0, 0.0, 1e-7).normalize()] {
            let a = incident_albedo(&m, wi, q);
            assert!(a.is_finite() && a.min_element() >= 0.0, "{}: {a}", m.name());
        }
    }
}

#[test]
fn delta_lobes_at_extremes() {
    let lobes = [
        DeltaLobe::Mirror {
            reflectance: Rgb::ONE,
        },
        DeltaLobe::Mirror {
            reflectance: Rgb::ZERO,
        },
        DeltaLobe::Dielectric { eta: 1.0 },
        DeltaLobe::Dielectric { eta: 0.5 },
        DeltaLobe::Dielectric { eta: 1e3 },
        DeltaLobe::Conductor {
            ior: ComplexIor::new(Rgb::splat(1e3), Rgb::splat(1e3)).unwrap(),
        },
        DeltaLobe::Conductor {
            ior: ComplexIor::new(Rgb::splat(1.5), Rgb::ZERO).unwrap(),
        },
    ];
    for l in lobes {
        for wo in directions() {
            for r in [l.reflection(wo), l.refraction(wo)].into_iter().flatten() {
                assert!(r.wi.is_finite() && r.weight.is_finite(), "{l:?} {wo}");
                // Reflectances are at most 1; a refracted radiance weight (1 - F)/eta_rel^2
                // exceeds 1 when leaving a denser medium (radiance compression undone).
                let bound = match l {
                    DeltaLobe::Dielectric { eta } => eta.max(1.0 / eta).powi(2),
                    _ => 1.0,
                };
                assert!(
                    r.weight.min_element() >= 0.0 && r.weight.max_element() <= bound * (1.0 + 1e-6)
                );
            }
            for ux in [0.0f32, 0.5, 0.999_999_9] {
                if let Some(s) = l.sample(wo, Vec2::new(ux, 0.5)) {
                    assert!(s.wi.is_finite() && s.weight.is_finite() && s.pdf > 0.0);
                }
            }
        }
    }
}

fn arb_dir() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, -0.2f32..1.0, prop::bool::ANY).prop_map(|(x, y, z, flat)| {
        let v = Vec3::new(x, y, if flat { z * 1e-6 } else { z });
        v.try_normalize().unwrap_or(Vec3::Z)
    })
}

fn arb_model() -> impl Strategy<Value = BrdfModel> {
    let rho = 0.0f32..0.999_999;
    let exp = prop_oneof![0.0f32..10.0, 0.0f32..1e3, 0.0f32..1e6];
    let m = prop_oneof![1e-4f32..1e-2, 1e-2f32..2.0];
    let n = prop_oneof![0.01f32..1.0, 1.0f32..3.0, 3.0f32..1e3];
    let k = prop_oneof![Just(0.0f32), 0.0f32..10.0, 10.0f32..1e3];
    (rho, exp, m, n, k, 0usize..6, prop::bool::ANY).prop_map(|(rho, e, m, n, k, which, schlick)| {
        let ks = 1.0 - rho;
        match which {
            0 => lambert(rho),
            1 => phong(rho, ks, e, false),
            2 => phong(rho, ks, e, true),
            3 => blinn(rho, ks, e, false),
            4 => blinn(rho, ks, e, true),
            _ => cook(
                rho,
                ks,
                m,
                ComplexIor::new(Rgb::splat(n), Rgb::splat(k)).unwrap(),
                if schlick {
                    FresnelModel::Schlick
                } else {
                    FresnelModel::Exact
                },
            ),
        }
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    #[test]
    fn any_model_any_directions_is_finite_and_non_negative(
        m in arb_model(), wo in arb_dir(), wi in arb_dir(), u in (0.0f32..1.0, 0.0f32..1.0)
    ) {
        assert_sane(&m, wo, wi);
        if let Some(s) = m.sample(wo, Vec2::new(u.0, u.1)) {
            prop_assert!(s.wi.is_finite() && s.wi.z > 0.0);
            prop_assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
            prop_assert!(s.pdf.is_finite() && s.pdf > 0.0);
        }
    }

    #[test]
    fn fresnel_is_a_reflectance(c in -1.0f32..=1.0, n in 1e-3f32..1e3, k in 0.0f32..1e3) {
        let r = twopass_brdf::fresnel::complex(c, n, k);
        prop_assert!((0.0..=1.0).contains(&r));
        let s = twopass_brdf::fresnel::schlick_ior(c, n, k);
        prop_assert!((0.0..=1.0).contains(&s));
        let d = twopass_brdf::fresnel::dielectric(c, n);
        prop_assert!((0.0..=1.0).contains(&d));
    }
}
