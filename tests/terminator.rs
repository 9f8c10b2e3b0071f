//! No sawtooth at a shadow terminator: a coarse sphere (320 triangles, smooth shading
//! normals) on a floor, lit at a slant by one area light, baked into a gathered lightmap and
//! rendered from it, against the path tracer, on the rows through the terminator. The
//! solution alone (radiosity at the element mesh's vertices, interpolated) shows the
//! terminator as a band that follows the triangles; the gathered texels take their direct
//! light per texel and follow the reference.

use twopass_bake::{ColorMapping, LightmapSettings, TexelSource, bake_lightmap, read_lightmap_glb};
use twopass_radiosity::{Options, Solver};
use twopass_scene::{DiffuseRadiance, Ray, Scene};
use twopass_trace::gather::{GatherSettings, Gatherer};
use twopass_trace::{Reference, ReferenceSettings, RenderProgress, RenderSettings, render};

const SCENE: &str = "version = 1\n\
    [camera]\nposition = [0, 1.2, 4.5]\nlook_at = [0, 1, 0]\nfov_y = 32\nresolution = [64, 64]\n\
    [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
    shape = { type = \"quad\", origin = [-4, 0, -4], edge_u = [0, 0, 8], edge_v = [8, 0, 0] }\n\
    [[object]]\nname = \"ball\"\nmaterial = \"grey\"\n\
    shape = { type = \"sphere\", center = [0, 1, 0], radius = 1, subdivisions = 2 }\n\
    [[object]]\nname = \"light\"\nmaterial = \"grey\"\nemission = 40\n\
    shape = { type = \"quad\", origin = [-3.2, 2.6, -0.5], edge_u = [0.6, 0.6, 0], edge_v = [0, 0, 1] }\n";

/// Radiance images (luminance per pixel) of the ball's pixels on the rows through its
/// middle, for one render.
fn rows(scene: &Scene, image: &twopass_image::Image) -> Vec<(u32, u32, f64)> {
    let cam = scene.camera;
    let mut out = Vec::new();
    for y in 28..36 {
        for x in 0..cam.width {
            let d = cam.direction(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            if scene
                .intersect(&Ray::new(cam.position, d))
                .is_some_and(|h| h.object == 1)
            {
                let p = image.get(x, y);
                let l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
                out.push((x, y, f64::from(l)));
            }
        }
    }
    out
}

fn render_with(scene: &Scene, radiance: &dyn DiffuseRadiance) -> twopass_image::Image {
    let r = twopass_trace::hybrid::radiosity_only(scene, radiance);
    let settings = RenderSettings {
        samples_per_pixel: 4,
        seed: 1,
        ..Default::default()
    };
    render(scene, &scene.camera, &r, &settings, &RenderProgress::new())
        .layers
        .composite()
}

/// Mean absolute deviation from the reference along the rows, relative to the reference's
/// mean there.
fn deviation(a: &[(u32, u32, f64)], reference: &[(u32, u32, f64)]) -> f64 {
    assert_eq!(a.len(), reference.len());
    let mean: f64 = reference.iter().map(|r| r.2).sum::<f64>() / reference.len() as f64;
    a.iter()
        .zip(reference)
        .map(|(x, r)| (x.2 - r.2).abs())
        .sum::<f64>()
        / a.len() as f64
        / mean
}

#[test]
fn a_gathered_lightmap_follows_the_terminator_of_a_coarse_sphere() {
    let (scene, _) =
        twopass_scene::load_toml(SCENE, std::path::Path::new("terminator.toml")).unwrap();
    let mut solver = Solver::new(&scene, Options::default()).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    let solution = solver.solution();

    let reference = Reference::new(&scene, ReferenceSettings::default());
    let settings = RenderSettings {
        samples_per_pixel: 1024,
        seed: 2,
        ..Default::default()
    };
    let truth = render(
        &scene,
        &scene.camera,
        &reference,
        &settings,
        &RenderProgress::new(),
    )
    .layers
    .composite();
    let truth = rows(&scene, &truth);
    assert!(
        truth.len() > 150,
        "the rows cross the ball: {}",
        truth.len()
    );

    let gatherer = Gatherer::new(&scene, &solution, GatherSettings::default());
    let lm_settings = LightmapSettings {
        texel_size: Some(0.02),
        ..LightmapSettings::default()
    };
    let lm = bake_lightmap(
        TexelSource::Gather(&gatherer),
        &scene,
        &lm_settings,
        ColorMapping::auto(&solution),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("terminator.lightmap.glb");
    std::fs::write(&glb, &lm.glb).unwrap();
    std::fs::write(dir.path().join("terminator.lightmap.exr"), &lm.exr).unwrap();
    let gathered = read_lightmap_glb(&glb, &scene).unwrap();

    let from_lightmap = deviation(&rows(&scene, &render_with(&scene, &gathered)), &truth);
    let from_solution = deviation(&rows(&scene, &render_with(&scene, &solution)), &truth);
    eprintln!(
        "terminator rows: gathered lightmap {:.2} %, solution alone {:.2} %",
        100.0 * from_lightmap,
        100.0 * from_solution
    );
    assert!(from_lightmap < 0.03, "{from_lightmap}");
    assert!(
        from_solution > 2.0 * from_lightmap,
        "the check must see a sawtooth"
    );
}
