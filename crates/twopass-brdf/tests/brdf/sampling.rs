//! Sampling: warps invert, the chi-square harness is right and has power, every sampled lobe
//! passes it with 1e6 samples, pdf integrates to the acceptance probability.

use glam::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF};
use twopass_brdf::check::{self, Chi2Options, Pcg32, chi2_test, chi2_test_brdf, direction_at_deg};
use twopass_brdf::quadrature::Quadrature;
use twopass_brdf::sample::*;
use twopass_brdf::{Brdf, BrdfModel, FresnelModel};

use crate::{blinn, chi2_dir, conductor, cook, dielectric, dir_deg, lambert, phong};

#[test]
fn chi2_survival_agrees_with_statrs() {
    for dof in [1.0f64, 2.0, 5.0, 50.0, 1000.0, 5000.0] {
        let dist = ChiSquared::new(dof).unwrap();
        for x in [0.1 * dof, 0.5 * dof, dof, 1.2 * dof, 2.0 * dof, 3.0 * dof] {
            let ours = check::chi2_survival(x, dof);
            let theirs = 1.0 - dist.cdf(x);
            assert!(
                (ours - theirs).abs() < 1e-9 + 1e-6 * theirs,
                "dof {dof} x {x}: {ours} vs {theirs}"
            );
        }
    }
}

#[test]
fn warps_invert() {
    let mut rng = Pcg32::new(7, 1);
    for _ in 0..10_000 {
        let u = rng.next_vec2() * 0.998 + Vec2::splat(0.001);
        let w = square_to_cosine_hemisphere(u);
        assert!((cosine_hemisphere_to_square(w) - u).abs().max_element() < 1e-4);
        for n in [0.0f32, 3.0, 50.0] {
            let w = square_to_phong_lobe(u, n);
            assert!((w.length() - 1.0).abs() < 1e-5);
            assert!(
                (phong_lobe_to_square(w, n) - u).abs().max_element() < 2e-3,
                "n {n} u {u}"
            );
        }
        for m in [0.1f32, 0.5, 2.0] {
            let d = twopass_brdf::beckmann::Beckmann::new(m).unwrap();
            let h = d.sample(u);
            assert!(
                (d.sample_inverse(h) - u).abs().max_element() < 2e-3,
                "m {m} u {u}"
            );
        }
    }
}

fn run(name: &str, model: &BrdfModel, wo: Vec3, tests: usize) {
    let opts = Chi2Options {
        tests,
        ..Chi2Options::default()
    };
    let report = chi2_test_brdf(model, wo, opts);
    println!("{name}: {}", report.message);
    if !report.passed {
        let dir = chi2_dir();
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{}.txt", name.replace([' ', '/', '='], "_")));
        std::fs::write(&path, report.tables_text()).unwrap();
        panic!("{name}: {} (tables in {})", report.message, path.display());
    }
}

/// Every sampled lobe, each with 1e6 samples; the family shares one Sidak correction.
#[test]
fn chi_square_every_sampled_lobe() {
    use FresnelModel::{Exact, Schlick};
    // One row per lobe: name, model, incidence (polar, azimuth; degrees).
    #[rustfmt::skip]
    let cases: [(&str, BrdfModel, (f32, f32)); 8] = [
        ("cosine hemisphere", lambert(0.7), (50.0, 0.0)),
        ("phong lobe", phong(0.0, 1.0, 20.0, false), (30.0, 40.0)),
        ("modified phong mixture", phong(0.4, 0.5, 60.0, true), (60.0, 0.0)),
        ("blinn-phong half-vector lobe", blinn(0.0, 1.0, 80.0, true), (45.0, 0.0)),
        ("blinn-phong classic grazing", blinn(0.2, 0.6, 10.0, false), (80.0, 0.0)),
        ("beckmann m 0.3", cook(0.0, 1.0, 0.3, conductor("gold"), Exact), (30.0, 0.0)),
        ("beckmann m 0.1 mixture grazing", cook(0.3, 0.7, 0.1, dielectric(1.5), Schlick), (75.0, 120.0)),
        ("beckmann m 1.5", cook(0.0, 1.0, 1.5, dielectric(1.5), Exact), (10.0, 0.0)),
    ];
    let n = cases.len();
    for (name, model, (theta, phi)) in &cases {
        run(name, model, dir_deg(*theta, *phi), n);
    }
}

#[test]
fn chi_square_rejects_a_wrong_density() {
    // Uniform samples claimed to be cosine distributed: must be rejected.
    let report = chi2_test(
        |u| {
            let z = u.x;
            let s = (1.0 - z * z).sqrt();
            let phi = std::f32::consts::TAU * u.y;
            Some(Vec3::new(s * phi.cos(), s * phi.sin(), z))
        },
        |w| f64::from(cosine_hemisphere_pdf(w)),
        Chi2Options::default(),
    );
    assert!(!report.passed, "{}", report.message);
    // A slightly wrong exponent is caught too: Phong lobe n = 20 claimed as n = 21.
    let report = chi2_test(
        |u| Some(square_to_phong_lobe(u, 20.0)),
        |w| f64::from(phong_lobe_pdf(w.z, 21.0)),
        Chi2Options::default(),
    );
    assert!(!report.passed, "{}", report.message);
}

#[test]
fn pdf_integrates_to_one_where_no_mass_leaves_the_hemisphere() {
    let q = Quadrature::default();
    for deg in [0.0f32, 45.0, 89.0] {
        let p = check::pdf_integral(&lambert(0.5), direction_at_deg(deg), q);
        assert!((p - 1.0).abs() < 1e-3, "lambert {deg}: {p}");
    }
    for n in [0.0f32, 10.0, 1e4] {
        let p = check::pdf_integral(&phong(0.0, 1.0, n, true), Vec3::Z, q);
        assert!((p - 1.0).abs() < 1e-3, "phong n {n}: {p}");
    }
    // Normal incidence, half-vector lobes: the mass with theta_h > 45 deg reflects below the
    // horizon. Blinn-Phong: 2^(-(n+1)/2) is lost; Beckmann: exp(-1/m^2).
    for n in [1.0f64, 4.0, 50.0] {
        let p = check::pdf_integral(&blinn(0.0, 1.0, n as f32, true), Vec3::Z, q);
        let expect = 1.0 - 2f64.powf(-(n + 1.0) / 2.0);
        assert!((p - expect).abs() < 1e-3, "blinn n {n}: {p} vs {expect}");
    }
    for m in [0.1f64, 0.5, 1.0, 2.0] {
        let ct = cook(0.0, 1.0, m as f32, crate::white_ior(), FresnelModel::Exact);
        let p = check::pdf_integral(&ct, Vec3::Z, q);
        let expect = 1.0 - (-1.0 / (m * m)).exp();
        assert!((p - expect).abs() < 1e-3, "beckmann m {m}: {p} vs {expect}");
    }
}

#[test]
fn pdf_integral_equals_the_acceptance_rate_at_oblique_incidence() {
    let models = [
        phong(0.2, 0.6, 5.0, true),
        blinn(0.0, 1.0, 8.0, true),
        cook(0.1, 0.9, 0.8, conductor("copper"), FresnelModel::Exact),
    ];
    for m in &models {
        let wo = direction_at_deg(70.0);
        let p = check::pdf_integral(m, wo, Quadrature::default());
        let mut rng = Pcg32::new(3, 9);
        let n = 1_000_000;
        let ok = (0..n)
            .filter(|_| m.sample(wo, rng.next_vec2()).is_some())
            .count();
        let rate = ok as f64 / n as f64;
        let sigma = (rate * (1.0 - rate) / n as f64).sqrt().max(1e-6);
        assert!(
            (p - rate).abs() < 5.0 * sigma + 1e-3,
            "{}: {p} vs {rate}",
            m.name()
        );
    }
}

#[test]
fn sample_weight_is_f_cos_over_pdf() {
    let models = [
        lambert(0.6),
        phong(0.3, 0.6, 30.0, true),
        phong(0.3, 0.6, 30.0, false),
        blinn(0.3, 0.6, 100.0, true),
        cook(0.3, 0.6, 0.2, conductor("aluminium"), FresnelModel::Exact),
    ];
    let mut rng = Pcg32::new(11, 2);
    for m in &models {
        for _ in 0..20_000 {
            let wo = square_to_cosine_hemisphere(rng.next_vec2());
            if let Some(s) = m.sample(wo, rng.next_vec2()) {
                let pdf = m.pdf(wo, s.wi);
                assert!((pdf - s.pdf).abs() <= 1e-4 * pdf, "{}", m.name());
                let expect = m.eval(wo, s.wi) * s.wi.z / pdf;
                assert!(
                    (s.weight - expect).abs().max_element() <= 1e-4 * expect.max_element() + 1e-7
                );
            }
        }
    }
}

#[test]
fn mean_sample_weight_is_the_albedo_seen_from_wo() {
    let m = cook(0.2, 0.7, 0.4, conductor("gold"), FresnelModel::Exact);
    let wo = direction_at_deg(40.0);
    let mut rng = Pcg32::new(5, 5);
    let n = 200_000;
    let mut sum = glam::DVec3::ZERO;
    for _ in 0..n {
        if let Some(s) = m.sample(wo, rng.next_vec2()) {
            sum += s.weight.as_dvec3();
        }
    }
    let mean = (sum / n as f64).as_vec3();
    let a = m.albedo(wo);
    assert!((mean - a).abs().max_element() < 5e-3, "{mean} vs {a}");
}
