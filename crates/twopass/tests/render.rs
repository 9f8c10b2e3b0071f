//! `twopass render`: every method writes a multi-layer EXR whose layers sum to the image.

use crate::common;

use crate::common::{cli, render_box, repo};

use std::path::{Path, PathBuf};

use twopass_composite::write::read_exr_layers;

/// A coarse radiosity mesh solved loosely: seconds, not minutes.
const COARSE: &str = "--element-size 80 --patch-size 150 --unshot 1e-2";

#[test]
fn every_method_writes_layers_that_sum_to_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-spheres.toml");
    for method in [
        "whitted",
        "radiosity",
        "hybrid",
        "hybrid-classic",
        "hybrid-direct",
        "reference",
    ] {
        let out = cli("render")
            .arg(&scene)
            .words("--method")
            .arg(method)
            .words("--width 24 --spp 2 --png --layers --json --output")
            .arg(dir.path())
            .words(COARSE)
            .run();
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
    // Without the final gather: the element mesh a bake gathers is not the solve's.
    let bake = common::bake_box(dir.path()).words("--format bake --gather off --quiet");
    common::assert_ok(&bake.words(COARSE).run());
    // Renders into `out`, with the bake file `bake` or a fresh solve.
    let render = |bake: Option<&Path>, out: &Path| {
        let mut c = cli("render")
            .arg(&scene)
            .words("--method radiosity --width 16 --spp 1 --layers --quiet")
            .words(COARSE);
        if let Some(bake) = bake {
            c = c.words("--bake").arg(bake);
        }
        common::assert_ok(&c.output(out).run());
        read_exr_layers(out).unwrap()
    };
    let baked_file = dir.path().join("cornell-box.bake");
    let from_bake = render(Some(&baked_file), &dir.path().join("a.exr"));
    let fresh = render(None, &dir.path().join("b.exr"));
    assert_eq!(
        from_bake.require("image").unwrap().pixels(),
        fresh.require("image").unwrap().pixels()
    );
}

#[test]
fn render_refuses_what_makes_no_sense() {
    let scene = repo("scenes/cornell-box.toml");
    let render = |words: &str| cli("render").arg(&scene).words(words).run();
    let out = render("--method whitted --bake x.bake");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--bake"));
    let out = render("--method phong");
    assert_eq!(out.status.code(), Some(2));
    let missing = render("--method radiosity --bake /nonexistent/x.bake --width 8");
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/x.bake"));
    // No light paths would leave the caustics out; more than a plan picks is refused too.
    for bad in ["0", "-1", "17", "nan", "inf"] {
        let out = render(&format!("--method reference --width 8 --light-paths {bad}"));
        assert_eq!(out.status.code(), Some(2), "--light-paths {bad}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("--light-paths"));
    }
    for bad in ["0", "-1", "65", "2.5"] {
        let out = render(&format!("--method reference --width 8 --splits {bad}"));
        assert_eq!(out.status.code(), Some(2), "--splits {bad}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("--splits"));
    }
}

/// The JSON summary of a 16-pixel-wide, 4-spp render of `scenes/<stem>.toml` with `method` and
/// `extra` arguments (a coarse solve), written into `dir`.
fn small_summary(dir: &Path, stem: &str, method: &str, extra: &str) -> serde_json::Value {
    let out = cli("render")
        .arg(repo(&format!("scenes/{stem}.toml")))
        .words("--width 16 --spp 4 --json --method")
        .arg(method)
        .words(extra)
        .words(COARSE)
        .output(dir)
        .run();
    common::ok_json(&out)
}

/// The path tracer splits its paths as `--splits` says, or as its pilot plans (within the
/// plan's range); the other methods do not split. The summary says which.
#[test]
fn path_splits_are_planned_or_given() {
    let dir = tempfile::tempdir().unwrap();
    let run = |method: &str, extra: &str| small_summary(dir.path(), "cornell-box", method, extra);
    let hybrid = run("hybrid", "");
    assert_eq!(hybrid["splits"], 1);
    assert!(hybrid.get("split_plan").is_none());
    let given = run("reference", "--splits 3");
    assert_eq!(given["splits"], 3);
    assert!(given.get("split_plan").is_none());
    let planned = run("reference", "");
    let n = planned["split_plan"]["splits"].as_u64().unwrap();
    assert!((1..=4).contains(&n), "{planned}");
    assert_eq!(planned["splits"], n, "{planned}");
}

/// The light tracing pass for caustics takes `--light-paths` per camera sample; without it the
/// path tracer's takes as many as its pilot plans (within the plan's range) and the hybrid's
/// one per camera sample. The summary says which.
#[test]
fn light_paths_are_planned_or_given() {
    let dir = tempfile::tempdir().unwrap();
    let run =
        |method: &str, extra: &str| small_summary(dir.path(), "cornell-spheres", method, extra);
    let samples = 16.0 * 16.0 * 4.0;
    let hybrid = run("hybrid", "");
    assert_eq!(hybrid["light_paths"], 1024);
    assert!(hybrid.get("light_plan").is_none());
    assert_eq!(run("hybrid", "--light-paths 0.25")["light_paths"], 256);
    let run = |extra: &str| run("reference", extra);
    let given = run("--light-paths 0.5");
    assert_eq!(given["light_paths"], 512);
    assert!(given.get("light_plan").is_none());
    let planned = run("");
    let r = planned["light_plan"]["paths_per_sample"].as_f64().unwrap();
    assert!((1.0 / 64.0..=16.0).contains(&r), "{r}");
    let paths = planned["light_paths"].as_f64().unwrap();
    assert_eq!(paths, (r as f32 as f64 * samples).ceil(), "{planned}");
}

/// Runs a small Whitted render of the Cornell box with `--output out` and `extra` arguments.
fn render_to(out: &Path, extra: &[&str]) -> std::process::Output {
    render_box("whitted", 16, 1).output(out).args(extra).run()
}

#[test]
fn output_with_an_image_extension_is_that_file() {
    let dir = tempfile::tempdir().unwrap();
    // `-o out.png`: the PNG file alone, not a directory named out.png.
    let png = dir.path().join("out.png");
    let v = common::ok_json(&render_to(&png, &["--json"]));
    assert!(png.is_file(), "{} is not a file", png.display());
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(v["png"].as_str(), png.to_str());
    assert!(v["exr"].is_null(), "no EXR asked for: {v}");
    assert!(!dir.path().join("out.exr").exists());

    // `-o out.exr`: the EXR file, and with --png the PNG beside it.
    let exr = dir.path().join("sub").join("out.exr");
    let out = render_to(&exr, &["--png"]);
    common::assert_ok(&out);
    assert!(exr.is_file(), "{} is not a file", exr.display());
    assert_eq!(
        &std::fs::read(&exr).unwrap()[..4],
        &[0x76, 0x2f, 0x31, 0x01],
        "not an EXR"
    );
    assert_eq!(rgba_exr(&exr).0, ["A", "B", "G", "R"]);
    assert!(exr.with_extension("png").is_file());

    // An image format render cannot write is a usage error, and nothing is created.
    let jpg = dir.path().join("out.jpg");
    let out = render_to(&jpg, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".jpg"));
    assert!(!jpg.exists());
}

#[test]
fn output_without_an_image_extension_is_a_directory() {
    let dir = tempfile::tempdir().unwrap();
    for (name, sub) in [("renders", "renders"), ("out.png/", "out.png")] {
        let out_dir = format!("{}/{name}", dir.path().display());
        let out = render_to(Path::new(&out_dir), &["--png"]);
        common::assert_ok(&out);
        let inside = dir.path().join(sub);
        assert!(inside.is_dir(), "{} is not a directory", inside.display());
        assert!(inside.join("cornell-box-whitted.exr").is_file());
        assert!(inside.join("cornell-box-whitted.png").is_file());
    }
}

/// The channel names (sorted) and, per channel, the samples of a one-part EXR, read with the
/// `exr` crate directly.
fn rgba_exr(path: &Path) -> (Vec<String>, Vec<Vec<f32>>) {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap();
    assert_eq!(image.layer_data.len(), 1, "one part");
    let channels = &image.layer_data[0].channel_data.list;
    (
        channels.iter().map(|c| c.name.to_string()).collect(),
        channels
            .iter()
            .map(|c| c.sample_data.values_as_f32().collect())
            .collect(),
    )
}

/// Issue 41: the render EXR is a plain RGBA image by default (what Blender, Nuke and tev open
/// as the image): channels R, G, B and A = 1 only, R, G, B bit for bit the final image of the
/// layered file `--layers` writes from the same render.
#[test]
fn the_default_exr_is_plain_rgba_and_layers_writes_every_pass() {
    let dir = tempfile::tempdir().unwrap();
    let render = |extra: &str, out: &Path| {
        let c = cli("render")
            .arg(repo("scenes/cornell-box.toml"))
            .words("--method whitted --width 16 --spp 1 --seed 3 --quiet")
            .words(extra);
        common::assert_ok(&c.output(out).run());
    };
    let (plain, layered) = (dir.path().join("plain.exr"), dir.path().join("layered.exr"));
    render("", &plain);
    render("--layers", &layered);
    let (names, samples) = rgba_exr(&plain);
    assert_eq!(names, ["A", "B", "G", "R"]);
    assert!(samples[0].iter().all(|&a| a == 1.0), "A is 1 everywhere");
    let image = read_exr_layers(&layered).unwrap();
    let image = image.require("image").unwrap();
    let pixels = image.pixels();
    assert_eq!(samples[3].len(), pixels.len());
    for (c, channel) in [(0, 3), (1, 2), (2, 1)] {
        let want: Vec<u32> = pixels.iter().map(|p| p[c].to_bits()).collect();
        let got: Vec<u32> = samples[channel].iter().map(|v| v.to_bits()).collect();
        assert_eq!(got, want, "channel {}", names[channel]);
    }
    // The layered file has the passes; the plain one has none.
    assert!(read_exr_layers(&layered).unwrap().names().count() > 1);
    assert_eq!(read_exr_layers(&plain).unwrap().names().count(), 0);
    // Python's OpenEXR, where installed, reads the same four channels.
    let py = std::process::Command::new("python3")
        .arg("-c")
        .arg("import sys, OpenEXR; print(' '.join(sorted(OpenEXR.InputFile(sys.argv[1]).header()['channels'])))")
        .arg(&plain)
        .output();
    match py {
        Ok(out) if out.status.success() => {
            assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "A B G R");
        }
        _ => eprintln!("note: the plain EXR not read with Python's OpenEXR (not installed)"),
    }
}

#[test]
fn the_gathered_hybrid_solves_on_a_mesh_twice_as_coarse_unless_told() {
    // Without --element-size the gathered hybrid solves with elements of the scene diagonal
    // / 12 (radiosity alone: / 24): the same image as that size given explicitly, and not
    // the image of radiosity alone's default mesh.
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-box.toml");
    let (box_scene, _) = twopass_scene::load(&scene).unwrap();
    let diagonal = box_scene.bounds.diagonal();
    let render = |extra: &str, out: &str| {
        let path = dir.path().join(out);
        let c = cli("render")
            .arg(&scene)
            .words("--method hybrid --width 16 --spp 1 --unshot 1e-2 --layers --quiet")
            .words(extra);
        common::assert_ok(&c.output(&path).run());
        read_exr_layers(&path).unwrap()
    };
    let default = render("", "default.exr");
    let coarse = render(&format!("--element-size={}", diagonal / 12.0), "coarse.exr");
    let fine = render(&format!("--element-size={}", diagonal / 24.0), "fine.exr");
    let image = |l: &twopass_composite::Layers| l.require("image").unwrap().pixels().to_vec();
    assert_eq!(image(&default), image(&coarse));
    assert_ne!(image(&default), image(&fine));
}

#[test]
fn a_render_without_spp_spends_its_samples_where_the_noise_is() {
    // The Cornell spheres' noise sits in the mirror and the glass sphere (the small light seen
    // in them, the caustic): by noise, the same 64 samples per pixel on average leave less
    // noise than 64 in every pixel. Noise is measured as the planner measures it, from two
    // renders with different seeds (one image's relative RMSE against the truth).
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cornell-spheres.toml");
    let render = |extra: &str, seed: u32| {
        let path = dir.path().join(format!("{}-{seed}.exr", extra.len()));
        let out = cli("render")
            .arg(&scene)
            .words(&format!(
                "--method hybrid --width 32 --layers --json --seed {seed} {COARSE}"
            ))
            .words(extra)
            .output(&path)
            .run();
        let v = common::ok_json(&out);
        let image = read_exr_layers(&path)
            .unwrap()
            .require("image")
            .unwrap()
            .clone();
        (v, image)
    };
    let noise = |extra: &str| {
        let ((v, a), (_, b)) = (render(extra, 1), render(extra, 2));
        let mut sum = 0.0;
        for (x, y) in a.pixels().iter().zip(b.pixels()) {
            for c in 0..3 {
                let (x, y) = (f64::from(x[c]), f64::from(y[c]));
                let m = 0.5 * (x + y);
                sum += (x - y) * (x - y) / 2.0 / (m * m + 0.01);
            }
        }
        (v, (sum / (3 * a.pixels().len()) as f64).sqrt())
    };
    let (by_noise, spread) = noise("");
    let (uniform, even) = noise("--spp 64");
    let a = &by_noise["allocation"];
    assert_eq!(a["pilot_spp"], 4, "{by_noise}");
    let (lo, hi) = (
        a["min_spp"].as_u64().unwrap(),
        a["max_spp"].as_u64().unwrap(),
    );
    assert!(lo < 64 && hi > 64, "{lo}-{hi} spp");
    assert_eq!(by_noise["spp"], 64);
    assert!(uniform.get("allocation").is_none(), "{uniform}");
    assert!(spread < even, "noise by noise {spread}, uniform {even}");
}
