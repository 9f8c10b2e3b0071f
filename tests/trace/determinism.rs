//! Determinism (ARCHITECTURE.md, "Conventions", seeds) and the handling of non-finite samples.

use twopass_scene::{Ray, Scene};
use twopass_trace::{
    Integrator, Layer, Radiance, Reference, ReferenceSettings, RenderProgress, RenderSettings,
    SampleState, Whitted, WhittedSettings, render,
};

use super::common::repo_scene;
use crate::on_threads;

#[test]
fn same_seed_gives_bit_identical_images_at_one_and_two_threads() {
    let scene = repo_scene("cornell-spheres.toml");
    let camera = scene.camera.with_resolution(Some(20), Some(20));
    let settings = RenderSettings {
        samples_per_pixel: 3,
        seed: 42,
        tile_size: 7,
        ..Default::default()
    };
    let reference = Reference::new(&scene, ReferenceSettings::default());
    let whitted = Whitted::new(
        &scene,
        twopass_trace::whitted::ambient_estimate(&scene),
        WhittedSettings::default(),
    );
    for integrator in [&reference as &dyn Integrator, &whitted] {
        let on = |threads| {
            on_threads(threads, || {
                render(
                    &scene,
                    &camera,
                    integrator,
                    &settings,
                    &RenderProgress::new(),
                )
            })
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one.layers, two.layers, "{} differs", integrator.name());
        assert_eq!(
            (one.stats.rays, one.stats.shadow_rays, one.stats.non_finite),
            (two.stats.rays, two.stats.shadow_rays, two.stats.non_finite)
        );
        // Another seed gives another image (the seed is used).
        let other = render(
            &scene,
            &camera,
            integrator,
            &RenderSettings {
                seed: 43,
                ..settings
            },
            &RenderProgress::new(),
        );
        assert_ne!(one.layers, other.layers);
    }
}

/// An integrator that returns NaN or infinity for some samples and 1 otherwise.
struct Faulty;

impl Integrator for Faulty {
    fn name(&self) -> &'static str {
        "faulty"
    }
    fn radiance(&self, _: &Scene, _: &Ray, sample: SampleState<'_>) -> Radiance {
        let u = sample.sampler.next_f32();
        let v = if u < 0.2 {
            f32::NAN
        } else if u < 0.3 {
            f32::INFINITY
        } else {
            1.0
        };
        Radiance::single(Layer::Diffuse, glam::Vec3::splat(v))
    }
}

#[test]
fn non_finite_samples_are_counted_and_never_written() {
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(16), Some(16));
    let settings = RenderSettings {
        samples_per_pixel: 4,
        ..Default::default()
    };
    let progress = RenderProgress::new();
    let out = render(&scene, &camera, &Faulty, &settings, &progress);
    assert_eq!(progress.done(), 256);
    assert_eq!(progress.fraction(), 1.0);
    // About 30% of 1024 samples are bad; the exact count is fixed by the seed.
    let bad = out.stats.non_finite;
    assert!((200..420).contains(&bad), "{bad}");
    for img in &out.layers.images {
        assert!(img.pixels().iter().all(|p| p.is_finite()));
    }
    // Each pixel is the mean of its finite samples: 1, or 0 where all four were bad.
    let d = out.layers.layer(Layer::Diffuse);
    assert!(
        d.pixels()
            .iter()
            .all(|p| *p == glam::Vec3::ONE || *p == glam::Vec3::ZERO)
    );
}

#[test]
fn layers_sum_to_the_image_and_split_by_first_event() {
    let scene = repo_scene("cornell-spheres.toml");
    let camera = scene.camera.with_resolution(Some(24), Some(24));
    let w = Whitted::new(
        &scene,
        twopass_trace::whitted::ambient_estimate(&scene),
        WhittedSettings::default(),
    );
    let out = render(
        &scene,
        &camera,
        &w,
        &RenderSettings::default(),
        &RenderProgress::new(),
    );
    let l = &out.layers;
    // The spheres reflect and refract; the walls are diffuse with ambient; the light emits.
    for layer in [
        Layer::Emission,
        Layer::Diffuse,
        Layer::Reflection,
        Layer::Refraction,
        Layer::Ambient,
    ] {
        assert!(
            l.layer(layer).mean().max_element() > 0.0,
            "{} empty",
            layer.name()
        );
    }
    // No glossy material in this scene.
    assert_eq!(l.layer(Layer::DirectSpecular).mean(), glam::Vec3::ZERO);
    let sum = l.composite();
    let manual = l.images.iter().fold(
        vec![glam::Vec3::ZERO; sum.pixels().len()],
        |mut acc, img| {
            for (a, p) in acc.iter_mut().zip(img.pixels()) {
                *a += *p;
            }
            acc
        },
    );
    assert_eq!(sum.pixels(), manual);
}
