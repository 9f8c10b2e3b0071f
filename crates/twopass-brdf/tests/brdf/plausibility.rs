//! Quadrature accuracy against closed forms, then the plausibility claims of issue 3.

use std::f64::consts::PI;

use glam::Vec3;
use twopass_brdf::beckmann::Beckmann;
use twopass_brdf::check::{self, CheckOptions, INCIDENCE_DEG, direction_at_deg};
use twopass_brdf::interface::incident_albedo;
use twopass_brdf::quadrature::{Quadrature, integrate_hemisphere};
use twopass_brdf::{BrdfModel, FresnelModel, blinn_phong};

use crate::{blinn, conductor, cook, dielectric, lambert, phong, white_ior};

const ACCURACY: f32 = 1e-3;

#[test]
fn quadrature_gives_lambert_albedo_rho_at_every_incidence() {
    let l = lambert(0.8);
    for deg in INCIDENCE_DEG {
        let a = incident_albedo(&l, direction_at_deg(deg), Quadrature::default()).x;
        assert!((a - 0.8).abs() < ACCURACY, "{deg} deg: {a}");
    }
}

#[test]
fn quadrature_gives_beckmann_projected_area_one() {
    for m in [1e-4f32, 1e-3, 1e-2, 0.1, 0.3, 0.5, 1.0, 2.0] {
        let d = Beckmann::new(m).unwrap();
        let area = integrate_hemisphere(Vec3::Z, Quadrature::default(), |h| {
            f64::from(d.d(h)) * f64::from(h.z)
        });
        assert!((area - 1.0).abs() < 1e-3, "m = {m}: {area}");
    }
}

#[test]
fn quadrature_matches_phong_closed_forms_up_to_exponent_1e6() {
    for n in [0.0f32, 1.0, 10.0, 100.0, 1e4, 1e6] {
        // Modified Phong, normal incidence: specular albedo = k_s exactly.
        let mp = phong(0.0, 1.0, n, true);
        let a = incident_albedo(&mp, Vec3::Z, Quadrature::default()).x;
        assert!((a - 1.0).abs() < ACCURACY, "modified Phong n = {n}: {a}");
        // Published Phong, normal incidence: rho + k_s 2 pi / (n + 2).
        let p = phong(0.3, 0.5, n, false);
        let a = f64::from(incident_albedo(&p, Vec3::Z, Quadrature::default()).x);
        let expect = 0.3 + 0.5 * 2.0 * PI / (f64::from(n) + 2.0);
        assert!((a - expect).abs() < 1e-3, "Phong n = {n}: {a} vs {expect}");
        // Normalized Blinn-Phong, normal incidence: k_s exactly, with c(n) derived by hand:
        // 1 / c = 8 pi (n + 2^(-n/2)) / ((n + 2)(n + 4)).
        let b = blinn(0.0, 1.0, n, true);
        let a = incident_albedo(&b, Vec3::Z, Quadrature::default()).x;
        assert!((a - 1.0).abs() < ACCURACY, "Blinn-Phong n = {n}: {a}");
    }
}

#[test]
fn blinn_phong_with_four_times_the_exponent_matches_the_phong_highlight() {
    // At normal incidence the lobe integrals have closed forms:
    // Phong: 2 pi / (n + 1); Blinn-Phong with 4n: 8 pi (1 - 2^-(2n+1)) / (4n + 2).
    for n in [1.0f64, 10.0, 100.0, 1000.0] {
        let nb = blinn_phong::exponent_matching_phong(n as f32);
        assert_eq!(nb, 4.0 * n as f32);
        let p = integrate_hemisphere(Vec3::Z, Quadrature::default(), |w| {
            f64::from(w.z).max(0.0).powf(n)
        });
        let b = integrate_hemisphere(Vec3::Z, Quadrature::default(), |w| {
            let h = (w + Vec3::Z).normalize();
            f64::from(h.z).powf(f64::from(nb))
        });
        let ep = 2.0 * PI / (n + 1.0);
        let eb = 8.0 * PI * (1.0 - 2f64.powf(-(2.0 * n + 1.0))) / (4.0 * n + 2.0);
        assert!(
            (p - ep).abs() < 1e-3 * ep && (b - eb).abs() < 1e-3 * eb,
            "n = {n}"
        );
        println!(
            "n = {n}: Blinn/Phong lobe solid angle at normal incidence = {:.4}",
            b / p
        );
    }
}

#[test]
fn popular_blinn_phong_factor_would_create_energy() {
    // (n + 8) / (8 pi) exceeds the exact factor for n > 0, so it is not used.
    for n in [1.0f32, 2.0, 10.0, 100.0] {
        assert!(blinn_phong::normalization(n) < (n + 8.0) / (8.0 * std::f32::consts::PI));
    }
    assert!((blinn_phong::normalization(0.0) - std::f32::consts::FRAC_1_PI).abs() < 1e-7);
}

fn plausible_models() -> Vec<(String, BrdfModel)> {
    let mut v = Vec::new();
    for rho in [0.0f32, 0.5, 0.999] {
        v.push((format!("lambert rho={rho}"), lambert(rho)));
    }
    for (rho, ks) in [(0.0f32, 1.0f32), (0.5, 0.5), (0.3, 0.2)] {
        for n in [0.0f32, 1.0, 10.0, 100.0, 1e4] {
            v.push((
                format!("modified phong {rho}/{ks}/{n}"),
                phong(rho, ks, n, true),
            ));
            v.push((
                format!("blinn-phong normalized {rho}/{ks}/{n}"),
                blinn(rho, ks, n, true),
            ));
        }
    }
    let iors = [dielectric(1.5), conductor("gold"), white_ior()];
    for ior in iors {
        for m in [1e-3f32, 0.05, 0.2, 0.5, 1.0, 2.0] {
            for f in [FresnelModel::Exact, FresnelModel::Schlick] {
                v.push((
                    format!("cook-torrance m={m} {ior:?} {f:?}"),
                    cook(0.0, 1.0, m, ior, f),
                ));
            }
            v.push((
                format!("cook-torrance+diffuse m={m}"),
                cook(0.4, 0.6, m, ior, FresnelModel::Exact),
            ));
        }
    }
    v
}

#[test]
fn plausible_models_are_reciprocal_positive_and_conserve_energy() {
    let opts = CheckOptions::default();
    for (name, m) in plausible_models() {
        let p = check::plausibility(&m, &opts);
        assert_eq!(p.non_finite, 0, "{name}");
        assert!(p.min_value >= 0.0, "{name}: min {}", p.min_value);
        assert!(
            p.reciprocity_error <= 1e-6,
            "{name}: reciprocity {}",
            p.reciprocity_error
        );
        assert!(
            p.max_albedo() <= 1.0 + ACCURACY,
            "{name}: albedo {}",
            p.max_albedo()
        );
    }
}

#[test]
fn cook_torrance_loses_energy_at_high_roughness() {
    println!("Cook-Torrance energy albedo with F = 1 (furnace), by incidence angle:");
    println!("     m |   0 deg |  30 deg |  60 deg |  80 deg |  89 deg");
    let mut at_normal = Vec::new();
    for m in [0.05f32, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0] {
        let ct = cook(0.0, 1.0, m, white_ior(), FresnelModel::Exact);
        let row: Vec<f32> = [0.0f32, 30.0, 60.0, 80.0, 89.0]
            .iter()
            .map(|&d| incident_albedo(&ct, direction_at_deg(d), Quadrature::default()).x)
            .collect();
        println!(
            "{m:>6} | {}",
            row.iter()
                .map(|a| format!("{a:.4}"))
                .collect::<Vec<_>>()
                .join(" |  ")
        );
        at_normal.push(row[0]);
        assert!(row.iter().all(|&a| a <= 1.0 + ACCURACY));
    }
    // The loss grows with roughness (single scattering drops inter-reflections).
    assert!(
        at_normal.windows(2).all(|w| w[1] <= w[0] + 1e-4),
        "{at_normal:?}"
    );
    assert!(
        at_normal[0] > 0.99 && *at_normal.last().unwrap() < 0.8,
        "{at_normal:?}"
    );
}

#[test]
fn published_phong_is_not_reciprocal_and_creates_energy() {
    let p = phong(0.5, 1.0, 1.0, false);
    let r = check::plausibility(&p, &CheckOptions::default());
    assert!(
        r.reciprocity_error > 0.5,
        "reciprocity error {}",
        r.reciprocity_error
    );
    // Normal incidence: 0.5 + 2 pi / 3 = 2.594 (closed form), far above 1.
    let a0 = r.albedo[0].albedo.x;
    assert!((a0 - (0.5 + 2.0 * std::f32::consts::PI / 3.0)).abs() < ACCURACY);
    // Even a sharp, dim lobe exceeds 1 towards grazing incidence (the 1/cos theta_i).
    for n in [1.0f32, 10.0, 100.0] {
        let dim = phong(0.5, 0.2, n, false);
        let row: Vec<f32> = [0.0f32, 60.0, 85.0, 89.0, 89.9]
            .iter()
            .map(|&d| incident_albedo(&dim, direction_at_deg(d), Quadrature::default()).x)
            .collect();
        println!("published Phong rho 0.5, ks 0.2, n {n}: albedo at 0/60/85/89/89.9 deg = {row:?}");
        if n == 10.0 {
            assert!(row[4] > 1.0 && row[4] > row[0]);
        }
    }
    // The classic Blinn-Phong shares both flaws.
    let b = check::plausibility(&blinn(0.5, 1.0, 4.0, false), &CheckOptions::default());
    assert!(b.reciprocity_error > 0.5 && b.max_albedo() > 1.0);
}

#[test]
fn albedo_seen_from_wo_matches_incident_albedo_for_reciprocal_models() {
    use twopass_brdf::Brdf;
    let ct = cook(0.2, 0.7, 0.3, conductor("copper"), FresnelModel::Exact);
    for deg in [0.0f32, 45.0, 80.0] {
        let w = direction_at_deg(deg);
        let a = ct.albedo(w);
        let b = incident_albedo(&ct, w, Quadrature::default());
        assert!((a - b).abs().max_element() < ACCURACY);
    }
}
