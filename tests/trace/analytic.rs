//! A Lambertian plane lit by a small parallel square emitter: the reflected radiance is
//! rho L_e F, with F the closed-form form factor from a differential area to a parallel
//! rectangle (Howell's catalogue, C-11, combined over the four corner rectangles).

use twopass_trace::{
    Layer, Reference, ReferenceSettings, RenderProgress, RenderSettings, Whitted, WhittedSettings,
    render,
};

use super::common::{mean_and_error, pixel_means, scene};
use crate::closed_form::corner_form_factor;

const RHO: f32 = 0.5;
const L_E: f32 = 10.0;
const SIDE: f64 = 0.5;
const HEIGHT: f64 = 1.0;

fn plane_scene() -> twopass_scene::Scene {
    scene(
        "version = 1\n\
         [camera]\nposition = [0, 0.9, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [32, 32]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[object]]\nname = \"plane\"\nmaterial = \"grey\"\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n\
         [[object]]\nname = \"light\"\nmaterial = \"black\"\nemission = 10\n\
         shape = { type = \"quad\", origin = [-0.25, 1, -0.25], edge_u = [0.5, 0, 0], edge_v = [0, 0, 0.5] }\n",
    )
}

/// Form factor from a differential area facing up at the origin to the rectangle
/// [x0, x1] x [z0, z1] at height `HEIGHT`, parallel to it.
fn form_factor(x0: f64, x1: f64, z0: f64, z1: f64) -> f64 {
    let corner = |x: f64, y: f64| corner_form_factor(x / HEIGHT, y / HEIGHT);
    corner(x1, z1) - corner(x0, z1) - corner(x1, z0) + corner(x0, z0)
}

/// The exact radiance of the plane seen through each pixel with `spp` samples: the mean of
/// the closed form at the points a render without jitter sees, the centres of the pixel's
/// k x k strata (k = floor(sqrt(spp))); None where one of them misses the plane's front. (The
/// pixel's mean, not its centre's value: the two differ by the light's curvature over a pixel,
/// about 0.3 % of this image at 8 x 8, a bias a converged estimate shows.)
fn expected(scene: &twopass_scene::Scene, spp: u32) -> Vec<Option<f64>> {
    pixel_means(scene, spp, |h| {
        (h.object == 0 && h.front_face).then(|| {
            let p = h.point.position.as_dvec3();
            let h2 = SIDE / 2.0;
            let f = form_factor(-h2 - p.x, h2 - p.x, -h2 - p.z, h2 - p.z);
            f64::from(RHO) * f64::from(L_E) * f
        })
    })
}

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: spp,
        seed: 11,
        jitter: false,
        tile_size: 8,
        adaptive: None,
    }
}

#[test]
fn closed_form_check_of_the_form_factor() {
    // A huge square: half of the hemisphere's projected area per pair of quadrants -> 1.
    assert!((form_factor(-1e6, 1e6, -1e6, 1e6) - 1.0).abs() < 1e-5);
    // Small source: F -> A cos^2 / (pi h^2) at normal incidence.
    let a = 1e-3;
    let f = form_factor(-a / 2.0, a / 2.0, -a / 2.0, a / 2.0);
    assert!((f / (a * a / std::f64::consts::PI) - 1.0).abs() < 1e-5);
}

#[test]
fn whitted_matches_the_closed_form_within_one_percent() {
    let scene = plane_scene();
    let exact = expected(&scene, 1);
    // 16 x 16 stratified shadow rays: the estimate of a smooth integrand over the square
    // converges as N^-3/2; per-pixel errors are far below the 1% the issue asks.
    let w = Whitted::new(
        &scene,
        glam::Vec3::ZERO,
        WhittedSettings {
            shadow_grid: 16,
            ..Default::default()
        },
    );
    let out = render(
        &scene,
        &scene.camera,
        &w,
        &settings(1),
        &RenderProgress::new(),
    );
    let img = out.layers.layer(Layer::Diffuse);
    let mut worst = 0.0_f64;
    let mut n = 0;
    for (i, e) in exact.iter().enumerate() {
        if let Some(e) = e {
            let got = f64::from(img.pixels()[i].x);
            worst = worst.max((got / e - 1.0).abs());
            n += 1;
        }
    }
    assert!(n > 500, "the plane fills the view: {n} pixels");
    assert!(worst < 0.01, "worst relative error {worst}");
    assert_eq!(out.stats.non_finite, 0);
}

#[test]
fn reference_matches_the_closed_form_within_its_noise_and_one_percent() {
    let scene = plane_scene();
    let exact = expected(&scene, 64);
    let r = Reference::new(&scene, ReferenceSettings::default());
    let out = render(
        &scene,
        &scene.camera,
        &r,
        &settings(64),
        &RenderProgress::new(),
    );
    let img = out.layers.composite();
    // Per pixel relative differences are independent estimates of zero.
    let diffs: Vec<f64> = exact
        .iter()
        .enumerate()
        .filter_map(|(i, e)| e.map(|e| f64::from(img.pixels()[i].x) / e - 1.0))
        .collect();
    let (mean, err) = mean_and_error(&diffs);
    eprintln!("reference vs closed form: mean relative difference {mean:.2e} +- {err:.1e}");
    assert!(mean.abs() < 4.0 * err, "biased: {mean} +- {err}");
    assert!(4.0 * err < 0.01, "too noisy to decide at 1%: {err}");
}

/// The plane under five parallel square emitters of different radiances at height `HEIGHT`
/// (centre x, centre z, L_e), and one more facing up (it lights nothing below).
const EMITTERS: [(f64, f64, f64); 5] = [
    (0.0, 0.0, 10.0),
    (-1.0, -1.0, 20.0),
    (1.0, -1.0, 5.0),
    (-1.0, 1.0, 40.0),
    (1.2, 0.9, 2.0),
];

fn many_emitters_scene() -> twopass_scene::Scene {
    let mut text = String::from(
        "version = 1\n\
         [camera]\nposition = [0, 0.9, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [32, 32]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[object]]\nname = \"plane\"\nmaterial = \"grey\"\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n",
    );
    let h = SIDE / 2.0;
    for (i, (x, z, l)) in EMITTERS.iter().enumerate() {
        text += &format!(
            "[[object]]\nname = \"light-{i}\"\nmaterial = \"black\"\nemission = {l}\n\
             shape = {{ type = \"quad\", origin = [{}, {HEIGHT}, {}], edge_u = [{SIDE}, 0, 0], edge_v = [0, 0, {SIDE}] }}\n",
            x - h,
            z - h
        );
    }
    text += &format!(
        "[[object]]\nname = \"up\"\nmaterial = \"black\"\nemission = 100\n\
         shape = {{ type = \"quad\", origin = [0.25, {HEIGHT}, 0.75], edge_u = [0, 0, {SIDE}], edge_v = [{SIDE}, 0, 0] }}\n"
    );
    scene(&text)
}

#[test]
fn whitted_under_many_emitters_matches_the_closed_form_with_a_shared_shadow_budget() {
    // 16 shadow rays per point in all, each ray's emitter chosen by its importance at the
    // point (not 16 per emitter): the estimate must stay unbiased against the sum of the
    // five closed forms, and the emitter facing away must add nothing.
    let scene = many_emitters_scene();
    let spp = 64;
    let exact = pixel_means(&scene, spp, |h| {
        (h.object == 0 && h.front_face).then(|| {
            let p = h.point.position.as_dvec3();
            let h2 = SIDE / 2.0;
            EMITTERS
                .iter()
                .map(|&(x, z, l)| {
                    let f = form_factor(x - h2 - p.x, x + h2 - p.x, z - h2 - p.z, z + h2 - p.z);
                    f64::from(RHO) * l * f
                })
                .sum::<f64>()
        })
    });
    let w = Whitted::new(
        &scene,
        glam::Vec3::ZERO,
        WhittedSettings {
            shadow_grid: 4,
            ..Default::default()
        },
    );
    let out = render(
        &scene,
        &scene.camera,
        &w,
        &settings(spp),
        &RenderProgress::new(),
    );
    let img = out.layers.layer(Layer::Diffuse);
    let diffs: Vec<f64> = exact
        .iter()
        .enumerate()
        .filter_map(|(i, e)| e.map(|e| f64::from(img.pixels()[i].x) / e - 1.0))
        .collect();
    assert!(
        diffs.len() > 500,
        "the plane fills the view: {}",
        diffs.len()
    );
    let (mean, err) = mean_and_error(&diffs);
    eprintln!("many emitters vs closed form: mean relative difference {mean:.2e} +- {err:.1e}");
    assert!(mean.abs() < 4.0 * err, "biased: {mean} +- {err}");
    assert!(4.0 * err < 0.01, "too noisy to decide at 1%: {err}");
    // The shared budget: 16 shadow rays per camera sample at most, not 16 per emitter.
    let samples = (diffs.len() as u64) * u64::from(spp);
    assert!(
        out.stats.shadow_rays <= 16 * 32 * 32 * u64::from(spp),
        "{} shadow rays for {samples} samples on the plane",
        out.stats.shadow_rays
    );
    assert_eq!(out.stats.non_finite, 0);
}
