//! Per-pixel sample budgets (`SampleBudget`, `render_budgeted`), with which the converged
//! reference spends its samples where its noise is: a pixel given n samples gets exactly the
//! estimate a uniform render of n samples per pixel gives it (so each pixel stays unbiased),
//! the budget follows the pilots' disagreement with the floor it promises, and the image is the
//! same on any thread count, light tracing included.

use twopass_image::Image;
use twopass_trace::{
    BUDGET_FLOOR, Integrator, Reference, ReferenceSettings, RenderProgress, RenderSettings,
    SampleBudget, render, render_budgeted,
};

use super::common::repo_scene;
use crate::on_threads;

/// `render_budgeted` with a fresh progress; `None` for a budget of another size than the
/// camera's.
fn budgeted(
    scene: &twopass_scene::Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: &SampleBudget,
) -> Option<twopass_trace::RenderOutput> {
    render_budgeted(
        scene,
        camera,
        integrator,
        settings,
        budget,
        &RenderProgress::new(),
    )
}

#[test]
fn a_pixel_given_n_samples_gets_the_uniform_estimate_at_n() {
    // The diffuse box: no delta surface, so no light tracing pass adds to the camera samples.
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(12), Some(12));
    let reference = Reference::new(&scene, ReferenceSettings::default());
    let settings = |spp| RenderSettings {
        samples_per_pixel: spp,
        seed: 21,
        ..RenderSettings::default()
    };
    let counts = [1u32, 2, 3, 4, 9];
    // A budget that cycles through the counts pixel by pixel, built as the pilots' would be
    // and then checked cell by cell against uniform renders at each count.
    let uniform: Vec<_> = counts
        .iter()
        .map(|&n| {
            render(
                &scene,
                &camera,
                &reference,
                &settings(n),
                &RenderProgress::new(),
            )
        })
        .collect();
    let pattern = |x: u32, y: u32| (x + 3 * y) as usize % counts.len();
    let a = Image::from_fn(
        12,
        12,
        |x, y| twopass_brdf::Rgb::splat(pattern(x, y) as f32),
    );
    let zero = Image::from_fn(12, 12, |_, _| twopass_brdf::Rgb::ZERO);
    // Any budget will do for the identity; the pattern one comes from the pilots' API.
    let budget = SampleBudget::from_pilots(&a, &zero, 4).unwrap();
    let out = budgeted(&scene, &camera, &reference, &settings(4), &budget)
        .expect("the budget has the camera's size");
    assert_eq!(out.stats.samples, budget.total());
    let image = out.layers.composite();
    let mut checked = 0;
    let mut seen = std::collections::BTreeSet::new();
    for y in 0..12 {
        for x in 0..12 {
            let n = budget.samples(x, y);
            if let Some(k) = counts.iter().position(|&c| c == n) {
                let want = uniform[k].layers.composite().get(x, y);
                assert_eq!(image.get(x, y), want, "pixel ({x}, {y}) with {n} samples");
                checked += 1;
                seen.insert(n);
            }
        }
    }
    assert!(
        checked >= 24,
        "only {checked} pixels had a count with a uniform render"
    );
    // A budget of another size is refused, not rendered.
    let small = SampleBudget::uniform(6, 6, 4);
    assert!(budgeted(&scene, &camera, &reference, &settings(4), &small).is_none());
}

#[test]
fn the_budget_follows_the_pilots_noise_with_its_floor() {
    let (w, h) = (40u32, 30u32);
    let grey = |_: u32, _: u32| twopass_brdf::Rgb::splat(0.5);
    let a = Image::from_fn(w, h, grey);
    // The pilots disagree in one 4 x 4 block only.
    let in_block = |x: u32, y: u32| (10..14).contains(&x) && (8..12).contains(&y);
    let b = Image::from_fn(w, h, |x, y| {
        twopass_brdf::Rgb::splat(if in_block(x, y) { 1.5 } else { 0.5 })
    });
    let spp = 64;
    let budget = SampleBudget::from_pilots(&a, &b, spp).unwrap();
    let pixels = u64::from(w * h);
    // The total is the mean's, up to the rounding of each pixel.
    let total = budget.total() as f64;
    assert!(
        (total - (spp as f64) * pixels as f64).abs() <= 0.5 * pixels as f64,
        "total {total}"
    );
    // Far from the block (beyond the 5 x 5 window) every pixel has the floor's weight: the
    // same count, below the mean, at least one sample.
    let far = budget.samples(35, 25);
    assert!(far >= 1 && far < spp, "far pixel {far}");
    for (x, y) in [(0, 0), (39, 29), (30, 5), (2, 28)] {
        assert_eq!(budget.samples(x, y), far);
    }
    // The spec's numbers: a block pixel's weighted squared difference is 3 x 1^2 / (1^2 + 0.01)
    // (a - b = 1, mean 1, three channels); sigma is the root of its mean over the 5 x 5
    // window clipped to the image; the far pixels' weight is the floor, BUDGET_FLOOR times the
    // mean sigma; counts are proportional to the weights.
    let v = 3.0 / 1.01;
    let sigma = |x: i64, y: i64| {
        let (mut sum, mut n) = (0.0, 0.0);
        for yy in (y - 2).max(0)..(y + 3).min(i64::from(h)) {
            for xx in (x - 2).max(0)..(x + 3).min(i64::from(w)) {
                sum += if in_block(xx as u32, yy as u32) {
                    v
                } else {
                    0.0
                };
                n += 1.0;
            }
        }
        f64::sqrt(sum / n)
    };
    let mean_sigma = (0..i64::from(h))
        .flat_map(|y| (0..i64::from(w)).map(move |x| (x, y)))
        .map(|(x, y)| sigma(x, y))
        .sum::<f64>()
        / pixels as f64;
    let floor = BUDGET_FLOOR * mean_sigma;
    let want_ratio = sigma(11, 9) / floor;
    let got_ratio = f64::from(budget.samples(11, 9)) / f64::from(far);
    // Both counts are rounded: the ratio is right to one sample in `far`.
    assert!(
        (got_ratio - want_ratio).abs() <= want_ratio / f64::from(far),
        "block centre / far: {got_ratio}, spec {want_ratio}"
    );
    assert!(want_ratio > 4.0, "the block must stand out: {want_ratio}");
    let (lo, _) = budget.range();
    assert_eq!(lo, far, "the floor is the fewest samples");
    // Pilots that agree everywhere: the uniform budget.
    let same = SampleBudget::from_pilots(&a, &a, spp).unwrap();
    assert_eq!(same, SampleBudget::uniform(w, h, spp));
    // Pilots of different sizes: no budget.
    let other = Image::from_fn(w, h + 1, grey);
    assert!(SampleBudget::from_pilots(&a, &other, spp).is_none());
}

#[test]
fn a_budgeted_render_with_light_tracing_is_the_same_on_one_and_two_threads() {
    let scene = repo_scene("cornell-spheres.toml");
    let camera = scene.camera.with_resolution(Some(20), Some(20));
    let reference = Reference::new(&scene, ReferenceSettings::default());
    assert!(
        reference.light_tracer().is_some(),
        "the spheres need light tracing"
    );
    let settings = RenderSettings {
        samples_per_pixel: 8,
        seed: 3,
        ..RenderSettings::default()
    };
    let pilot = |seed| {
        let s = RenderSettings { seed, ..settings };
        render(&scene, &camera, &reference, &s, &RenderProgress::new())
            .layers
            .composite()
    };
    let budget = SampleBudget::from_pilots(&pilot(100), &pilot(101), 8).unwrap();
    let (lo, hi) = budget.range();
    assert!(hi > lo, "the spheres' pilots disagree unevenly: {lo}..{hi}");
    let on = |threads| {
        on_threads(threads, || {
            budgeted(&scene, &camera, &reference, &settings, &budget).unwrap()
        })
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one.layers, two.layers);
    assert_eq!(one.stats.samples, budget.total());
    // As many light paths per camera sample as the pilot planned, the same on both.
    let plan = one
        .stats
        .light_plan
        .expect("the reference plans its light paths");
    assert_eq!(two.stats.light_plan, Some(plan));
    let want = (f64::from(plan.paths_per_sample) * budget.total() as f64).ceil() as u64;
    assert_eq!(one.stats.light_paths, want);
}

#[test]
fn runs_that_continue_a_sequence_are_together_the_single_run_of_all_their_samples() {
    // Runs of 3 and then 5 samples per pixel (`continuing(0)`, `continuing(3)`) against one run
    // of 8 (`continuing(0)`): per pixel the sample-weighted mean of the runs is the single
    // run's mean, to f32 rounding of the sums, because the samples are the same ones. The
    // diffuse box: no light tracing pass, whose paths each run draws anew.
    let scene = repo_scene("cornell-box.toml");
    let camera = scene.camera.with_resolution(Some(10), Some(10));
    let reference = Reference::new(&scene, ReferenceSettings::default());
    let settings = RenderSettings {
        samples_per_pixel: 8,
        seed: 5,
        ..RenderSettings::default()
    };
    let run = |n: u32, first: u32| {
        let budget = SampleBudget::uniform(10, 10, n).continuing(first);
        assert_eq!(budget.first(), Some(first));
        budgeted(&scene, &camera, &reference, &settings, &budget)
            .unwrap()
            .layers
            .composite()
    };
    let (a, b, all) = (run(3, 0), run(5, 3), run(8, 0));
    for (i, ((a, b), all)) in a
        .pixels()
        .iter()
        .zip(b.pixels())
        .zip(all.pixels())
        .enumerate()
    {
        let mean = (*a * 3.0 + *b * 5.0) / 8.0;
        assert!(
            (mean - *all).abs().max_element() <= 1e-5 * all.max_element().max(1e-3),
            "pixel {i}: {mean} vs {all}"
        );
    }
    // A second run of the same samples is the same estimate; another run is not.
    assert_eq!(run(3, 0).pixels(), a.pixels());
    assert_ne!(run(3, 3).pixels(), a.pixels());
}
