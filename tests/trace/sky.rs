//! The sky in the tracer against closed forms: a plane of reflectance rho under a uniform
//! sky of radiance L shows rho L in every integrator (the path tracer's light sample and its
//! escaping BRDF rays count the sky once between them); a diffuse sphere of albedo a under a
//! uniform sky shows a L (the white furnace); a plane under daylight shows rho / pi (E_sun +
//! E_dome) with the model's own sun radiance; the final gather's direct part is rho L; a sun
//! at or below the horizon puts no NaN in any image; one and two threads give the same image.

use glam::Vec3;
use twopass_scene::Scene;
use twopass_trace::gather::{GatherSettings, Gatherer};
use twopass_trace::{
    Integrator, Reference, ReferenceSettings, RenderProgress, RenderSettings, WhittedSettings,
    render,
};

use super::common::{mean_and_error, pixel_means, scene};
use crate::lamps::{RHO, plane_under};

fn settings(spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: spp,
        seed,
        jitter: false,
        tile_size: 8,
        adaptive: None,
    }
}

/// A solution of `scene` converged to 1e-6 of the emitted power (a sky's power is what
/// crosses the scene's bounding sphere, most of which reaches no surface, so the default
/// stop would leave an ambient term that shows in the classic hybrid).
fn solve(scene: &Scene, element_size: f32) -> twopass_radiosity::Solution {
    let options = twopass_radiosity::Options {
        element_size: Some(element_size),
        stop: twopass_radiosity::Stop {
            unshot_fraction: 1e-6,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut solver = twopass_radiosity::Solver::new(scene, options).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    solver.solution()
}

/// `integrator`'s image of `s` through `camera` at `spp` samples per pixel with `seed`,
/// after checking that no sample was NaN or infinite (`what` names the case).
fn image(
    s: &Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    (spp, seed): (u32, u64),
    what: &str,
) -> twopass_image::Image {
    let out = render(
        s,
        camera,
        integrator,
        &settings(spp, seed),
        &RenderProgress::new(),
    );
    assert_eq!(out.stats.non_finite, 0, "{what}");
    out.layers.composite()
}

const UNIFORM: &str = "[sky]\nkind = \"uniform\"\nradiance = [1, 2, 3]\n";

/// Every integrator for `s` (the hybrids over a solution of it).
fn integrators<'a>(
    s: &'a Scene,
    solution: &'a twopass_radiosity::Solution,
) -> Vec<Box<dyn Integrator + 'a>> {
    vec![
        Box::new(Reference::new(s, ReferenceSettings::default())),
        Box::new(twopass_trace::Whitted::new(
            s,
            Vec3::ZERO,
            WhittedSettings::default(),
        )),
        Box::new(twopass_trace::hybrid::gathered(
            s,
            solution,
            WhittedSettings::default(),
        )),
        Box::new(twopass_trace::hybrid::hybrid(
            s,
            solution,
            twopass_trace::hybrid::DirectLight::FromSolution,
            WhittedSettings::default(),
        )),
        Box::new(twopass_trace::hybrid::hybrid(
            s,
            solution,
            twopass_trace::hybrid::DirectLight::PerPixel,
            WhittedSettings::default(),
        )),
    ]
}

#[test]
fn a_plane_under_a_uniform_sky_shows_rho_l_in_every_integrator() {
    let s = plane_under(UNIFORM, false);
    let solution = solve(&s, 0.25);
    let plane = pixel_means(&s, 4, |h| (h.object == 0 && h.front_face).then_some(1.0));
    let sky_only = pixel_means(&s, 4, |_| None::<f64>);
    let l = Vec3::new(1.0, 2.0, 3.0);
    for integrator in integrators(&s, &solution) {
        let img = image(
            &s,
            &s.camera,
            integrator.as_ref(),
            (4, 5),
            integrator.name(),
        );
        let (mut on_plane, mut on_sky) = (0, 0);
        for (i, p) in img.pixels().iter().enumerate() {
            // Whole pixels on the plane: rho L (each light sample and escaping BRDF ray of a
            // uniform sky gives it exactly: f32 rounding only); whole pixels of sky: L.
            let expected = if plane[i].is_some() {
                on_plane += 1;
                l * RHO as f32
            } else if sky_only[i].is_none() && is_sky_pixel(&s, i) {
                on_sky += 1;
                l
            } else {
                continue;
            };
            assert!(
                ((*p - expected).abs() / expected).max_element() < 1e-4,
                "{}: pixel {i}: {p} vs {expected}",
                integrator.name()
            );
        }
        assert!(on_plane > 100 && on_sky > 10, "{on_plane} {on_sky}");
    }
}

/// Whether every stratum centre of pixel `i` at 4 spp misses the scene.
fn is_sky_pixel(s: &Scene, i: usize) -> bool {
    let cam = s.camera;
    let (x, y) = ((i as u32 % cam.width) as f32, (i as u32 / cam.width) as f32);
    [0.25, 0.75].iter().all(|&a| {
        [0.25, 0.75].iter().all(|&b| {
            let d = cam.direction(glam::Vec2::new(x + a, y + b));
            s.intersect(&twopass_scene::Ray::new(cam.position, d))
                .is_none()
        })
    })
}

#[test]
fn a_diffuse_sphere_under_a_uniform_sky_shows_albedo_times_l_the_white_furnace() {
    // The camera is close enough that the sphere fills the image: every pixel is the sphere,
    // which, convex, sees only the sky: L_out = a L.
    let s = scene(
        "version = 1\n\
         [camera]\nposition = [0, 0, 1.6]\nlook_at = [0, 0, 0]\nfov_y = 30\nresolution = [24, 24]\n\
         [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.8\n\
         [[object]]\nname = \"ball\"\nmaterial = \"white\"\n\
         shape = { type = \"sphere\", center = [0, 0, 0], radius = 1, subdivisions = 5 }\n\
         [sky]\nkind = \"uniform\"\nradiance = 2\n",
    );
    let solution = solve(&s, 0.2);
    for integrator in integrators(&s, &solution) {
        let name = integrator.name();
        let img = image(&s, &s.camera, integrator.as_ref(), (16, 2), name);
        let values: Vec<f64> = img.pixels().iter().map(|p| f64::from(p.x)).collect();
        let (mean, error) = mean_and_error(&values);
        let worst = values.iter().map(|v| (v - 1.6).abs()).fold(0.0, f64::max);
        eprintln!("{name}: mean {mean} +- {error}, worst pixel off by {worst}");
        // The sphere's facets: a direction sampled about a smooth shading normal can leave
        // below its flat facet (carrying nothing), about 1 - cos of the facet's half angle
        // at subdivision 5 (1.2e-3); the radiosity solution interpolates vertex values over
        // flat elements the same way. Nothing else may differ.
        assert!(
            (mean - 1.6).abs() < 2e-3 * 1.6 + 5.0 * error,
            "{name}: {mean} +- {error}"
        );
    }
}

#[test]
fn a_plane_under_daylight_shows_the_suns_closed_form_plus_the_dome() {
    let s = plane_under(
        "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = 35\nsun_azimuth = 30\nscale = 0.001\n",
        false,
    );
    let sky = s.sky.as_ref().unwrap();
    let sun = sky.sun.unwrap();
    let half = (0.53f64 / 2.0).to_radians();
    let omega = std::f64::consts::TAU * (1.0 - half.cos());
    let e_sun = f64::from(sun.radiance.x) * omega * 35f64.to_radians().sin();
    // The dome's irradiance (red), by a fine midpoint rule over the upper hemisphere.
    let e_dome = crate::sky::dome_irradiance(sky, Vec3::Y).x;
    let expected = RHO / std::f64::consts::PI * (e_sun + e_dome);
    let plane = pixel_means(&s, 16, |h| (h.object == 0 && h.front_face).then_some(1.0));
    let solution = solve(&s, 0.25);
    for integrator in integrators(&s, &solution) {
        let name = integrator.name();
        let img = image(&s, &s.camera, integrator.as_ref(), (16, 4), name);
        let values: Vec<f64> = plane
            .iter()
            .zip(img.pixels())
            .filter_map(|(p, v)| p.map(|_| f64::from(v.x)))
            .collect();
        // Each pixel is an independent estimate of the same value (the plane is evenly
        // lit): their mean is within five standard errors, plus 1e-3 for the quadrature and
        // the sun's and dome's rounding.
        let (mean, error) = mean_and_error(&values);
        eprintln!("{name}: {mean} +- {error} vs {expected}");
        assert!(
            (mean - expected).abs() < 5.0 * error + 1e-3 * expected,
            "{name}: {mean} +- {error} vs {expected}"
        );
    }
}

#[test]
fn the_final_gathers_direct_part_under_a_uniform_sky_is_rho_l() {
    let s = plane_under(UNIFORM, false);
    let solution = solve(&s, 0.25);
    let gatherer = Gatherer::new(&s, &solution, GatherSettings::default());
    use twopass_scene::RadianceEstimator;
    for (key, b) in [[0.2f32, 0.3, 0.5], [0.6, 0.2, 0.2], [1.0 / 3.0; 3]]
        .into_iter()
        .enumerate()
    {
        let e = gatherer.estimate(0, b, key as u64);
        let expected = Vec3::new(1.0, 2.0, 3.0) * RHO as f32;
        assert!(
            ((e.direct - expected).abs() / expected).max_element() < 1e-4,
            "{} vs {expected}",
            e.direct
        );
        // The gather rays escape: nothing reflects onto the plane.
        assert_eq!(e.indirect, Vec3::ZERO);
    }
}

#[test]
fn a_sun_at_or_below_the_horizon_puts_no_nan_in_any_image() {
    for elevation in [0.0, -0.01, -30.0, 0.01] {
        let s = plane_under(
            &format!("[sky]\nkind = \"daylight\"\nsun_elevation = {elevation}\nscale = 0.001\n"),
            true,
        );
        let solution = solve(&s, 0.25);
        assert!(solution.vertex_radiosity().iter().all(|v| v.is_finite()));
        for integrator in integrators(&s, &solution) {
            let what = format!("{elevation}: {}", integrator.name());
            let img = image(&s, &s.camera, integrator.as_ref(), (4, 1), &what);
            assert!(img.pixels().iter().all(|p| p.is_finite()), "{what}");
        }
    }
}

#[test]
fn the_sky_renders_the_same_on_one_and_two_threads() {
    let s = plane_under(
        "[sky]\nkind = \"daylight\"\nsun_elevation = 40\nscale = 0.001\n",
        true,
    );
    let solution = solve(&s, 0.25);
    let camera = s.camera.with_resolution(Some(16), Some(16));
    for i in 0..integrators(&s, &solution).len() {
        let image = || {
            let all = integrators(&s, &solution);
            render(
                &s,
                &camera,
                all[i].as_ref(),
                &settings(8, 9),
                &RenderProgress::new(),
            )
            .layers
            .composite()
        };
        let one = crate::on_threads(1, image);
        let two = crate::on_threads(2, image);
        assert!(one.pixels() == two.pixels(), "integrator {i}");
    }
}
