//! Scene builders and statistics shared by the tests.

use std::path::Path;

use twopass_scene::Scene;

/// A scene from TOML text.
pub fn scene(text: &str) -> Scene {
    twopass_scene::load_toml(text, Path::new("test.toml"))
        .expect("test scene loads")
        .0
}

/// A scene of the repository's `scenes/` folder.
pub fn repo_scene(name: &str) -> Scene {
    let path = crate::scene_path(name);
    twopass_scene::load(&path)
        .expect("repository scene loads")
        .0
}

/// Mean and standard error of the mean of `values`.
pub fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Per pixel of `scene`'s camera, the mean of `value` over the first hits of a render of
/// `spp` samples without jitter (the centres of the pixel's k x k strata, k = floor(sqrt(spp)));
/// `None` where a ray misses or `value` declines a hit.
pub fn pixel_means(
    scene: &Scene,
    spp: u32,
    value: impl Fn(&twopass_scene::Hit) -> Option<f64>,
) -> Vec<Option<f64>> {
    let cam = scene.camera;
    let k = spp.isqrt().max(1);
    let mut out = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let mut sum = Some(0.0);
            for s in 0..k * k {
                let offset = glam::Vec2::new(
                    ((s % k) as f32 + 0.5) / k as f32,
                    ((s / k) as f32 + 0.5) / k as f32,
                );
                let d = cam.direction(glam::Vec2::new(x as f32, y as f32) + offset);
                let hit = scene.intersect(&twopass_scene::Ray::new(cam.position, d));
                sum = sum.zip(hit.as_ref().and_then(&value)).map(|(a, b)| a + b);
            }
            out.push(sum.map(|t| t / f64::from(k * k)));
        }
    }
    out
}

/// A render of the reference path tracer with `settings`, `size` x `size` pixels, `spp`
/// samples per pixel, seed `seed`.
pub fn render_with(
    scene: &Scene,
    settings: twopass_trace::ReferenceSettings,
    size: u32,
    spp: u32,
    seed: u64,
) -> twopass_trace::RenderOutput {
    let camera = scene.camera.with_resolution(Some(size), Some(size));
    let reference = twopass_trace::Reference::new(scene, settings);
    let settings = twopass_trace::RenderSettings {
        samples_per_pixel: spp,
        seed,
        ..twopass_trace::RenderSettings::default()
    };
    twopass_trace::render(
        scene,
        &camera,
        &reference,
        &settings,
        &twopass_trace::RenderProgress::new(),
    )
}
