//! A render split into tile shares (`twopass render --part`), its light tracing pass split by
//! paths, and assembled gives the single render's bits, for any number of shares.

use twopass_trace::{
    Integrator, LayerImages, LightPaths, Reference, ReferenceSettings, RenderProgress,
    RenderSettings, TileShare, Whitted, WhittedSettings, add_light, light_image, render,
    render_share, tile_origins,
};

use super::common::repo_scene;

/// The shares' tiles copied into one image, then the light pass added, as the merge does.
fn assembled(
    scene: &twopass_scene::Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    parts: usize,
) -> (LayerImages, u64, usize) {
    let tiles = tile_origins(camera.width, camera.height, settings.tile_size);
    let mut layers = LayerImages::new(camera.width, camera.height);
    let mut light = Vec::new();
    let mut rays = 0;
    for i in 0..parts {
        let share = TileShare {
            tiles: tiles.len() * i / parts..tiles.len() * (i + 1) / parts,
            light: (i as u32, parts as u32),
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
            light.push(l);
        }
    }
    let traced = light.iter().filter(|l| !l.splats.is_empty()).count();
    if let Some(paths) = light.first().map(|l| l.paths) {
        assert_eq!(
            light.len(),
            parts,
            "every share traces its run of the light pass"
        );
        let image = light_image(
            camera.width,
            camera.height,
            paths,
            light.iter().map(|l| l.splats.as_slice()),
        );
        add_light(&mut layers, &image);
    }
    (layers, rays, traced)
}

#[test]
fn shares_assembled_equal_the_single_render_bit_for_bit() {
    let scene = repo_scene("cornell-spheres.toml");
    // 48 x 48 pixels at 8 samples: 18,432 light paths, five chunks of the light pass.
    let camera = scene.camera.with_resolution(Some(48), Some(48));
    let settings = RenderSettings {
        samples_per_pixel: 8,
        seed: 7,
        tile_size: 7,
        ..Default::default()
    };
    // The reference traces light paths through the glass sphere (a whole-image pass): one
    // per camera sample, enough for several chunks, and as many as each share's pilot plans
    // (every share must plan the same).
    let reference = Reference::new(
        &scene,
        ReferenceSettings {
            light_paths: LightPaths::PerSample(1.0),
            ..ReferenceSettings::default()
        },
    );
    assert!(reference.light_tracer().is_some());
    let planned = Reference::new(&scene, ReferenceSettings::default());
    let whitted = Whitted::new(
        &scene,
        twopass_trace::whitted::ambient_estimate(&scene),
        WhittedSettings::default(),
    );
    // With whether its light pass spans several chunks.
    for (integrator, chunks) in [
        (&reference as &dyn Integrator, true),
        (&planned, false),
        (&whitted, false),
    ] {
        let whole = render(
            &scene,
            &camera,
            integrator,
            &settings,
            &RenderProgress::new(),
        );
        // 49 tiles and 5 light chunks: 3 and 4 parts split both unevenly, 10 leave some parts
        // no light chunk.
        for parts in [1, 3, 4, 10] {
            let (layers, rays, traced) = assembled(&scene, &camera, integrator, &settings, parts);
            if chunks && parts > 1 {
                assert!(
                    traced > 1,
                    "{parts} parts: the light pass is split ({traced})"
                );
            }
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
        light: (0, 1),
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
