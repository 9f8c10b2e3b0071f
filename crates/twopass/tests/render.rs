//! `twopass render`: every method writes a multi-layer EXR whose layers sum to the image.

mod common;

use common::{repo, twopass};

use std::path::{Path, PathBuf};

use twopass_composite::write::read_exr_layers;

const COARSE: [&str; 6] = [
    "--element-size",
    "80",
    "--patch-size",
    "150",
    "--unshot",
    "1e-2",
];

#[test]
fn every_method_writes_layers_that_sum_to_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-spheres.toml");
    for method in [
        "whitted",
        "radiosity",
        "hybrid",
        "hybrid-direct",
        "reference",
    ] {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--method",
            method,
            "--width",
            "24",
            "--spp",
            "2",
            "--png",
            "--json",
        ];
        args.extend(["--output", dir.path().to_str().unwrap()]);
        args.extend(COARSE);
        let out = twopass(&args);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["non_finite_samples"], 0);
        let exr = PathBuf::from(v["exr"].as_str().unwrap());
        assert!(exr.with_extension("png").exists());
        let layers = read_exr_layers(&exr).unwrap();
        let names: Vec<&str> = layers.names().collect();
        for name in [
            "image",
            "emission",
            "diffuse",
            "direct_specular",
            "reflection",
            "refraction",
            "ambient",
        ] {
            assert!(names.contains(&name), "{method}: {names:?}");
        }
        let image = layers.require("image").unwrap();
        assert_eq!(image.size(), (24, 24));
        let parts: Vec<&str> = names.iter().copied().filter(|n| *n != "image").collect();
        let sum = layers.sum(&parts).unwrap();
        for (a, b) in image.pixels().iter().zip(sum.pixels()) {
            assert!(
                a.is_finite()
                    && (*a - *b).abs().max_element() <= 1e-5 * a.abs().max_element().max(1.0),
                "{method}: {a} vs {b}"
            );
        }
        // The reported mean is the image's mean.
        let mean = image.pixels().iter().copied().sum::<glam::Vec3>() / image.pixels().len() as f32;
        let reported = v["mean"].as_array().unwrap()[0].as_f64().unwrap() as f32;
        assert!(
            (mean.x - reported).abs() <= 1e-5 * mean.x.max(1.0),
            "{mean} vs {reported}"
        );
    }
}

#[test]
fn a_bake_renders_the_same_as_a_fresh_solve_with_the_same_settings() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-box.toml");
    let d = dir.path().to_str().unwrap();
    let mut bake = vec![
        "bake",
        scene.to_str().unwrap(),
        "--format",
        "bake",
        "--output",
        d,
        "--quiet",
    ];
    bake.extend(COARSE);
    assert_eq!(twopass(&bake).status.code(), Some(0));
    let render = |extra: &[&str], out: &str| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--method",
            "radiosity",
            "--width",
            "16",
            "--spp",
            "1",
            "--quiet",
        ];
        args.extend(COARSE);
        args.extend(extra);
        args.extend(["--output", out]);
        let o = twopass(&args);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        read_exr_layers(Path::new(out)).unwrap()
    };
    let baked_file = dir.path().join("cornell-box.bake");
    let from_bake = render(
        &["--bake", baked_file.to_str().unwrap()],
        &format!("{d}/a.exr"),
    );
    let fresh = render(&[], &format!("{d}/b.exr"));
    assert_eq!(
        from_bake.require("image").unwrap().pixels(),
        fresh.require("image").unwrap().pixels()
    );
}

#[test]
fn render_refuses_what_makes_no_sense() {
    let scene = repo("scenes/cornell-box.toml");
    let out = twopass(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "whitted",
        "--bake",
        "x.bake",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--bake"));
    let out = twopass(&["render", scene.to_str().unwrap(), "--method", "phong"]);
    assert_eq!(out.status.code(), Some(2));
    let missing = twopass(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "radiosity",
        "--bake",
        "/nonexistent/x.bake",
        "--width",
        "8",
    ]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/x.bake"));
}
