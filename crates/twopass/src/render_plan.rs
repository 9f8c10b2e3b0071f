//! The render planner (`render --target-error`, `render --time-budget`): how many samples per
//! pixel reach a noise target or fit a time, and, when `--method` is left to it, whether the
//! hybrid or the path tracer gets there first, measured on the scene itself.
//!
//! Each candidate method renders a **pilot** twice: the image at [`PILOT_SPP`] samples per
//! pixel, with independent seeds. The two pilots' difference gives the method's noise, the
//! relative RMSE of one image against the truth ([`pilot_noise`]: the difference of two
//! independent estimates has twice one's variance); their time gives its seconds per sample per
//! pixel. The noise at `n` samples per pixel is then `sigma_pilot sqrt(PILOT_SPP / n)` (so for
//! stratified anti-aliasing, whose error falls faster, the samples planned err on the side of
//! more) and the time `n` times the seconds per sample per pixel:
//!
//! - `--target-error E`: the fewest samples with `sigma sqrt(PILOT_SPP / n) <= E`;
//! - `--time-budget S`: the most samples whose predicted time fits what is left of `S` after
//!   the solve and the pilots;
//! - both: the target's samples, cut to the budget's.
//!
//! A candidate's time counts what it needs before its first sample: the hybrid's solve. The
//! planner picks the candidate that reaches the target in the least time (or, under a budget
//! alone, the least noise) and says why. What it measures is the image's noise, not its bias:
//! the radiosity methods also carry the solution's discretization, which no pilot sees (`bench
//! tradeoff` and `bench bakes` measure it against a converged reference).

use std::time::Instant;

use serde::Serialize;
use twopass_composite::metric::REL_EPSILON;
use twopass_image::Image;
use twopass_scene::{Camera, Scene};
use twopass_trace::{Integrator, RenderProgress};

use crate::error::CliError;
use crate::pipeline::{RenderMethod, check_dropped};
use crate::preset::RenderKnobs;

/// Samples per pixel of each of a candidate's two pilot renders, at the image's size: the
/// planner costs each candidate four samples per pixel.
pub const PILOT_SPP: u32 = 2;
/// Most samples per pixel the planner asks for (the `--spp` limit).
pub const MAX_PLANNED_SPP: u32 = 1_000_000;

/// What the plan aims at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Goal {
    /// Relative RMSE of the image's noise to reach (`--target-error`), unitless.
    pub target_error: Option<f64>,
    /// Seconds the whole render may take, from the process's start (`--time-budget`).
    pub time_budget: Option<f64>,
}

/// One method the planner measured.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// The method.
    pub method: RenderMethod,
    /// Seconds it needed before its first sample (the solve), already spent.
    pub setup_seconds: f64,
    /// Seconds one sample per pixel of the whole image takes, from the pilots.
    pub seconds_per_spp: f64,
    /// The image's noise at one sample per pixel (relative RMSE), from the pilots.
    pub noise_at_one_spp: f64,
    /// The samples per pixel planned for it.
    pub spp: u32,
    /// Its predicted noise at `spp` (relative RMSE).
    pub predicted_noise: f64,
    /// Its predicted seconds: setup plus `spp` samples.
    pub predicted_seconds: f64,
}

/// The plan: the candidates measured, the one chosen and why.
#[derive(Debug, Clone, Serialize)]
pub struct RenderPlan {
    /// What was asked for.
    pub goal: Goal,
    /// Every candidate, in the order measured.
    pub candidates: Vec<Candidate>,
    /// Index of the chosen candidate.
    pub chosen: usize,
    /// Seconds the pilots took.
    pub pilot_seconds: f64,
    /// Why, for the user.
    pub reason: String,
}

impl RenderPlan {
    /// The chosen candidate.
    pub fn choice(&self) -> &Candidate {
        &self.candidates[self.chosen]
    }
}

/// The samples per pixel `goal` asks of a method whose image has noise `noise_at_one_spp` at
/// one sample per pixel and takes `seconds_per_spp` per sample per pixel, with `seconds_left`
/// of a budget (`None`: no budget). At least 1, at most [`MAX_PLANNED_SPP`].
pub fn planned_spp(
    goal: &Goal,
    noise_at_one_spp: f64,
    seconds_per_spp: f64,
    seconds_left: Option<f64>,
) -> u32 {
    let clamp = |n: f64| {
        if n.is_nan() {
            1
        } else {
            n.clamp(1.0, f64::from(MAX_PLANNED_SPP)) as u32
        }
    };
    let by_error = goal
        .target_error
        .map(|e| clamp((noise_at_one_spp / e).powi(2).ceil()));
    let by_time = seconds_left.map(|s| clamp((s / seconds_per_spp.max(1e-12)).floor()));
    match (by_error, by_time) {
        (Some(e), Some(t)) => e.min(t),
        (Some(e), None) => e,
        (None, Some(t)) => t,
        (None, None) => 1,
    }
}

/// Which candidate a goal picks: with a target, the one predicted to reach it soonest among
/// those that reach it (all of them when none does: the least noise then); under a budget
/// alone, the least predicted noise. With the reason in words.
pub fn choose(goal: &Goal, candidates: &[Candidate]) -> (usize, String) {
    let by = |key: &dyn Fn(&Candidate) -> f64| {
        (0..candidates.len())
            .min_by(|&a, &b| key(&candidates[a]).total_cmp(&key(&candidates[b])))
            .unwrap_or(0)
    };
    let listed = candidates
        .iter()
        .map(|c| {
            format!(
                "{} {} spp: noise {:.2} % in {:.2} s",
                c.method.name(),
                c.spp,
                100.0 * c.predicted_noise,
                c.predicted_seconds
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let (chosen, why) = match goal.target_error {
        Some(e) => {
            let reach: Vec<usize> = (0..candidates.len())
                .filter(|&i| candidates[i].predicted_noise <= e * (1.0 + 1e-9))
                .collect();
            if reach.is_empty() {
                (
                    by(&|c| c.predicted_noise),
                    format!(
                        "no method reaches {:.2} % in the time given: the least noise",
                        100.0 * e
                    ),
                )
            } else {
                let i = reach
                    .iter()
                    .copied()
                    .min_by(|&a, &b| {
                        candidates[a]
                            .predicted_seconds
                            .total_cmp(&candidates[b].predicted_seconds)
                    })
                    .unwrap_or(reach[0]);
                (i, format!("the soonest to {:.2} %", 100.0 * e))
            }
        }
        None => (
            by(&|c| c.predicted_noise),
            "the least noise in the time given".into(),
        ),
    };
    let reason = if candidates.len() > 1 {
        format!(
            "{} ({why}; predicted {listed})",
            candidates[chosen].method.name()
        )
    } else {
        format!("{listed} ({why})")
    };
    (chosen, reason)
}

/// Measures one candidate: two pilots of `integrator` (with `knobs`) at [`PILOT_SPP`] on the
/// image's own camera (a smaller one would overweight the pixels on edges, whose share of the
/// image grows as it shrinks). Returns (seconds per sample per pixel, noise at one sample per
/// pixel).
pub fn pilot(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    knobs: &RenderKnobs,
    seed: u64,
    ctx: &crate::context::Context,
) -> Result<(f64, f64), CliError> {
    let pilot_knobs = RenderKnobs {
        spp: PILOT_SPP,
        adaptive: None,
        ..*knobs
    };
    let mut images = Vec::new();
    let started = Instant::now();
    for k in 0..2u64 {
        // Seeds apart from the final render's, whose image must not share their streams.
        let settings = pilot_knobs.settings(seed ^ (0x9117_0700_0000_0000 + k));
        let out =
            twopass_trace::render(scene, camera, integrator, &settings, &RenderProgress::new());
        check_dropped(&out.stats, &scene.path, ctx)?;
        images.push(out.layers.composite());
    }
    let seconds_per_spp = started.elapsed().as_secs_f64() / (2.0 * f64::from(PILOT_SPP));
    Ok((
        seconds_per_spp,
        pilot_noise(&images[0], &images[1]) * f64::from(PILOT_SPP).sqrt(),
    ))
}

/// The noise of one of two independent renders `a` and `b` of one image: the project's
/// relative RMSE, `sqrt(mean((x - r)^2 / (r^2 + 0.01)))` over pixels and channels, with the
/// pair's mean standing for the converged `r` (neither alone: a lone noisy image in the
/// denominator would weigh its own errors) and half the pair's squared difference for one's
/// squared error.
pub fn pilot_noise(a: &Image, b: &Image) -> f64 {
    let mut sum = 0.0f64;
    for (x, y) in a.pixels().iter().zip(b.pixels()) {
        for c in 0..3 {
            let (x, y) = (f64::from(x[c]), f64::from(y[c]));
            let m = 0.5 * (x + y);
            sum += (x - y) * (x - y) / 2.0 / (m * m + REL_EPSILON);
        }
    }
    (sum / (3.0 * a.pixels().len().max(1) as f64)).sqrt()
}

/// Plans a render toward `goal`: pilots every candidate (method, its integrator, the seconds
/// it spent before its first sample), plans each one's samples, and chooses. `started` is when
/// the process began (the budget counts from it).
#[allow(clippy::too_many_arguments)]
pub fn plan(
    scene: &Scene,
    camera: &Camera,
    candidates: &[(RenderMethod, &dyn Integrator, f64)],
    knobs: &RenderKnobs,
    goal: Goal,
    seed: u64,
    started: Instant,
    ctx: &crate::context::Context,
) -> Result<RenderPlan, CliError> {
    let pilots_started = Instant::now();
    let mut measured = Vec::new();
    for &(method, integrator, setup) in candidates {
        let (per_spp, noise) = pilot(scene, camera, integrator, knobs, seed, ctx)?;
        measured.push((method, setup, per_spp, noise));
    }
    let pilot_seconds = pilots_started.elapsed().as_secs_f64();
    let left = goal
        .time_budget
        .map(|b| (b - started.elapsed().as_secs_f64()).max(0.0));
    let candidates: Vec<Candidate> = measured
        .into_iter()
        .map(
            |(method, setup_seconds, seconds_per_spp, noise_at_one_spp)| {
                let spp = planned_spp(&goal, noise_at_one_spp, seconds_per_spp, left);
                Candidate {
                    method,
                    setup_seconds,
                    seconds_per_spp,
                    noise_at_one_spp,
                    spp,
                    predicted_noise: noise_at_one_spp / f64::from(spp).sqrt(),
                    predicted_seconds: setup_seconds + f64::from(spp) * seconds_per_spp,
                }
            },
        )
        .collect();
    let (chosen, reason) = choose(&goal, &candidates);
    Ok(RenderPlan {
        goal,
        candidates,
        chosen,
        pilot_seconds,
        reason,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn goal(target_error: Option<f64>, time_budget: Option<f64>) -> Goal {
        Goal {
            target_error,
            time_budget,
        }
    }

    fn candidate(
        method: RenderMethod,
        setup: f64,
        per_spp: f64,
        noise1: f64,
        g: &Goal,
    ) -> Candidate {
        let spp = planned_spp(g, noise1, per_spp, g.time_budget.map(|b| b - setup));
        Candidate {
            method,
            setup_seconds: setup,
            seconds_per_spp: per_spp,
            noise_at_one_spp: noise1,
            spp,
            predicted_noise: noise1 / f64::from(spp).sqrt(),
            predicted_seconds: setup + f64::from(spp) * per_spp,
        }
    }

    /// Two images whose pixels are m + d and m - d: the unbiased variance of two samples is
    /// ((m + d - m)^2 + (m - d - m)^2) / (2 - 1) = 2 d^2, so one image's noise is
    /// sqrt(2) d / sqrt(m^2 + 0.01).
    #[test]
    fn pilot_noise_is_one_image_against_the_pair_mean() {
        // Exact in f32, so the images hold exactly these values.
        let (m, d) = (0.25f32, 0.03125f32);
        let a = Image::filled(4, 4, twopass_brdf::Rgb::splat(m + d));
        let b = Image::filled(4, 4, twopass_brdf::Rgb::splat(m - d));
        let want = 2f64.sqrt() * f64::from(d) / (f64::from(m) * f64::from(m) + 0.01).sqrt();
        assert!((pilot_noise(&a, &b) - want).abs() < 1e-6 * want);
        assert_eq!(pilot_noise(&a, &a), 0.0);
    }

    #[test]
    fn samples_follow_the_inverse_square_of_the_target_and_the_budget() {
        // 0.4 at one sample: 0.02 needs (0.4 / 0.02)^2 = 400 samples.
        assert_eq!(planned_spp(&goal(Some(0.02), None), 0.4, 0.01, None), 400);
        // 3 s at 0.01 s a sample: 300 samples; both: the fewer.
        assert_eq!(
            planned_spp(&goal(None, Some(3.0)), 0.4, 0.01, Some(3.0)),
            300
        );
        assert_eq!(
            planned_spp(&goal(Some(0.02), Some(3.0)), 0.4, 0.01, Some(3.0)),
            300
        );
        // Never below one, never above the limit, never from a NaN.
        assert_eq!(planned_spp(&goal(None, Some(0.0)), 0.4, 0.01, Some(0.0)), 1);
        assert_eq!(
            planned_spp(&goal(Some(1e-9), None), 0.4, 0.01, None),
            MAX_PLANNED_SPP
        );
        assert_eq!(
            planned_spp(&goal(Some(0.02), None), f64::NAN, 0.01, None),
            1
        );
    }

    #[test]
    fn the_soonest_candidate_to_the_target_is_chosen_and_the_reason_says_so() {
        let g = goal(Some(0.02), None);
        // A hybrid with a 2 s solve and little noise against a path tracer without setup:
        // 2 + 16 * 0.05 = 2.8 s against 2500 * 0.01 = 25 s.
        let hybrid = candidate(RenderMethod::Hybrid, 2.0, 0.05, 0.08, &g);
        let path = candidate(RenderMethod::Reference, 0.0, 0.01, 1.0, &g);
        assert_eq!((hybrid.spp, path.spp), (16, 2500));
        let (i, why) = choose(&g, &[hybrid.clone(), path.clone()]);
        assert_eq!(i, 0, "{why}");
        assert!(why.starts_with("hybrid (the soonest to 2.00 %"), "{why}");
        // A solve of 60 s makes the path tracer sooner.
        let slow = candidate(RenderMethod::Hybrid, 60.0, 0.05, 0.08, &g);
        let (i, why) = choose(&g, &[slow, path]);
        assert_eq!(i, 1, "{why}");
        assert!(why.starts_with("reference"), "{why}");
    }

    #[test]
    fn under_a_budget_alone_the_least_noise_is_chosen() {
        let g = goal(None, Some(10.0));
        // 8 s left after the hybrid's solve: 160 samples, noise 0.08 / sqrt(160) = 0.0063;
        // the path tracer 1000 samples, 1 / sqrt(1000) = 0.032.
        let hybrid = candidate(RenderMethod::Hybrid, 2.0, 0.05, 0.08, &g);
        let path = candidate(RenderMethod::Reference, 0.0, 0.01, 1.0, &g);
        assert_eq!((hybrid.spp, path.spp), (160, 1000));
        assert_eq!(choose(&g, &[hybrid, path]).0, 0);
    }
}
