//! `twopass bench tradeoff`: the front, the presets and the cache, checked from its own report.

use crate::common;

use crate::common::{cli, repo, twopass};

use std::path::Path;

use serde_json::Value;

fn sweep(out: &Path) -> Value {
    let scene = repo("scenes/cornell-box.toml");
    let o = cli("bench tradeoff")
        .arg(&scene)
        .words("--quick --width 32 --reference-spp 64 --targets 0.3,0.2,0.12 --json")
        .output(out)
        .run();
    common::ok_json(&o)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn front_presets_and_cache_agree_with_the_measured_rows() {
    let dir = tempfile::tempdir().unwrap();
    let first = sweep(dir.path());
    let rows = first["rows"].as_array().unwrap();

    // Every method the diffuse box calls for was measured (the classic hybrid is skipped, and
    // says why).
    for m in [
        "reference",
        "whitted",
        "radiosity",
        "hybrid",
        "hybrid-direct",
    ] {
        assert!(rows.iter().any(|r| r["method"] == m), "{m} missing");
    }
    assert!(rows.iter().all(|r| r["method"] != "hybrid-classic"));
    // Radiosity alone over a gathered element mesh, the bake's final gather, is a curve of its
    // own, with its rays per point.
    let gathered: Vec<&Value> = rows
        .iter()
        .filter(|r| r["method"] == "radiosity-gathered")
        .collect();
    assert!(!gathered.is_empty(), "no gathered solve was measured");
    assert!(
        gathered
            .iter()
            .all(|r| r["final_gather"].as_u64() == Some(2))
    );
    assert!(
        rows.iter()
            .filter(|r| r["method"] != "radiosity-gathered")
            .all(|r| r["final_gather"].is_null())
    );
    assert!(
        first["skipped"][0]
            .as_str()
            .unwrap()
            .starts_with("hybrid-classic")
    );

    // The front, recomputed from the definition: no other row is no slower and no less
    // accurate while strictly better in one of the two.
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (f(&r["total_seconds"]), f(&r["rel_rmse"])))
        .collect();
    for (i, r) in rows.iter().enumerate() {
        let dominated = pts.iter().enumerate().any(|(j, q)| {
            j != i
                && q.0 <= pts[i].0
                && q.1 <= pts[i].1
                && (q.0 < pts[i].0 || q.1 < pts[i].1 || j < i)
        });
        assert_eq!(r["pareto"].as_bool().unwrap(), !dominated, "row {i}: {r}");
        assert!(pts[i].1.is_finite() && pts[i].1 > 0.0);
        assert!(f(&r["peak_memory_mib"]) > 0.0, "row {i} has no peak memory");
        assert!(
            (f(&r["total_seconds"]) - f(&r["radiosity_seconds"]) - f(&r["render_seconds"])).abs()
                < 1e-9
        );
    }

    // Each preset is the cheapest row reaching its target, or the most accurate of all, among
    // the rows `render` can reproduce (not the bake's final gather).
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .zip(&pts)
        .filter(|(r, _)| r["method"] != "radiosity-gathered")
        .map(|(_, &q)| q)
        .collect();
    let presets = first["presets"].as_array().unwrap();
    let names: Vec<&str> = presets
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["draft", "preview", "final"]);
    for p in presets {
        let target = f(&p["target_rel_rmse"]);
        let reaching = pts.iter().filter(|q| q.1 <= target);
        let expected = match reaching.clone().map(|q| q.0).reduce(f64::min) {
            Some(t) => {
                assert!(p["reached"].as_bool().unwrap());
                t
            }
            None => {
                assert!(!p["reached"].as_bool().unwrap());
                let best = pts.iter().map(|q| q.1).fold(f64::INFINITY, f64::min);
                assert_eq!(f(&p["measured_rel_rmse"]), best);
                pts.iter()
                    .filter(|q| q.1 == best)
                    .map(|q| q.0)
                    .fold(f64::INFINITY, f64::min)
            }
        };
        assert_eq!(f(&p["measured_seconds"]), expected, "{p}");
    }

    // The path tracer converges: 4 spp beats 1 spp, and the reference's own noise is below both.
    let pt = |spp: u64| {
        rows.iter()
            .find(|r| r["method"] == "reference" && r["spp"] == spp)
            .map(|r| f(&r["rel_rmse"]))
            .unwrap()
    };
    let noise = f(&first["reference"]["noise_rel_rmse"]);
    assert!(
        pt(1) > pt(4) && pt(4) > noise && noise > 0.0,
        "{} {} {noise}",
        pt(1),
        pt(4)
    );
    assert!(!first["reference"]["cached"].as_bool().unwrap());

    // Past the sweep's own runs (1 and 4 spp, far above 12 %), the path tracer renders on
    // until it reaches the smallest target, each run at the samples its last one predicts
    // (error^2 = noise^2 + c / spp, 15 % to spare), never past the reference's 64 spp.
    let path_tracer: Vec<&Value> = rows.iter().filter(|r| r["method"] == "reference").collect();
    let extended: Vec<&Value> = path_tracer
        .iter()
        .copied()
        .filter(|r| r["knob"] == "spp-extended")
        .collect();
    assert!(!extended.is_empty(), "the path tracer was not extended");
    for pair in path_tracer.windows(2).skip(1) {
        let (spp, error) = (f(&pair[0]["spp"]), f(&pair[0]["rel_rmse"]));
        let predicted = spp * (error * error - noise * noise) / (0.12f64.powi(2) - noise * noise);
        assert_eq!(
            f(&pair[1]["spp"]),
            (predicted * 1.15).ceil().min(64.0),
            "{pair:?}"
        );
    }
    let last = path_tracer.last().unwrap();
    assert!(
        f(&last["rel_rmse"]) <= 0.12 || f(&last["spp"]) == 64.0,
        "the path tracer stopped short: {last}"
    );
    assert!(
        path_tracer[..path_tracer.len() - 1]
            .iter()
            .all(|r| f(&r["rel_rmse"]) > 0.12),
        "the path tracer rendered past the target"
    );

    // Outputs exist; the plot is a PNG.
    let png = std::fs::read(first["plot"].as_str().unwrap()).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let csv = std::fs::read_to_string(first["csv"].as_str().unwrap()).unwrap();
    assert_eq!(csv.lines().count(), rows.len() + 1);

    // The second run takes the reference from the cache, and renders deterministically: every
    // error is the same to the last bit.
    let second = sweep(dir.path());
    assert!(second["reference"]["cached"].as_bool().unwrap());
    assert_eq!(
        second["reference"]["noise_rel_rmse"],
        first["reference"]["noise_rel_rmse"]
    );
    let errors = |v: &Value| -> Vec<f64> {
        v["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| f(&r["rel_rmse"]))
            .collect()
    };
    assert_eq!(errors(&first), errors(&second));

    // `render --preset` takes the preset's method and settings.
    let presets_file = first["presets_file"].as_str().unwrap();
    let scene = repo("scenes/cornell-box.toml");
    let exr = dir.path().join("preset.exr");
    let o = cli("render")
        .arg(&scene)
        .words("--preset draft --presets")
        .arg(presets_file)
        .words("--width 16 --json")
        .output(&exr)
        .run();
    let summary = common::ok_json(&o);
    assert_eq!(summary["method"], presets[0]["method"]);
    assert_eq!(summary["spp"], presets[0]["render"]["spp"]);
    assert_eq!(summary["preset"], "draft");
}

#[test]
fn missing_presets_and_unknown_names_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-box.toml");
    // Exit code and stderr of `render --preset NAME --presets FILE`.
    let render = |name: &str, file: &Path| {
        let o = cli("render")
            .arg(&scene)
            .words("--preset")
            .arg(name)
            .words("--presets")
            .arg(file)
            .run();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = render("draft", &dir.path().join("none.presets.toml"));
    assert_eq!(code, Some(1));
    assert!(
        err.contains("none.presets.toml") && err.contains("bench tradeoff"),
        "{err}"
    );

    let file = dir.path().join("x.presets.toml");
    std::fs::write(
        &file,
        "measured_by = \"hand\"\nwidth = 8\nheight = 8\nthreads = 1\npresets = []\n",
    )
    .unwrap();
    let (code, err) = render("final", &file);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("x.presets.toml") && err.contains("no preset `final`"),
        "{err}"
    );

    // A preset's knobs are held to the ranges of the flags they stand for.
    let measured = std::fs::read_to_string(repo("scenes/cornell-box.presets.toml")).unwrap();
    let bad = measured.replacen("shadow_grid = ", "gather_rays = 0\nshadow_grid = ", 1);
    assert_ne!(bad, measured, "the measured presets set a shadow grid");
    std::fs::write(&file, bad).unwrap();
    let (code, err) = render("draft", &file);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("x.presets.toml") && err.contains("gather_rays 0 must be 1 to 1024"),
        "{err}"
    );

    // A preset conflicts with the settings it sets.
    let o = cli("render")
        .arg(&scene)
        .words("--preset draft --spp 4")
        .run();
    assert_eq!(o.status.code(), Some(2));

    let o = cli("bench tradeoff")
        .arg(&scene)
        .words("--quick --targets 0.1,0.05")
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--targets"));

    let o = twopass(&["bench", "tradeoff", "no/such/scene.toml", "--quick"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no/such/scene.toml"));
}
