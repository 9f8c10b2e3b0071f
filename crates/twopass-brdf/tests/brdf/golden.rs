//! Golden values from issue 3 and closed forms, each derived independently of the code.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use twopass_brdf::beckmann::Beckmann;
use twopass_brdf::delta::DeltaLobe;
use twopass_brdf::phong::PhongShading;
use twopass_brdf::{Brdf, ComplexIor, FresnelModel, Material, PhongParams, Rgb, fresnel};

use crate::{conductor, cook, dielectric, dir_deg, phong};

#[test]
fn fresnel_normal_incidence_of_glass_is_four_percent() {
    assert!((fresnel::complex(1.0, 1.5, 0.0) - 0.04).abs() < 1e-6);
    assert!((fresnel::dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    assert!((fresnel::normal_incidence(1.5, 0.0) - 0.04).abs() < 1e-6);
}

#[test]
fn brewster_angle_of_glass_is_56_31_degrees() {
    // Scan R_p on a 0.001-degree grid for its minimum.
    let (mut best, mut best_deg) = (f32::INFINITY, 0.0);
    for i in 0..=20_000 {
        let deg = 50.0 + i as f32 * 0.001;
        let (_, rp) = fresnel::polarized(deg.to_radians().cos(), 1.5, 0.0);
        if rp < best {
            best = rp;
            best_deg = deg;
        }
    }
    assert!((best_deg - 56.31).abs() < 0.005, "Brewster at {best_deg}");
    assert!(best < 1e-7, "R_p at Brewster = {best}");
}

#[test]
fn critical_angle_of_glass_is_41_81_degrees() {
    // Light inside the glass (cos_i < 0): bisect the smallest angle of total reflection.
    let tir = |deg: f32| fresnel::dielectric(-deg.to_radians().cos(), 1.5) >= 1.0;
    let (mut lo, mut hi) = (30.0f32, 60.0f32);
    assert!(!tir(lo) && tir(hi));
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if tir(mid) { hi = mid } else { lo = mid }
    }
    assert!((hi - 41.81).abs() < 0.005, "critical angle {hi}");
    // Snell agrees: no refracted ray beyond it, one before it.
    assert!(fresnel::refract(-dir_deg(41.7, 0.0), 1.5).is_some());
    assert!(fresnel::refract(-dir_deg(41.9, 0.0), 1.5).is_none());
    // The complex-index formula with eta = 1/1.5 gives total reflection too.
    assert_eq!(
        fresnel::complex(42.0f32.to_radians().cos(), 1.0 / 1.5, 0.0),
        1.0
    );
}

#[test]
fn silver_at_635_8_nm_reflects_0_9687() {
    let r = fresnel::complex(1.0, 0.136, 4.011);
    assert!((r - 0.9687).abs() < 5e-5, "R = {r}");
    assert!((fresnel::normal_incidence(0.136, 4.011) - 0.9687).abs() < 5e-5);
}

#[test]
fn beckmann_at_the_normal_is_one_over_pi_m2() {
    for m in [1e-4f32, 1e-2, 0.1, 0.5, 1.0, 2.0] {
        let d = Beckmann::new(m).unwrap().d(Vec3::Z);
        let expect = 1.0 / (std::f64::consts::PI * f64::from(m).powi(2));
        assert!(((f64::from(d) - expect) / expect).abs() < 1e-6, "m = {m}");
    }
}

#[test]
fn conductor_with_zero_extinction_equals_dielectric() {
    for eta in [0.5f32, 1.0, 1.33, 1.5, 2.4, 1e3] {
        for i in 0..=100 {
            let c = i as f32 / 100.0;
            let a = fresnel::complex(c, eta, 0.0);
            let b = fresnel::dielectric(c, eta);
            assert!((a - b).abs() < 2e-6, "eta {eta} cos {c}: {a} vs {b}");
        }
    }
}

#[test]
fn index_one_reflects_nothing() {
    for i in 0..=100 {
        let c = i as f32 / 100.0;
        assert_eq!(fresnel::complex(c, 1.0, 0.0), 0.0);
        assert_eq!(fresnel::dielectric(c, 1.0), 0.0);
    }
    let glass = DeltaLobe::Dielectric { eta: 1.0 };
    let wo = dir_deg(40.0, 10.0);
    assert!(glass.reflection(wo).is_none());
    let t = glass.refraction(wo).unwrap();
    assert!((t.wi + wo).length() < 1e-6 && (t.weight - Rgb::ONE).length() < 1e-6);
}

#[test]
fn conductor_table_reflects_in_the_metals_colours() {
    let r = |name: &str| {
        let ior = ComplexIor::conductor(name).unwrap();
        fresnel::complex_rgb(1.0, &ior)
    };
    let (gold, silver, copper, al) = (r("gold"), r("silver"), r("copper"), r("aluminium"));
    assert!(gold.x > gold.y && gold.y > gold.z, "gold {gold}");
    assert!(
        copper.x > copper.y && copper.y > copper.z,
        "copper {copper}"
    );
    assert!(silver.min_element() > 0.97, "silver {silver}");
    assert!(
        al.min_element() > 0.9 && al.max_element() < 0.93,
        "aluminium {al}"
    );
    // Tabulated reflectances of the doc table, recomputed from ((n-1)^2+k^2)/((n+1)^2+k^2).
    for (name, expect) in [
        ("gold", [0.957, 0.792, 0.408]),
        ("silver", [0.990, 0.983, 0.980]),
        ("copper", [0.935, 0.624, 0.538]),
        ("aluminium", [0.906, 0.915, 0.922]),
    ] {
        let got = r(name).to_array();
        for c in 0..3 {
            assert!((got[c] - expect[c]).abs() < 6e-4, "{name}: {got:?}");
        }
    }
    assert!(ComplexIor::conductor("SILVER").is_some());
    assert!(ComplexIor::conductor("unobtainium").is_none());
}

#[test]
fn schlick_error_is_measured() {
    let mut worst = Vec::new();
    for (name, n, k) in [
        ("glass 1.5", 1.5f32, 0.0f32),
        ("gold R", 0.1556, 3.6024),
        ("aluminium G", 1.0152, 6.6273),
    ] {
        let f0 = fresnel::normal_incidence(n, k);
        let mut max_err = 0.0f32;
        for i in 0..=1000 {
            let c = i as f32 / 1000.0;
            max_err = max_err.max((fresnel::schlick(c, f0) - fresnel::complex(c, n, k)).abs());
        }
        // Exact at both ends.
        assert!((fresnel::schlick(1.0, f0) - fresnel::complex(1.0, n, k)).abs() < 1e-6);
        assert!((fresnel::schlick(0.0, f0) - fresnel::complex(0.0, n, k)).abs() < 1e-6);
        worst.push((name, max_err));
    }
    println!("max |Schlick - exact| over cos in [0, 1]: {worst:?}");
    // Schlick misses the dip of aluminium near grazing incidence by several percent.
    assert!(worst[2].1 > worst[0].1);
}

#[test]
fn cook_torrance_closed_form_at_normal_incidence() {
    for m in [0.05f32, 0.3, 1.0] {
        let ct = cook(0.0, 0.8, m, dielectric(1.5), FresnelModel::Exact);
        let f = ct.eval(Vec3::Z, Vec3::Z).x;
        // h = N: D = 1/(pi m^2), G = 1, F = 0.04, 4 cos cos = 4.
        let expect = 0.8 * 0.04 / (PI * m * m) / 4.0;
        assert!(
            ((f - expect) / expect).abs() < 1e-5,
            "m {m}: {f} vs {expect}"
        );
    }
}

#[test]
fn modified_phong_peak_and_lambert_value() {
    let mp = phong(0.2, 0.5, 30.0, true);
    let wo = dir_deg(35.0, 20.0);
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    let expect = 0.2 / PI + 0.5 * 32.0 / (2.0 * PI);
    assert!((mp.eval(wo, mirror).x - expect).abs() < 1e-5 * expect);
    let l = crate::lambert(0.6);
    assert!((l.eval(wo, mirror).x - 0.6 / PI).abs() < 1e-7);
}

#[test]
fn phong_shading_form_equals_brdf_times_cosine() {
    let m = Material::phong(PhongParams {
        diffuse: Rgb::new(0.5, 0.4, 0.3),
        specular: Rgb::splat(0.4),
        exponent: 12.0,
        ambient: Rgb::splat(0.1),
        normalized: false,
    })
    .unwrap();
    let shading = PhongShading::from_material(&m);
    let model = m.model().unwrap();
    let (wo, wi) = (dir_deg(30.0, 0.0), dir_deg(25.0, 170.0));
    let i_in = Rgb::new(2.0, 3.0, 4.0);
    let got = shading.light_term(i_in, wo, wi);
    let expect = i_in * model.eval(wo, wi) * wi.z;
    assert!((got - expect).abs().max_element() < 1e-5 * expect.max_element());
    let total = shading.shade(Rgb::splat(0.5), &[(i_in, wi)], wo);
    assert!((total - got - Rgb::splat(0.05)).abs().max_element() < 1e-6);
}

#[test]
fn smooth_dielectric_conserves_energy_and_obeys_snell() {
    let glass = DeltaLobe::Dielectric { eta: 1.5 };
    for deg in [0.0f32, 20.0, 45.0, 70.0, 89.0] {
        for side in [1.0f32, -1.0] {
            let wo = dir_deg(deg, 30.0) * Vec3::new(1.0, 1.0, side);
            let r = glass.reflection(wo).map_or(0.0, |r| r.weight.x);
            match glass.refraction(wo) {
                Some(t) => {
                    let eta_rel: f32 = if side > 0.0 { 1.5 } else { 1.0 / 1.5 };
                    // Radiance weight (1 - F)/eta^2: F + T eta^2 = 1.
                    assert!((r + t.weight.x * eta_rel * eta_rel - 1.0).abs() < 1e-5);
                    let sin_i = (1.0 - wo.z * wo.z).sqrt();
                    let sin_t = (1.0 - t.wi.z * t.wi.z).sqrt();
                    assert!((sin_i - eta_rel * sin_t).abs() < 1e-5, "Snell at {deg}");
                    assert!(t.wi.z * wo.z < 0.0);
                }
                None => assert_eq!(r, 1.0),
            }
            // One-sample choice: expected weight equals the sum of both branches.
            let mut mean = 0.0;
            let n = 1000;
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, 0.5);
                if let Some(s) = glass.sample(wo, u) {
                    assert!(s.kind.is_delta());
                    mean += s.weight.x
                        * if s.kind == twopass_brdf::SampleKind::SpecularReflection {
                            1.0
                        } else {
                            let e: f32 = if side > 0.0 { 1.5 } else { 1.0 / 1.5 };
                            e * e
                        };
                }
            }
            assert!((mean / n as f32 - 1.0).abs() < 2e-3);
        }
    }
}

#[test]
fn mirror_and_conductor_reflect_about_the_normal() {
    let wo = dir_deg(60.0, 45.0);
    let m = Material::mirror(Rgb::new(0.9, 0.8, 0.7)).unwrap();
    let r = m.delta().unwrap().reflection(wo).unwrap();
    assert!((r.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-7);
    assert_eq!(r.weight, Rgb::new(0.9, 0.8, 0.7));
    let ag = conductor("silver");
    let c = Material::conductor(ag).unwrap();
    let r = c.delta().unwrap().reflection(wo).unwrap();
    assert_eq!(r.weight, fresnel::complex_rgb(wo.z, &ag));
    assert!(c.delta().unwrap().reflection(-wo).is_none());
    assert_eq!(c.eval(wo, r.wi), Rgb::ZERO);
}

#[test]
fn material_split_adds_up() {
    let m = Material::phong(PhongParams {
        diffuse: Rgb::splat(0.4),
        specular: Rgb::splat(0.3),
        exponent: 20.0,
        ambient: Rgb::ZERO,
        normalized: true,
    })
    .unwrap();
    let (wo, wi) = (dir_deg(20.0, 0.0), dir_deg(30.0, 180.0));
    let sum = m.eval_diffuse(wo, wi) + m.eval_non_diffuse(wo, wi);
    assert!((m.eval(wo, wi) - sum).abs().max_element() < 1e-6);
    assert!(m.has_non_diffuse() && m.reflects_diffusely());
    let white = Material::lambert(Rgb::splat(0.7)).unwrap();
    assert_eq!(white.eval_non_diffuse(wo, wi), Rgb::ZERO);
    assert!(white.delta().is_none() && !white.has_non_diffuse());
    let glass = Material::dielectric(1.5).unwrap();
    assert!(glass.model().is_none() && glass.delta().is_some());
    assert_eq!(glass.diffuse_albedo(), Rgb::ZERO);
    assert_eq!(glass.pdf(wo, wi), 0.0);
    assert!(glass.sample(-wo, Vec2::new(0.9, 0.1)).is_some());
}
