//! Adaptive anti-aliasing: every pixel is exactly either its first-pass estimate or its
//! full-rate estimate (each pixel estimate is a function of the seed, the pixel and the sample
//! number only), edges are refined, the image is the same on any thread count, and the error
//! against the method's own converged image is close to the full rate's at a fraction of the
//! samples.

use std::ops::ControlFlow;

use twopass_brdf::colour::luminance;
use twopass_radiosity::{Finish, Options, Solver};
use twopass_trace::hybrid::radiosity_only;
use twopass_trace::{AdaptiveSampling, RenderOutput, RenderProgress, RenderSettings, render};

use super::common::repo_scene;
use super::hybrid::relative_rmse;
use crate::on_threads;

#[test]
fn adaptive_pixels_are_first_pass_or_full_rate_and_edges_are_refined() {
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(128), Some(128));
    let mut solver = Solver::new(&scene, Options::default()).unwrap();
    assert_eq!(solver.run(|_| ControlFlow::Continue(())), Finish::Converged);
    let solution = solver.solution();
    let method = radiosity_only(&scene, &solution);
    let settings = |spp: u32, adaptive: Option<AdaptiveSampling>| RenderSettings {
        samples_per_pixel: spp,
        seed: 5,
        adaptive,
        ..RenderSettings::default()
    };
    let go = |s: &RenderSettings| -> RenderOutput {
        render(&scene, &camera, &method, s, &RenderProgress::new())
    };
    let a = AdaptiveSampling {
        base: 4,
        contrast: 0.05,
    };
    let adaptive = go(&settings(64, Some(a)));
    let first = go(&settings(4, None));
    let full = go(&settings(64, None));
    let converged = go(&settings(1024, None));

    let (img, first_img, full_img) = (
        adaptive.layers.composite(),
        first.layers.composite(),
        full.layers.composite(),
    );
    let (w, h) = (camera.width as usize, camera.height as usize);
    let lum: Vec<f32> = first_img.pixels().iter().map(|p| luminance(*p)).collect();
    let mut refined = 0;
    for (i, p) in img.pixels().iter().enumerate() {
        let is_first = *p == first_img.pixels()[i];
        let is_full = *p == full_img.pixels()[i];
        assert!(is_first || is_full, "pixel {i} is neither estimate");
        refined += usize::from(!is_first);
        // A first-pass edge against a neighbour (contrast above the threshold) is refined.
        let (x, y) = (i % w, i / w);
        for j in [(x + 1 < w).then(|| i + 1), (y + 1 < h).then(|| i + w)]
            .into_iter()
            .flatten()
        {
            let (lo, hi) = (lum[i].min(lum[j]), lum[i].max(lum[j]));
            if hi > 0.0
                && (hi - lo) / (hi + lo) > 0.05
                && first_img.pixels()[i] != full_img.pixels()[i]
            {
                assert!(
                    is_full,
                    "pixel {i} borders an edge to {j} but was not refined"
                );
            }
        }
    }
    // A refined pixel whose two estimates agree (on the light, say) looks unrefined.
    assert!(refined as u64 <= adaptive.stats.refined_pixels);
    let pixels = (w * h) as u64;
    assert!(
        adaptive.stats.refined_pixels > pixels / 50 && adaptive.stats.refined_pixels < pixels / 2,
        "{} of {pixels} pixels refined",
        adaptive.stats.refined_pixels
    );
    assert_eq!(
        adaptive.stats.samples,
        4 * pixels + 64 * adaptive.stats.refined_pixels
    );

    // Against the method's own converged image: near the full rate, far below the first pass.
    let truth = converged.layers.composite();
    let (e_adaptive, e_first, e_full) = (
        relative_rmse(&img, &truth),
        relative_rmse(&first_img, &truth),
        relative_rmse(&full_img, &truth),
    );
    println!(
        "relative RMSE against 1024 spp: first pass {e_first:.4}, adaptive {e_adaptive:.4}, \
         full rate {e_full:.4}; {} of {pixels} pixels refined",
        adaptive.stats.refined_pixels
    );
    assert!(
        e_adaptive < 1.5 * e_full,
        "{e_adaptive} vs full rate {e_full}"
    );
    assert!(
        e_adaptive < 0.5 * e_first,
        "{e_adaptive} vs first pass {e_first}"
    );

    // Same image on one and two threads.
    let on = |threads| on_threads(threads, || go(&settings(64, Some(a))).layers);
    assert_eq!(on(1), on(2));
}
