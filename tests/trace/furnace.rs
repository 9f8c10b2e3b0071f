//! The furnace for the path tracer: a closed enclosure whose every surface has albedo 0.5 and
//! emits 0.5 has radiance L = L_e / (1 - rho) = 1 everywhere. The enclosure is a cube of six
//! inward-facing quads (built-in spheres face outward and emitters are one-sided, so a sphere
//! seen from inside would neither emit nor reflect).

use twopass_trace::{Reference, ReferenceSettings, RenderProgress, RenderSettings, render};

use super::common::{mean_and_error, scene};

pub(super) const CUBE: &str = "version = 1\n\
    [camera]\nposition = [0.1, -0.2, 0.05]\nlook_at = [0.4, 0.3, 1]\nfov_y = 100\nresolution = [32, 32]\n\
    [[material]]\nname = \"half\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[object]]\nname = \"floor\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [-1, -1, -1], edge_u = [0, 0, 2], edge_v = [2, 0, 0] }\n\
    [[object]]\nname = \"ceiling\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [-1, 1, -1], edge_u = [2, 0, 0], edge_v = [0, 0, 2] }\n\
    [[object]]\nname = \"left\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [-1, -1, -1], edge_u = [0, 2, 0], edge_v = [0, 0, 2] }\n\
    [[object]]\nname = \"right\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [1, -1, -1], edge_u = [0, 0, 2], edge_v = [0, 2, 0] }\n\
    [[object]]\nname = \"back\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [-1, -1, -1], edge_u = [2, 0, 0], edge_v = [0, 2, 0] }\n\
    [[object]]\nname = \"front\"\nmaterial = \"half\"\nemission = 0.5\n\
    shape = { type = \"quad\", origin = [-1, -1, 1], edge_u = [0, 2, 0], edge_v = [2, 0, 0] }\n";

#[test]
fn path_tracer_furnace_has_radiance_one() {
    let scene = scene(CUBE);
    let r = Reference::new(&scene, ReferenceSettings::default());
    let settings = RenderSettings {
        samples_per_pixel: 16,
        seed: 3,
        ..Default::default()
    };
    let out = render(&scene, &scene.camera, &r, &settings, &RenderProgress::new());
    assert_eq!(out.stats.non_finite, 0);
    assert_reads_one(&out.layers.composite(), 0.02);
    // The camera sees only emitters: the emission layer holds exactly L_e = 0.5.
    let e = out.layers.layer(twopass_trace::Layer::Emission).mean();
    assert!(e.abs_diff_eq(glam::Vec3::splat(0.5), 1e-6), "{e}");
}

/// Asserts that `img`, whose every pixel is an independent unbiased estimate of 1 (the
/// furnace's radiance), has a mean of 1 per channel within four standard errors, and that
/// four standard errors are below `resolution`.
pub(super) fn assert_reads_one(img: &twopass_image::Image, resolution: f64) {
    for c in 0..3 {
        let values: Vec<f64> = img.pixels().iter().map(|p| f64::from(p[c])).collect();
        let (mean, err) = mean_and_error(&values);
        eprintln!("furnace channel {c}: {mean:.5} +- {err:.5}");
        assert!((mean - 1.0).abs() < 4.0 * err, "biased: {mean} +- {err}");
        assert!(
            4.0 * err < resolution,
            "too noisy to decide at {resolution}: {err}"
        );
    }
}
