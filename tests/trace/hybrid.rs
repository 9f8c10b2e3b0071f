//! The hybrid invariant (STYLE.md G.4): on a scene whose materials are all Lambertian, the
//! hybrid renders exactly what radiosity alone renders, with a test double and with a real
//! solution; and the hybrid against the reference path tracer on the diffuse Cornell box.

use std::ops::ControlFlow;

use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;
use twopass_trace::hybrid::{hybrid, hybrid_direct, radiosity_only};
use twopass_trace::{
    Layer, Progress, Reference, ReferenceSettings, RenderSettings, WhittedSettings, render,
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
        &Progress::new(),
    );
    let b = render(
        &scene,
        &camera,
        &hybrid(&scene, &double, WhittedSettings::default()),
        &settings(),
        &Progress::new(),
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
    let _ = solver.run(|_| ControlFlow::Continue(()));
    let solution = solver.solution();
    let p = Progress::new();
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
        &hybrid(&scene, &solution, WhittedSettings::default()),
        &settings(),
        &p,
    );
    assert_eq!(alone.layers, h.layers);

    // Against the reference: the difference is the radiosity mesh's discretisation error
    // plus the reference's noise; reported, and bounded loosely as a sanity check.
    let hd = render(
        &scene,
        &camera,
        &hybrid_direct(&scene, &solution, WhittedSettings::default()),
        &settings(),
        &p,
    );
    let reference = Reference::new(&scene, ReferenceSettings::default());
    let ref_settings = RenderSettings {
        samples_per_pixel: 64,
        ..settings()
    };
    let r = render(&scene, &camera, &reference, &ref_settings, &p)
        .layers
        .composite();
    let rel_rms = |img: &twopass_trace::Image| {
        let (mut num, mut den) = (0.0_f64, 0.0_f64);
        for (a, b) in img.pixels.iter().zip(&r.pixels) {
            num += f64::from((*a - *b).length_squared());
            den += f64::from(b.length_squared());
        }
        (num / den).sqrt()
    };
    let e_h = rel_rms(&h.layers.composite());
    let e_hd = rel_rms(&hd.layers.composite());
    let (mh, mr) = (h.layers.composite().mean(), r.mean());
    eprintln!(
        "relative RMS vs reference (24x24, 64 spp, reference noise included): hybrid {e_h:.3}, \
         hybrid-direct {e_hd:.3}; image means hybrid {mh}, reference {mr}"
    );
    // Sanity bound only: the image means agree to the mesh's discretisation error.
    assert!(
        ((mh / mr) - glam::Vec3::ONE).abs().max_element() < 0.1,
        "{mh} vs {mr}"
    );
    // Both see the light itself identically.
    assert_eq!(
        h.layers.layer(Layer::Emission).mean().max_element() > 0.0,
        hd.layers.layer(Layer::Emission).mean().max_element() > 0.0
    );
}
