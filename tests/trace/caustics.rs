//! Light tracing of caustics (twopass_trace::light_tracing) and the reference path tracer that
//! leaves the caustic paths to it: the light through a flat mirror against the exact
//! form factor of the mirrored emitter, the two strategies of the reference against each other
//! on the Cornell spheres (each path counted once: same image in expectation), the same
//! image on one and two threads, and the light paths a pilot plans for the pass.

use std::f64::consts::PI;

use glam::{DVec3, Vec2};
use twopass_scene::Scene;
use twopass_trace::{
    CausticScope, Caustics, LightPaths, LightTracer, LightTracingSettings, ReferenceSettings,
    RenderOutput, RenderProgress,
};

use super::common::{render_with, repo_scene, scene};
use crate::on_threads;
use crate::specular::{mirror_text, through_mirror};

/// A flat mirror of reflectance (0.9, 0.6, 0.3) in y = 0 (x in [-1.2, 0], facing up), a small emitter
/// (0.2 x 0.2, L_e = 1, black) and a grey receiver (rho = 0.5, 0.4 x 0.4) side by side in the
/// plane y = 1, both facing down, and a camera under the receiver looking up at it. The
/// receiver sees the emitter only through the mirror: every bit of its light is a caustic path
/// L S D E, which the reference leaves to light tracing.
fn mirror_scene() -> Scene {
    let camera = "position = [0.5, 0.35, 0.0]\nlook_at = [0.5, 1, 0]\nup = [0, 0, 1]\nfov_y = 40";
    scene(&mirror_text(camera, [0.9, 0.6, 0.3], false, "black"))
}

fn render_reference(
    scene: &Scene,
    size: u32,
    spp: u32,
    seed: u64,
    caustics: Caustics,
) -> RenderOutput {
    // One light path per camera sample: the strategies compared, not the plan.
    let settings = ReferenceSettings {
        caustics,
        light_paths: LightPaths::PerSample(1.0),
        ..ReferenceSettings::default()
    };
    render_with(scene, settings, size, spp, seed)
}

#[test]
fn light_traced_caustic_through_a_mirror_is_the_mirrored_emitters_light() {
    let s = mirror_scene();
    let size = 24;
    let camera = s.camera.with_resolution(Some(size), Some(size));
    let tracer = LightTracer::new(&s, LightTracingSettings::new(CausticScope::All))
        .expect("a mirror and an emitter: light tracing has work");
    let paths = 1 << 22;
    let lit = tracer.trace(&s, &camera, paths, 7, &RenderProgress::new(), 0);
    assert_eq!(lit.paths, paths);
    assert_eq!(lit.non_finite, 0);
    let image = lit.layers.composite();
    // Per pixel, the exact mean radiance: rho / pi times the irradiance through the mirror,
    // averaged over an 8 x 8 grid of points of the pixel's footprint on the plane y = 1; only
    // pixels whose footprint lies inside the receiver count.
    let r = [0.9, 0.6, 0.3];
    let (mut measured, mut expected, mut pixels) = (DVec3::ZERO, DVec3::ZERO, 0);
    let mut worst_block: f64 = 0.0;
    let mut blocks = std::collections::BTreeMap::<(u32, u32), (DVec3, DVec3)>::new();
    for y in 0..size {
        for x in 0..size {
            let mut sum = 0.0;
            let mut inside = true;
            for k in 0..64 {
                let p = Vec2::new(
                    x as f32 + ((k % 8) as f32 + 0.5) / 8.0,
                    y as f32 + ((k / 8) as f32 + 0.5) / 8.0,
                );
                let d = camera.direction(p).as_dvec3();
                let o = camera.position.as_dvec3();
                let hit = o + d * ((1.0 - o.y) / d.y);
                if !(0.3..=0.7).contains(&hit.x) || !(-0.2..=0.2).contains(&hit.z) {
                    inside = false;
                }
                sum += through_mirror(hit);
            }
            if !inside {
                continue;
            }
            let want = DVec3::from_array(r) * (0.5 / PI * sum / 64.0);
            let got = image.get(x, y).as_dvec3();
            measured += got;
            expected += want;
            pixels += 1;
            let b = blocks.entry((x / 4, y / 4)).or_default();
            b.0 += got;
            b.1 += want;
        }
    }
    assert!(pixels >= 200, "{pixels} pixels see only the receiver");
    // About 1.5 % of the light paths aimed at the mirror land on the receiver (its solid angle
    // seen from the emitter's image, 0.014 sr, over the cone the mirror's bounding sphere
    // subtends, 0.95 sr): some 60,000 splats of 2^22 paths, so the sum over the receiver has a
    // relative standard error near 0.4 %, and a 4 x 4 block of pixels (a 25th of them) near
    // 2.5 %. Bounds: five standard errors.
    for c in 0..3 {
        let ratio = measured[c] / expected[c];
        assert!(
            (ratio - 1.0).abs() < 0.02,
            "channel {c}: light traced {} vs exact {} (ratio {ratio})",
            measured[c],
            expected[c]
        );
    }
    for (block, (got, want)) in &blocks {
        let ratio = got.element_sum() / want.element_sum();
        worst_block = worst_block.max((ratio - 1.0).abs());
        assert!(
            (ratio - 1.0).abs() < 0.12,
            "block {block:?}: light traced {got} vs exact {want}"
        );
    }
    eprintln!(
        "mirror caustic: {pixels} pixels, ratio {:.4} {:.4} {:.4}, worst 4x4 block off by {:.3}",
        measured.x / expected.x,
        measured.y / expected.y,
        measured.z / expected.z,
        worst_block
    );
}

/// Mean over a rectangle given in fractions of the image.
fn region(img: &twopass_image::Image, x: (f32, f32), y: (f32, f32)) -> f64 {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let (mut sum, mut n) = (0.0, 0.0);
    for py in (y.0 * h) as u32..(y.1 * h) as u32 {
        for px in (x.0 * w) as u32..(x.1 * w) as u32 {
            sum += img.get(px, py).as_dvec3().element_sum();
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn both_strategies_of_the_reference_agree_on_the_spheres() {
    let s = repo_scene("cornell-spheres.toml");
    let size = 24;
    let light = render_reference(&s, size, 256, 11, Caustics::LightTracing);
    let path = render_reference(&s, size, 4096, 12, Caustics::PathTracing);
    let (a, b) = (light.layers.composite(), path.layers.composite());
    // The whole image and its four quadrants: the same integral by two estimators with no
    // sample in common. The path tracer's own noise on the caustics bounds the agreement.
    let halves = [(0.0, 0.5), (0.5, 1.0)];
    let mut report = Vec::new();
    for (name, x, y, tolerance) in [("image", (0.0, 1.0), (0.0, 1.0), 0.01)].into_iter().chain(
        halves
            .iter()
            .flat_map(|&x| halves.iter().map(move |&y| ("quadrant", x, y, 0.03))),
    ) {
        let ratio = region(&a, x, y) / region(&b, x, y);
        report.push(format!("{name} {x:?} {y:?}: {ratio:.4}"));
        assert!(
            (ratio - 1.0).abs() < tolerance,
            "{name} {x:?} {y:?}: light tracing / path tracing = {ratio}"
        );
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn light_tracing_gives_the_same_image_on_one_and_two_threads() {
    let s = repo_scene("cornell-spheres.toml");
    // 24 x 24 x 480 light paths: more than one batch of parallel jobs.
    let on = |threads| {
        on_threads(threads, || {
            render_reference(&s, 24, 480, 5, Caustics::LightTracing)
        })
    };
    let (one, two) = (on(1), on(2));
    assert!(one.stats.light_paths > 4096 * 64);
    assert_eq!(one.layers, two.layers);
    assert_eq!(one.stats.shadow_rays, two.stats.shadow_rays);
}

/// A render of the default reference with light paths `light_paths`, 24 x 24 pixels, 64 spp.
fn render_planned(scene: &Scene, light_paths: LightPaths) -> RenderOutput {
    let settings = ReferenceSettings {
        light_paths,
        ..ReferenceSettings::default()
    };
    render_with(scene, settings, 24, 64, 9)
}

/// The pilot gives the light tracing pass light paths where the image's noise is: on the
/// mirror scene, whose receiver only light through the mirror reaches (the camera pass finds
/// none of it, so all of the noise is the light pass's), more than one per camera sample; on
/// the Cornell spheres, whose path-traced light is everything but the caustics of the two
/// spheres, fewer than one.
#[test]
fn the_plan_gives_light_paths_where_the_noise_is() {
    let pick = |s: &Scene| {
        let out = render_planned(s, LightPaths::Planned);
        let plan = out.stats.light_plan.expect("planned");
        let (lo, hi) = twopass_trace::light_plan::PLANNED_RANGE;
        assert!((lo..=hi).contains(&plan.paths_per_sample), "{plan:?}");
        assert!(plan.camera_cost > 0.0 && plan.light_cost > 0.0, "{plan:?}");
        plan.paths_per_sample
    };
    let mirror = pick(&mirror_scene());
    let spheres = pick(&repo_scene("cornell-spheres.toml"));
    eprintln!("light paths per camera sample: mirror {mirror}, spheres {spheres}");
    assert!(mirror > 1.0, "mirror scene: {mirror}");
    assert!(spheres < 1.0, "spheres: {spheres}");
}

/// A planned render is exactly the render with a fixed number of light paths per camera
/// sample, the plan's pick: the pilot's samples and paths are its own, not the image's, so the
/// estimate is the fixed-ratio one, unbiased as the strategies' agreement above shows.
#[test]
fn a_planned_render_is_the_fixed_ratio_render_of_its_pick() {
    let s = repo_scene("cornell-spheres.toml");
    let planned = render_planned(&s, LightPaths::Planned);
    let r = planned.stats.light_plan.expect("planned").paths_per_sample;
    let fixed = render_planned(&s, LightPaths::PerSample(r));
    assert!(fixed.stats.light_plan.is_none());
    assert_eq!(planned.stats.light_paths, fixed.stats.light_paths);
    assert_eq!(planned.layers, fixed.layers);
}

/// The plans (light paths and continuations) stay numbers in their ranges, and the image
/// finite, for emitters from 1e-6 to 1e6
/// times the Cornell spheres' (the metric's offset makes the weights absolute for a dim scene
/// and relative for a bright one; neither may overflow or divide by zero).
#[test]
fn the_plan_holds_for_emitters_from_1e_minus_6_to_1e6() {
    let text = std::fs::read_to_string(crate::scene_path("cornell-spheres.toml")).unwrap();
    assert!(text.contains("emission = [17, 12, 4]"));
    for scale in [1e-6, 1.0, 1e6] {
        let scaled = text.replace(
            "emission = [17, 12, 4]",
            &format!(
                "emission = [{}, {}, {}]",
                17.0 * scale,
                12.0 * scale,
                4.0 * scale
            ),
        );
        let out = render_planned(&scene(&scaled), LightPaths::Planned);
        let plan = out.stats.light_plan.expect("planned");
        let (lo, hi) = twopass_trace::light_plan::PLANNED_RANGE;
        assert!(
            (lo..=hi).contains(&plan.paths_per_sample),
            "{scale}: {plan:?}"
        );
        assert!(
            plan.camera_variance.is_finite() && plan.light_variance.is_finite(),
            "{scale}: {plan:?}"
        );
        // The split plan's pilot weighs its errors by the same metric.
        let split = out.stats.split_plan.expect("planned");
        assert!(
            split.prefix_variance.is_finite() && split.continuation_variance.is_finite(),
            "{scale}: {split:?}"
        );
        assert!(
            (1..=twopass_trace::split_plan::MAX_SPLITS).contains(&split.splits),
            "{scale}: {split:?}"
        );
        assert_eq!(out.stats.non_finite, 0, "{scale}");
        let image = out.layers.composite();
        assert!(image.pixels().iter().all(|p| p.is_finite()), "{scale}");
        assert!(image.mean().max_element() > 0.0, "{scale}");
    }
}
