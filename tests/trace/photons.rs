//! The caustic photon map (`twopass_trace::photons`) against a closed form: a one-sided light
//! facing up under a horizontal mirror lights the floor only through the mirror, as its mirror
//! image would directly, so the photons' irradiance on the floor is the image source's, and
//! the final gather counts that light once, from the photons or from its gather rays.

use glam::Vec3;
use twopass_scene::RadianceEstimator;
use twopass_trace::gather::{GatherSettings, Gatherer};
use twopass_trace::photons::{CausticPhotons, PhotonSettings};

use super::common::scene;
use super::gather::{Constant, floor_point};

/// A 0.1 m square light at y = 1 facing up (radiance 100), a 10 m mirror at y = 2 facing down,
/// a 10 m grey floor at y = 0: no direct light reaches the floor.
const MIRRORED: &str = "version = 1\n\
    [camera]\nposition = [0, 1.5, 6]\nlook_at = [0, 0, 0]\nfov_y = 50\nresolution = [16, 16]\n\
    [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = 1\n\
    [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
    shape = { type = \"quad\", origin = [-5, 0, -5], edge_u = [0, 0, 10], edge_v = [10, 0, 0] }\n\
    [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
    shape = { type = \"quad\", origin = [-5, 2, -5], edge_u = [10, 0, 0], edge_v = [0, 0, 10] }\n\
    [[object]]\nname = \"light\"\nmaterial = \"grey\"\nemission = 100\n\
    shape = { type = \"quad\", origin = [-0.05, 1, -0.05], edge_u = [0, 0, 0.1], edge_v = [0.1, 0, 0] }\n";

/// Irradiance at floor point `p` from the light's mirror image (the square at y = 3 facing
/// down), by midpoint quadrature over the square: L cos(theta_e) cos(theta_r) / r^2 dA.
fn image_irradiance(p: Vec3) -> f64 {
    let n = 200;
    let side = 0.1f64;
    let da = (side / n as f64).powi(2);
    let mut e = 0.0;
    for i in 0..n {
        for j in 0..n {
            let q = [
                -0.05 + side * (i as f64 + 0.5) / n as f64,
                3.0,
                -0.05 + side * (j as f64 + 0.5) / n as f64,
            ];
            let d = [
                q[0] - f64::from(p.x),
                q[1] - f64::from(p.y),
                q[2] - f64::from(p.z),
            ];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let cos = d[1] / r2.sqrt();
            e += 100.0 * cos * cos / r2 * da;
        }
    }
    e
}

#[test]
fn photons_on_the_floor_give_the_mirror_image_of_the_light() {
    let s = scene(MIRRORED);
    let photons = CausticPhotons::build(
        &s,
        PhotonSettings {
            paths: 1 << 20,
            nearest: 256,
            ..PhotonSettings::default()
        },
    )
    .expect("the mirror sends light to the floor");
    for radius in [0.6f32, 1.5] {
        // Sixteen points on a ring: far enough apart that their photons do not overlap, so
        // their mean has about a quarter of one estimate's noise (1 / sqrt(255) = 6 %).
        let ring: Vec<Vec3> = (0..16)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 16.0;
                Vec3::new(radius * a.cos(), 0.0, radius * a.sin())
            })
            .collect();
        let measured = ring
            .iter()
            .map(|&p| f64::from(photons.irradiance(p, Vec3::Y).y))
            .sum::<f64>()
            / ring.len() as f64;
        let want = image_irradiance(ring[0]);
        let sigma = want / (255.0f64 * 16.0).sqrt();
        eprintln!("ring {radius}: photons {measured:.5} W/m^2, image source {want:.5}");
        assert!(
            (measured - want).abs() < 4.0 * sigma,
            "ring {radius}: photons {measured:.5} W/m^2 vs the image source's {want:.5} (sigma {sigma:.5})"
        );
    }
    // The floor's back and a wall facing it take none of the floor's photons.
    let p = Vec3::new(0.6, 0.0, 0.0);
    assert_eq!(photons.irradiance(p, -Vec3::Y).y, 0.0);
    assert_eq!(photons.irradiance(p, Vec3::X).y, 0.0);
    // Beyond the radius cap from every photon: nothing.
    assert_eq!(
        photons.irradiance(Vec3::new(0.0, 50.0, 0.0), Vec3::Y).y,
        0.0
    );
}

#[test]
fn the_photon_map_does_not_depend_on_the_thread_count() {
    let s = scene(MIRRORED);
    let build = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| CausticPhotons::build(&s, PhotonSettings::default()).unwrap())
    };
    let (one, two) = (build(1), build(2));
    assert_eq!(one.len(), two.len());
    for i in 0..32 {
        let p = Vec3::new(-1.5 + 0.1 * i as f32, 0.0, 0.3);
        assert_eq!(
            one.irradiance(p, Vec3::Y).to_array().map(f32::to_bits),
            two.irradiance(p, Vec3::Y).to_array().map(f32::to_bits)
        );
    }
}

#[test]
fn the_gather_counts_the_mirrored_light_once_and_smoother_with_photons() {
    let s = scene(MIRRORED);
    // The solution is the light's emission alone (object 2), so a floor point's indirect part
    // is exactly the light reaching it through the mirror: rho / pi E_image.
    let emission = Constant::new(&s, 100.0, &[2]);
    let estimates = |photons: Option<PhotonSettings>| {
        let g = Gatherer::new(
            &s,
            &emission,
            GatherSettings {
                photons,
                min_rays: 256,
                max_rays: 256,
                ..GatherSettings::default()
            },
        );
        assert_eq!(g.caustic_photons() > 0, photons.is_some());
        (0..24u64)
            .map(|k| {
                let a = k as f32 * std::f32::consts::TAU / 24.0;
                let (t, b) = floor_point(&s, 0.8 * a.cos(), 0.8 * a.sin());
                let e = g.estimate(t, b, k);
                assert_eq!(e.direct.y, 0.0, "no direct light reaches the floor");
                f64::from(e.indirect.y)
            })
            .collect::<Vec<f64>>()
    };
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt(), var.sqrt() / mean)
    };
    let want = 0.5 / std::f64::consts::PI * image_irradiance(Vec3::new(0.8, 0.0, 0.0));
    let (photons, e1, spread1) = stats(&estimates(Some(PhotonSettings::default())));
    let (rays, e2, spread2) = stats(&estimates(None));
    eprintln!(
        "floor at 0.8 m: photons {photons:.5} +- {e1:.5} (spread {spread1:.3}), gather rays \
         {rays:.5} +- {e2:.5} (spread {spread2:.3}), closed form {want:.5}"
    );
    // Once each way: counting it twice would double it.
    assert!(
        (photons - want).abs() < 4.0 * e1,
        "photons {photons} vs {want}"
    );
    assert!(
        (rays - want).abs() < 4.0 * e2,
        "gather rays {rays} vs {want}"
    );
    assert!(
        spread1 < 0.5 * spread2,
        "photons spread {spread1} vs gather rays {spread2}"
    );
}

/// A directional lamp's beam turned by a mirror onto a wall (`lamps::BEAM_WALL`): the photons
/// there give the beam's irradiance E, and none reach the wall outside the mirror's image.
#[test]
fn photons_carry_a_directional_lamp_through_a_mirror() {
    use crate::lamps::{BEAM_E, BEAM_WALL, in_mirrored_beam};
    let s = scene(BEAM_WALL);
    let photons = CausticPhotons::build(
        &s,
        PhotonSettings {
            paths: 1 << 18,
            nearest: 256,
            ..PhotonSettings::default()
        },
    )
    .expect("the mirror sends the lamp's light to the wall");
    let normal = Vec3::new(0.0, 0.0, -1.0);
    let mut lit = Vec::new();
    for i in 0..5 {
        for j in 0..3 {
            let p = Vec3::new(-0.3 + 0.15 * i as f32, -0.1 + 0.1 * j as f32, 2.0);
            assert_eq!(in_mirrored_beam(p, 0.1), Some(true));
            lit.push(f64::from(photons.irradiance(p, normal).y));
        }
    }
    let mean = lit.iter().sum::<f64>() / lit.len() as f64;
    // 256 photons an estimate: 6 % noise each, under 2 % over the fifteen points.
    assert!((mean / BEAM_E - 1.0).abs() < 0.05, "{mean} vs {BEAM_E}");
    for p in [Vec3::new(1.5, 0.0, 2.0), Vec3::new(0.0, 0.7, 2.0)] {
        assert_eq!(in_mirrored_beam(p, 0.1), Some(false));
        let e = photons.irradiance(p, normal);
        assert!(e.max_element() == 0.0, "{e:?} at {p}");
    }
}
