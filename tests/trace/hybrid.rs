//! The classic hybrid's invariant (ARCHITECTURE.md, "Hybrid without double counting"): on a
//! scene whose materials are all Lambertian, the classic hybrid (`hybrid-classic`: the solution
//! shown where the camera sees a diffuse surface) renders exactly what radiosity alone renders,
//! with a test double and with a real solution; and the classic hybrid against the reference
//! path tracer on the diffuse Cornell box. The gathered hybrid (`hybrid`) traces shadow and
//! gather rays on any scene; tests/trace/gathered.rs checks it.

use std::ops::ControlFlow;

use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;
use twopass_trace::hybrid::{DirectLight, hybrid, radiosity_only};
use twopass_trace::{
    Layer, Reference, ReferenceSettings, RenderProgress, RenderSettings, WhittedSettings, render,
};

use super::common::repo_scene;

/// A smooth, position-dependent stand-in for a solution.
struct Smooth;

impl DiffuseRadiance for Smooth {
    fn radiance(&self, triangle: u32, b: [f32; 3]) -> Rgb {
        Rgb::new(
            0.3 + 0.2 * b[0],
            0.1 + 0.01 * (triangle % 13) as f32,
            0.5 * b[2],
        )
    }
    fn indirect_radiance(&self, triangle: u32, b: [f32; 3]) -> Rgb {
        self.radiance(triangle, b) * 0.25
    }
}

fn settings() -> RenderSettings {
    RenderSettings {
        samples_per_pixel: 4,
        seed: 9,
        ..Default::default()
    }
}

#[test]
fn hybrid_equals_radiosity_alone_on_lambertian_scenes() {
    let scene = repo_scene("cornell-box.toml");
    assert!(
        scene
            .materials
            .iter()
            .all(|m| !m.material.has_non_diffuse())
    );
    let camera = scene.camera.with_resolution(Some(24), Some(24));
    let double = Smooth;
    let a = render(
        &scene,
        &camera,
        &radiosity_only(&scene, &double),
        &settings(),
        &RenderProgress::new(),
    );
    let b = render(
        &scene,
        &camera,
        &hybrid(
            &scene,
            &double,
            DirectLight::FromSolution,
            WhittedSettings::default(),
        ),
        &settings(),
        &RenderProgress::new(),
    );
    assert_eq!(a.layers, b.layers, "hybrid differs from radiosity alone");
    assert_eq!(
        b.stats.shadow_rays, 0,
        "the hybrid traced shadow rays on Lambertian walls"
    );
    assert_eq!(a.stats.rays, b.stats.rays);
}

#[test]
fn hybrid_with_a_real_solution_matches_radiosity_alone_and_the_reference() {
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(24), Some(24));
    let mut solver =
        twopass_radiosity::Solver::new(&scene, twopass_radiosity::Options::default()).unwrap();
    let finish = solver.run(|_| ControlFlow::Continue(()));
    assert_eq!(finish, twopass_radiosity::Finish::Converged);
    let solution = solver.solution();
    let p = RenderProgress::new();
    let alone = render(
        &scene,
        &camera,
        &radiosity_only(&scene, &solution),
        &settings(),
        &p,
    );
    let h = render(
        &scene,
        &camera,
        &hybrid(
            &scene,
            &solution,
            DirectLight::FromSolution,
            WhittedSettings::default(),
        ),
        &settings(),
        &p,
    );
    assert_eq!(alone.layers, h.layers);

    // Both see the light itself identically.
    let hd = render(
        &scene,
        &camera,
        &hybrid(
            &scene,
            &solution,
            DirectLight::PerPixel,
            WhittedSettings::default(),
        ),
        &settings(),
        &p,
    );
    assert_eq!(
        h.layers.layer(Layer::Emission),
        hd.layers.layer(Layer::Emission)
    );
}

/// Relative RMS error of issue 7: sqrt(mean((x - r)^2 / (r^2 + 0.01))) over pixels and channels.
pub(super) fn relative_rmse(x: &twopass_image::Image, r: &twopass_image::Image) -> f64 {
    let mut sum = 0.0;
    for (a, b) in x.pixels().iter().zip(r.pixels()) {
        for c in 0..3 {
            let (a, b) = (f64::from(a[c]), f64::from(b[c]));
            sum += (a - b).powi(2) / (b * b + 0.01);
        }
    }
    (sum / (3 * x.pixels().len()) as f64).sqrt()
}

#[test]
fn hybrid_error_against_the_reference_shrinks_as_the_mesh_is_refined() {
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(16), Some(16));
    let p = RenderProgress::new();
    // Two independent references: their difference measures the reference's own noise.
    let reference = Reference::new(&scene, ReferenceSettings::default());
    let spp = |samples_per_pixel, seed| RenderSettings {
        samples_per_pixel,
        seed,
        ..Default::default()
    };
    let r1 = render(&scene, &camera, &reference, &spp(1024, 1), &p)
        .layers
        .composite();
    let r2 = render(&scene, &camera, &reference, &spp(1024, 2), &p)
        .layers
        .composite();
    // Each reference has noise e / sqrt(2) when two differ by e.
    let noise = relative_rmse(&r1, &r2) / std::f64::consts::SQRT_2;
    let mut errors = Vec::new();
    for element_size in [250.0, 60.0, 20.0] {
        let options = twopass_radiosity::Options {
            element_size: Some(element_size),
            patch_size: Some(120.0_f32.max(element_size)),
            adaptive: None,
            stop: twopass_radiosity::Stop {
                unshot_fraction: 1e-4,
                ..Default::default()
            },
            ..Default::default()
        };
        let mut solver = twopass_radiosity::Solver::new(&scene, options).unwrap();
        let finish = solver.run(|_| ControlFlow::Continue(()));
        assert_eq!(
            finish,
            twopass_radiosity::Finish::Converged,
            "element size {element_size}: the solve must reach unshot 1e-4"
        );
        let solution = solver.solution();
        // As many pixel samples as the reference: the light's edge pixels then agree, and what
        // remains is the mesh's discretisation error.
        let h = render(
            &scene,
            &camera,
            &hybrid(
                &scene,
                &solution,
                DirectLight::FromSolution,
                WhittedSettings::default(),
            ),
            &spp(1024, 3),
            &p,
        )
        .layers
        .composite();
        errors.push(relative_rmse(&h, &r1));
    }
    // The error is sqrt(d^2 + noise^2), d the mesh's discretisation error; the same reference
    // serves every mesh, so its noise shifts all three alike and their order is the mesh's.
    let d: Vec<f64> = errors
        .iter()
        .map(|e| (e * e - noise * noise).max(0.0).sqrt())
        .collect();
    eprintln!(
        "relative RMSE vs reference (16x16, 1024 spp): {errors:?}; reference noise {noise:.4}; discretisation {d:?}"
    );
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
    assert!(
        errors[0] - errors[2] > 2.0 * noise,
        "{errors:?} with reference noise {noise}"
    );
}
