//! Samples where the noise is: a `render` that names no `--spp` (and no `--adaptive`, preset,
//! part or planner goal) spends its default samples per pixel as a mean, pixel by pixel in
//! proportion to the noise measured there.
//!
//! Two pilot renders of [`pilot_spp`] samples per pixel each, the first two runs of every
//! pixel's sample sequence, give every pixel's noise ([`SampleBudget::from_pilots`]: the
//! pilots' squared difference, weighted as the relative error weighs it, smoothed over 5 x 5
//! pixels); the samples left after the pilots go to the pixels in proportion to its standard
//! deviation, which for a fixed total minimises the summed variance. The budgeted render
//! continues each pixel's sequence ([`SampleBudget::continuing`]), so the sample-weighted mean
//! of the three renders is exactly one render of the pixel's samples, stratified together: no
//! sample is wasted, and the gather and shadow rays, stratified over a pixel's samples, keep
//! the convergence they have in one render (independent pilots would lose it: on the grazing
//! room that costs more than the allocation gains). Keeping the pilots' samples in a pixel
//! whose count they helped decide is not strictly unbiased (Kirk and Arvo 1991): a pixel whose
//! pilots happened to disagree gets more samples that dilute them. The count follows the noise
//! of the pixel's 5 x 5 neighbourhood, 25 pixels' pilots, so one pixel's own samples weigh
//! little in it; the image means of the scenes measured agree with uniform renders within
//! their noise (docs/benchmarks.md, "The gathered hybrid").
//!
//! What it pays for: the camera's own noise concentrates where a few samples decide a pixel
//! (a small bright emitter seen in a chrome ball, an edge, a thin mirror), and those pixels get
//! several times the mean while smooth ones get less. Where the noise is even (a diffuse box)
//! it changes little. A render split into parts (`--part`) takes the same samples in every
//! pixel: a pixel's share would depend on the pilots of the whole image.

use serde::Serialize;
use twopass_scene::{Camera, Scene};
use twopass_trace::{Integrator, RenderOutput, RenderSettings, RenderStats, SampleBudget};

use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{render_budgeted_with_bar, render_with_bar};

/// The pilots take one sample per pixel each per this many of the mean.
pub const PILOT_SHARE: u32 = 16;

/// How a render's samples were spread over its pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Allocation {
    /// Samples per pixel of each of the two pilots (their samples count in the image).
    pub pilot_spp: u32,
    /// Fewest samples any pixel got, pilots included.
    pub min_spp: u32,
    /// Most samples any pixel got, pilots included.
    pub max_spp: u32,
}

/// Samples per pixel of each pilot for a mean of `spp`, or `None` when `spp` is too few to
/// share out (fewer than [`PILOT_SHARE`]).
pub fn pilot_spp(spp: u32) -> Option<u32> {
    let p = spp / PILOT_SHARE;
    (p >= 1).then_some(p)
}

/// Renders with `settings.samples_per_pixel` samples per pixel: with `by_noise` on average,
/// spread by the noise the pilots measure (see the module documentation), and otherwise, or
/// when there are too few to share out, the same in every pixel (`None` then). The statistics
/// of a spread render are its three runs' summed, with the mean samples per pixel.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    by_noise: bool,
    label: &str,
    ctx: &Context,
) -> Result<(RenderOutput, Option<Allocation>), CliError> {
    let spp = settings.samples_per_pixel;
    let Some(p) = pilot_spp(spp).filter(|_| by_noise) else {
        let out = render_with_bar(scene, camera, integrator, settings, label, ctx)?;
        return Ok((out, None));
    };
    // The pilots are the first 2p samples of every pixel's sequence, in two runs of p; the
    // budgeted render continues the sequence, so each pixel is one stratified sequence. Only
    // their sum and their two composites are kept, so the allocation adds a film and a half
    // to the render's memory.
    let mut composites = Vec::with_capacity(2);
    let mut pilots: Option<RenderOutput> = None;
    for k in 0..2 {
        let run = SampleBudget::uniform(camera.width, camera.height, p).continuing(k * p);
        let out = render_budgeted_with_bar(
            scene,
            camera,
            integrator,
            settings,
            &run,
            &format!("{label} (pilot {})", k + 1),
            ctx,
        )?;
        composites.push(out.layers.composite());
        pilots = Some(match pilots {
            None => out,
            Some(sum) => add(sum, &out),
        });
    }
    let budget = SampleBudget::from_pilots(&composites[0], &composites[1], spp - 2 * p)
        .ok_or_else(|| {
            CliError::Input(format!(
                "{}: the pilot renders are empty ({} x {} pixels)",
                scene.path.display(),
                camera.width,
                camera.height
            ))
        })?
        .continuing(2 * p);
    drop(composites);
    let main = render_budgeted_with_bar(scene, camera, integrator, settings, &budget, label, ctx)?;
    let (lo, hi) = budget.range();
    let allocation = Allocation {
        pilot_spp: p,
        min_spp: lo.saturating_add(2 * p),
        max_spp: hi.saturating_add(2 * p),
    };
    let pilots = pilots.expect("two pilots were rendered");
    Ok((combine(&pilots, main, &budget, p, spp), Some(allocation)))
}

/// `sum` with `out`'s layers added pixel by pixel and its statistics summed.
fn add(mut sum: RenderOutput, out: &RenderOutput) -> RenderOutput {
    for (s, o) in sum.layers.images.iter_mut().zip(&out.layers.images) {
        for (a, b) in s.pixels_mut().iter_mut().zip(o.pixels()) {
            *a += *b;
        }
    }
    add_stats(&mut sum.stats, &out.stats);
    sum
}

/// The counts and times of `s` added to `t`.
fn add_stats(t: &mut RenderStats, s: &RenderStats) {
    t.samples += s.samples;
    t.non_finite += s.non_finite;
    t.rays += s.rays;
    t.shadow_rays += s.shadow_rays;
    t.light_paths += s.light_paths;
    // A render's own plan over its pilots' (which plan for their fewer samples).
    t.light_plan = t.light_plan.or(s.light_plan);
    t.split_plan = t.split_plan.or(s.split_plan);
    t.elapsed += s.elapsed;
}

/// Each pixel of every layer of `main` as the sample-weighted mean of the two pilots' (`pilots`
/// holds their sum, `p` samples each) and the budgeted render's (`budget`'s samples there);
/// statistics summed, with `spp` the mean samples per pixel.
fn combine(
    pilots: &RenderOutput,
    mut main: RenderOutput,
    budget: &SampleBudget,
    p: u32,
    spp: u32,
) -> RenderOutput {
    let width = main.layers.width();
    let p = p as f32;
    for (m, a) in main.layers.images.iter_mut().zip(&pilots.layers.images) {
        for (i, (m, a)) in m.pixels_mut().iter_mut().zip(a.pixels()).enumerate() {
            let n = budget.samples(i as u32 % width, i as u32 / width) as f32;
            *m = (*a * p + *m * n) / (2.0 * p + n);
        }
    }
    add_stats(&mut main.stats, &pilots.stats);
    main.stats.samples_per_pixel = spp;
    main
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use twopass_brdf::Rgb;
    use twopass_trace::LayerImages;

    /// An 8 x 1 render whose every layer holds `value` times its index + 1 in every pixel,
    /// `samples` taken.
    fn output(value: f32, samples: u64) -> RenderOutput {
        let mut layers = LayerImages::new(8, 1);
        for (l, img) in layers.images.iter_mut().enumerate() {
            img.pixels_mut().fill(Rgb::splat(value * (l + 1) as f32));
        }
        RenderOutput {
            layers,
            stats: RenderStats {
                method: "test",
                width: 8,
                height: 1,
                samples_per_pixel: 1,
                samples,
                refined_pixels: 0,
                non_finite: 1,
                rays: samples,
                shadow_rays: 2 * samples,
                light_paths: 0,
                light_plan: None,
                splits: 1,
                split_plan: None,
                elapsed: Duration::from_millis(samples),
            },
        }
    }

    #[test]
    fn a_pixel_is_the_sample_weighted_mean_of_its_three_estimates() {
        // Pilots of 2 samples each reading 1 and 3, the budgeted render 5 with the budget's n
        // samples in the pixel: (2 * 1 + 2 * 3 + n * 5) / (4 + n), in every layer scaled by
        // its index + 1. The budget gives the pixel whose pilots differ more samples.
        // Pilots that differ in the first pixel alone: after smoothing over 5 x 5 pixels the
        // first three pixels are noisy, the last three not.
        let image = |first: f32| {
            let mut pixels = vec![Rgb::ZERO; 8];
            pixels[0] = Rgb::splat(first);
            twopass_image::Image::from_pixels(8, 1, pixels).unwrap()
        };
        let budget = SampleBudget::from_pilots(&image(0.0), &image(1.0), 8).unwrap();
        let (lo, hi) = (budget.samples(7, 0), budget.samples(0, 0));
        assert!(lo < hi, "the noisier pixel gets more: {lo} {hi}");
        let pilots = add(output(1.0, 4), &output(3.0, 4));
        let out = combine(&pilots, output(5.0, 16), &budget, 2, 12);
        for (l, img) in out.layers.images.iter().enumerate() {
            let k = (l + 1) as f32;
            for (x, n) in [(7, lo), (0, hi)] {
                let n = n as f32;
                let want = k * (2.0 + 6.0 + 5.0 * n) / (4.0 + n);
                let got = img.pixels()[x].x;
                assert!(
                    (got - want).abs() <= 1e-5 * want,
                    "layer {l} pixel {x}: {got} vs {want}"
                );
            }
        }
        let s = out.stats;
        assert_eq!(
            (s.samples, s.rays, s.shadow_rays, s.non_finite),
            (24, 24, 48, 3)
        );
        assert_eq!(s.elapsed, Duration::from_millis(24));
        assert_eq!(s.samples_per_pixel, 12);
    }

    #[test]
    fn the_pilots_take_a_sixteenth_and_too_few_samples_stay_uniform() {
        assert_eq!(pilot_spp(64), Some(4));
        assert_eq!(pilot_spp(16), Some(1));
        assert_eq!(pilot_spp(15), None);
        assert_eq!(pilot_spp(1), None);
    }
}
