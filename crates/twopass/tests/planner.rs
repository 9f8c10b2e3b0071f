//! `render --target-error` and `--time-budget`: the planner's samples reach the noise it
//! promises, it picks between the hybrid and the path tracer by what it measures and says so,
//! and bad targets are usage errors.

use std::path::Path;

use twopass_composite::write::read_exr;
use twopass_image::Image;

use crate::common::{assert_exit, cli, ok_json, render_box, repo};

/// The image of a render's (plain RGBA) EXR.
fn image(exr: &Path) -> Image {
    read_exr(exr).unwrap()
}

/// One image's noise from two independent renders, written from the metric's definition:
/// sqrt(mean over pixels and channels of (a - b)^2 / 2 / (m^2 + 0.01)), m the pair's mean.
fn noise(a: &Image, b: &Image) -> f64 {
    let mut sum = 0.0;
    let mut n = 0.0;
    for (x, y) in a.pixels().iter().zip(b.pixels()) {
        for c in 0..3 {
            let (x, y) = (f64::from(x[c]), f64::from(y[c]));
            let m = 0.5 * (x + y);
            sum += (x - y).powi(2) / 2.0 / (m * m + 0.01);
            n += 1.0;
        }
    }
    (sum / n).sqrt()
}

/// The planned render reaches its target: a second render of the chosen method at the planned
/// samples with another seed differs from the first by what two images of noise `target`
/// would (within the pilots' own noise and stratified anti-aliasing's faster convergence,
/// which make the plan err on the side of more samples).
#[test]
fn the_planned_samples_reach_the_noise_target() {
    let dir = tempfile::tempdir().unwrap();
    for (target, seed) in [(0.05, 1), (0.02, 2)] {
        let first = dir.path().join(format!("plan-{target}.exr"));
        let v = ok_json(
            &cli("render")
                .arg(repo("scenes/cornell-box.toml"))
                .words(&format!(
                    "--target-error {target} --width 96 --json --quiet --seed {seed}"
                ))
                .output(&first)
                .run(),
        );
        let plan = &v["plan"];
        let candidates = plan["candidates"].as_array().unwrap();
        let methods: Vec<&str> = candidates
            .iter()
            .map(|c| c["method"].as_str().unwrap())
            .collect();
        assert_eq!(methods, ["hybrid", "reference"], "{plan}");
        let chosen = &candidates[plan["chosen"].as_u64().unwrap() as usize];
        let (method, spp) = (v["method"].as_str().unwrap(), v["spp"].as_u64().unwrap());
        assert_eq!(chosen["method"], method);
        assert_eq!(chosen["spp"], spp);
        assert!(
            plan["reason"].as_str().unwrap().starts_with(method),
            "{plan}"
        );
        // The chosen one is the sooner of those predicted to reach the target.
        for c in candidates {
            if c["predicted_noise"].as_f64().unwrap() <= target {
                assert!(
                    chosen["predicted_seconds"].as_f64() <= c["predicted_seconds"].as_f64(),
                    "{plan}"
                );
            }
        }
        let second = dir.path().join(format!("again-{target}.exr"));
        ok_json(
            &render_box(method, 96, spp as u32)
                .words(&format!("--json --quiet --seed {}", seed + 100))
                .output(&second)
                .run(),
        );
        let got = noise(&image(&first), &image(&second));
        assert!(
            got <= 1.5 * target && got >= 0.3 * target,
            "{method} at {spp} spp: noise {got} for a target of {target}"
        );
    }
}

#[test]
fn bad_targets_are_usage_errors() {
    for words in [
        "--target-error 0",
        "--target-error 1",
        "--target-error nan",
        "--target-error 0.02 --spp 4",
        "--target-error 0.02 --preset final",
    ] {
        let out = cli("render")
            .arg(repo("scenes/cornell-box.toml"))
            .words(words)
            .words("--width 16 --quiet")
            .output(tempfile::tempdir().unwrap().path().join("x.exr"))
            .run();
        assert_exit(&out, 2);
    }
}

/// A time budget alone plans the samples that fit what the solve and the pilots leave: a
/// budget the solve already spends leaves one sample per pixel; with `--method` given, the
/// planner measures that method alone. With `--spp` given, the budget bounds the solve only.
#[test]
fn a_spent_time_budget_leaves_one_sample() {
    let dir = tempfile::tempdir().unwrap();
    let v = ok_json(
        &cli("render")
            .arg(repo("scenes/cornell-box.toml"))
            .words("--method hybrid --width 32 --time-budget 0.001 --json --quiet")
            .output(dir.path().join("b.exr"))
            .run(),
    );
    assert_eq!(v["spp"], 1, "{}", v["plan"]);
    assert_eq!(v["plan"]["candidates"].as_array().unwrap().len(), 1);
    let v = ok_json(
        &render_box("hybrid", 32, 3)
            .words("--time-budget 0.001 --json --quiet")
            .output(dir.path().join("c.exr"))
            .run(),
    );
    assert_eq!(v["spp"], 3);
    assert!(v.get("plan").is_none(), "{v}");
}
