//! The sky model against the published formulas and its samplers against their densities.

use glam::{Vec2, Vec3};
use twopass_brdf::random::Pcg32;

use super::*;

/// Preetham et al. 1999, appendix A.2, typed from the paper: the zenith luminance in kcd/m^2
/// for turbidity `t` and sun zenith angle `theta_s` (radians).
fn paper_zenith_luminance(t: f64, theta_s: f64) -> f64 {
    let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * theta_s);
    (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192
}

fn daylight(turbidity: f32, elevation_deg: f32) -> Sky {
    let e = elevation_deg.to_radians();
    let sun = Vec3::new(e.cos() * 0.6, e.sin(), e.cos() * 0.8);
    Sky::daylight(
        turbidity,
        sun,
        SUN_DIAMETER_DEGREES.to_radians(),
        Vec3::Y,
        1.0,
        Vec::new(),
    )
}

#[test]
fn zenith_luminance_is_the_papers() {
    #[rustfmt::skip]
    let cases = [(2.0, 60.0), (3.0, 30.0), (5.0, 45.0), (10.0, 10.0), (2.5, 80.0)];
    for (t, elevation) in cases {
        let sky = daylight(t, elevation);
        // CIE Y of linear sRGB by the sRGB specification's RGB-to-XYZ row (unrounded, unlike
        // the 4-digit Rec. 709 weights), and cd/m^2 back from W/(m^2 sr): times 683 lm/W.
        let rgb = sky.dome_radiance(Vec3::Y).as_dvec3();
        let y = rgb.dot(glam::DVec3::new(0.212_672_9, 0.715_152_2, 0.072_175_0));
        let got = y * 683.0 / 1000.0;
        let theta_s = (90.0 - f64::from(elevation)).to_radians();
        let expected = paper_zenith_luminance(f64::from(t), theta_s);
        // f32 radiance: 1e-5 relative.
        assert!(
            (got - expected).abs() < 1e-5 * expected,
            "T {t}, elevation {elevation}: {got} vs {expected} kcd/m^2"
        );
    }
}

#[test]
fn a_sun_at_or_below_the_horizon_gives_no_light_and_no_nan() {
    for elevation in [0.0, -0.1, -10.0, -90.0, 0.05] {
        let sky = daylight(3.0, elevation);
        if elevation <= 0.0 {
            assert!(sky.sun.is_none(), "{elevation}");
            assert_eq!(sky.sample_sun(Vec2::splat(0.5)), None);
        }
        assert_eq!(sky.sun_share() == 0.0, elevation <= 0.0);
        let mut rng = Pcg32::new(7, 1);
        for _ in 0..2000 {
            let u = rng.next_vec2();
            let d = twopass_brdf::sample::square_to_cosine_hemisphere(u);
            let dir = Vec3::new(
                d.x,
                d.z * if rng.next_f32() < 0.5 { 1.0 } else { -1.0 },
                d.y,
            );
            let l = sky.radiance(dir);
            assert!(
                l.is_finite() && l.min_element() >= 0.0,
                "{elevation}: {l} toward {dir}"
            );
        }
        let p = sky.power(10.0);
        assert!(p.is_finite() && p.min_element() >= 0.0, "{p}");
    }
}

#[test]
fn sun_samples_fill_its_disc_at_its_density() {
    let sky = daylight(3.0, 40.0);
    let sun = sky.sun.expect("above the horizon");
    // The disc of 0.53 degrees: solid angle 2 pi (1 - cos 0.265 deg).
    let half = (0.53f64 / 2.0).to_radians();
    let omega = 2.0 * std::f64::consts::PI * (1.0 - half.cos());
    assert!((f64::from(sun.solid_angle()) - omega).abs() < 1e-6 * omega);
    let mut rng = Pcg32::new(3, 4);
    for _ in 0..1000 {
        let (dir, pdf) = sky.sample_sun(rng.next_vec2()).expect("a sun");
        assert!((dir.length() - 1.0).abs() < 1e-6);
        assert_eq!(sky.sun_radiance(dir), sun.radiance, "{dir}");
        assert_eq!(pdf, sky.sun_pdf(dir));
    }
    // Just outside the disc: nothing.
    let frame = Frame::from_normal(sun.direction);
    let out = frame.to_world(Vec3::new(
        (half * 1.01).sin() as f32,
        0.0,
        (half * 1.01).cos() as f32,
    ));
    assert_eq!(sky.sun_radiance(out), Rgb::ZERO);
    assert_eq!(sky.sun_pdf(out), 0.0);
}

#[test]
fn dome_sampling_through_a_portal_is_unbiased() {
    // A point under a 1 x 1 window 2 above it: E[cos / pdf] over the sampled directions is the
    // integral of the cosine over the hemisphere, pi, with the portal mixed in or not.
    let portal = Portal {
        origin: Vec3::new(-0.5, 2.0, -0.5),
        edge_u: Vec3::new(1.0, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 1.0),
    };
    for portals in [vec![], vec![portal]] {
        let sky = Sky::uniform(Rgb::ONE, portals);
        let mut rng = Pcg32::new(11, 2);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let Some((dir, pdf)) =
                sky.sample_dome(Vec3::ZERO, Vec3::Y, rng.next_vec2(), rng.next_f32())
            else {
                continue;
            };
            let v = f64::from(dir.y.max(0.0) / pdf);
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / f64::from(n);
        let sigma = ((sum2 / f64::from(n) - mean * mean).max(0.0) / f64::from(n)).sqrt();
        // Five standard errors of the mean, plus f32 rounding of each term (without portals
        // every term is pi exactly but for it).
        let tolerance = 5.0 * sigma + 1e-6 * std::f64::consts::PI;
        assert!(
            (mean - std::f64::consts::PI).abs() < tolerance,
            "{mean} +- {sigma}"
        );
    }
}

#[test]
fn dome_emission_samples_integrate_the_domes_radiance() {
    // Stratified samples of L / pdf over the emission directions estimate the dome's radiance
    // integral (computed at construction by quadrature); daylight's stay above the horizon.
    let uniform = Sky::uniform(Rgb::new(1.0, 2.0, 3.0), Vec::new());
    for sky in [daylight(3.0, 40.0), daylight(6.0, 10.0), uniform] {
        let k = 256;
        let mut sum = glam::DVec3::ZERO;
        for i in 0..k * k {
            let u = Vec2::new(
                ((i % k) as f32 + 0.5) / k as f32,
                ((i / k) as f32 + 0.5) / k as f32,
            );
            let (dir, pdf) = sky.sample_dome_emission(u);
            assert!((dir.length() - 1.0).abs() < 1e-5);
            if matches!(sky.kind, SkyKind::Daylight(_)) {
                assert!(dir.dot(sky.up) >= -1e-6, "{dir}");
            }
            sum += (sky.dome_radiance(dir) / pdf).as_dvec3();
        }
        let estimate = sum / f64::from(k * k);
        let (dome, _) = sky.integrals();
        let rel = ((estimate - dome.as_dvec3()).abs() / dome.as_dvec3()).max_element();
        assert!(rel < 2e-3, "{estimate} vs {dome}: {rel}");
    }
}

#[test]
fn the_suns_integral_is_its_radiance_times_its_solid_angle() {
    let sky = daylight(3.0, 40.0);
    let sun = sky.sun.unwrap();
    let (_, integral) = sky.integrals();
    assert_eq!(integral, sun.radiance * sun.solid_angle());
    // Below the horizon: nothing.
    assert_eq!(daylight(3.0, -5.0).integrals().1, Rgb::ZERO);
}
