//! `twopass compare`: the report's numbers are recomputed from the EXRs it wrote.

use crate::common;

use crate::common::{BOX, SPHERES, cli, repo};

use std::path::Path;

use serde_json::Value;

use twopass_composite::metric::compare;
use twopass_composite::sheet::ComparisonOptions;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::read_exr_layers;

/// The JSON report of `compare --quick` on `scene` (relative to the repository root) into
/// `dir` with [width, spp, reference spp].
fn quick_compare(scene: &str, dir: &Path, [width, spp, reference_spp]: [&str; 3]) -> Value {
    let small = format!("--width {width} --spp {spp} --reference-spp {reference_spp}");
    let line = cli("compare").arg(repo(scene)).words(&small);
    common::ok_json(&line.output(dir).words("--quick --json").run())
}

#[test]
fn report_matches_the_images_it_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let report = quick_compare(SPHERES, dir.path(), ["24", "2", "16"]);
    let rows = report["rows"].as_array().unwrap();
    let methods = common::row_methods(&report);
    // The spheres call for every method; the reference comes first.
    assert_eq!(
        methods,
        [
            "reference",
            "whitted",
            "radiosity",
            "hybrid",
            "hybrid-classic",
            "hybrid-direct"
        ]
    );
    let image = |row: &Value| {
        let layers = read_exr_layers(Path::new(row["exr"].as_str().unwrap())).unwrap();
        layers.require("image").unwrap().clone()
    };
    let reference = image(&rows[0]);
    let tone = ToneMap::auto_default(&reference)
        .unwrap()
        .with_curve(ComparisonOptions::default().curve);
    assert_eq!(report["tone_map"].as_str().unwrap(), tone.describe());
    for row in &rows[1..] {
        let m = compare(&image(row), &reference, &tone).unwrap();
        for (key, value) in [
            ("mae", m.mae),
            ("rmse", m.rmse),
            ("rel_mse", m.rel_mse),
            ("rel_rmse", m.rel_rmse),
            ("ssim", m.ssim),
        ] {
            let reported = row[key].as_f64().unwrap();
            assert!(
                (reported - value).abs() <= 1e-12 * value.abs().max(1.0),
                "{} {key}: {reported} vs {value}",
                row["method"]
            );
        }
        assert!(row["total_seconds"].as_f64().unwrap() >= row["render_seconds"].as_f64().unwrap());
    }
    assert!(rows[0]["rel_rmse"].is_null());
    // The CSV holds the same rows.
    let csv = std::fs::read_to_string(dir.path().join("cornell-spheres-compare.csv")).unwrap();
    assert_eq!(csv.lines().count(), rows.len() + 1);
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .starts_with("method,width,height,spp")
    );
    // The sheet exists and is a PNG holding two rows of 24-pixel panels.
    let png = std::fs::read(dir.path().join("cornell-spheres-compare.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn a_diffuse_scene_skips_the_classic_hybrid_and_says_why() {
    // On Lambertian walls the classic hybrid is radiosity alone; the gathered hybrid is not.
    let dir = tempfile::tempdir().unwrap();
    let report = quick_compare(BOX, dir.path(), ["16", "1", "4"]);
    let methods = common::row_methods(&report);
    assert!(methods.contains(&"hybrid"));
    assert!(!methods.contains(&"hybrid-classic"));
    let skipped = report["skipped"][0].as_str().unwrap();
    assert!(
        skipped.starts_with("hybrid-classic") && skipped.contains("purely diffuse"),
        "{skipped}"
    );
}
