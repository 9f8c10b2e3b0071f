//! A render split into tile shares (`twopass render --part`) and assembled gives the single
//! render's bits, for any number of shares.

use twopass_trace::{
    Integrator, LayerImages, Reference, ReferenceSettings, RenderProgress, RenderSettings,
    TileShare, Whitted, WhittedSettings, add_light, render, render_share, tile_origins,
};

use super::common::repo_scene;

/// The shares' tiles copied into one image, then the light pass added, as the merge does.
fn assembled(
    scene: &twopass_scene::Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    parts: usize,
) -> (LayerImages, u64) {
    let tiles = tile_origins(camera.width, camera.height, settings.tile_size);
    let mut layers = LayerImages::new(camera.width, camera.height);
    let mut light = None;
    let mut rays = 0;
    for i in 0..parts {
        let share = TileShare {
            tiles: tiles.len() * i / parts..tiles.len() * (i + 1) / parts,
            light: i == 0,
        };
        let out = render_share(
            scene,
            camera,
            integrator,
            settings,
            &share,
            &RenderProgress::new(),
        )
        .expect("no adaptive sampling");
        rays += out.stats.rays;
        let t = settings.tile_size;
        for &(x0, y0) in &tiles[share.tiles.clone()] {
            for y in y0..(y0 + t).min(camera.height) {
                for x in x0..(x0 + t).min(camera.width) {
                    let at = (y * camera.width + x) as usize;
                    for (dst, src) in layers.images.iter_mut().zip(&out.layers.images) {
                        dst.pixels_mut()[at] = src.pixels()[at];
                    }
                }
            }
        }
        if let Some(l) = out.light {
            assert!(light.is_none(), "one share carries the light pass");
            light = Some(l);
        }
    }
    if let Some(l) = &light {
        add_light(&mut layers, l);
    }
    (layers, rays)
}

#[test]
fn shares_assembled_equal_the_single_render_bit_for_bit() {
    let scene = repo_scene("cornell-spheres.toml");
    let camera = scene.camera.with_resolution(Some(20), Some(20));
    let settings = RenderSettings {
        samples_per_pixel: 2,
        seed: 7,
        tile_size: 7,
        ..Default::default()
    };
    // The reference traces light paths through the glass sphere (a whole-image pass).
    let reference = Reference::new(&scene, ReferenceSettings::default());
    assert!(reference.light_tracer().is_some());
    let whitted = Whitted::new(
        &scene,
        twopass_trace::whitted::ambient_estimate(&scene),
        WhittedSettings::default(),
    );
    for integrator in [&reference as &dyn Integrator, &whitted] {
        let whole = render(
            &scene,
            &camera,
            integrator,
            &settings,
            &RenderProgress::new(),
        );
        // 9 tiles: 4 parts leave shares of 2 and 3 tiles, 10 leave one part empty.
        for parts in [1, 3, 4, 10] {
            let (layers, rays) = assembled(&scene, &camera, integrator, &settings, parts);
            assert_eq!(
                layers,
                whole.layers,
                "{} in {parts} parts",
                integrator.name()
            );
            assert_eq!(
                rays,
                whole.stats.rays,
                "{} in {parts} parts",
                integrator.name()
            );
        }
    }
}

#[test]
fn adaptive_sampling_is_not_split() {
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(8), Some(8));
    let settings = RenderSettings {
        samples_per_pixel: 16,
        adaptive: Some(Default::default()),
        ..Default::default()
    };
    let whitted = Whitted::new(&scene, glam::Vec3::ZERO, WhittedSettings::default());
    let share = TileShare {
        tiles: 0..1,
        light: true,
    };
    let out = render_share(
        &scene,
        &camera,
        &whitted,
        &settings,
        &share,
        &RenderProgress::new(),
    );
    assert!(out.is_none());
}
