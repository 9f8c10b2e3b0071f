//! The command line as scripts drive it: exit codes, messages on stderr, JSON on stdout.

use crate::common;

use crate::common::{BOX, SPHERES, cli, repo, twopass};

#[test]
fn info_json_describes_the_cornell_box() {
    let scene = repo("scenes/cornell-box.toml");
    let out = twopass(&["info", scene.to_str().unwrap(), "--json", "--width", "256"]);
    let v = common::ok_json(&out);
    assert_eq!(v["triangles"], 32);
    assert_eq!(
        v["resolution"],
        serde_json::json!([256, 256]),
        "--width alone keeps the aspect"
    );
    assert_eq!(v["plan"]["diffuse"]["required"], true);
    assert_eq!(
        v["plan"]["specular"]["required"], false,
        "an all-Lambertian scene needs no specular pass"
    );
    decision(
        &v,
        "specular_transfer",
        false,
        "no mirror, conductor or dielectric",
    );
    decision(&v, "caustics", false, "no light through mirrors and glass");
    assert_eq!(v["emitters"].as_array().unwrap().len(), 1);
}

#[test]
fn specular_pass_is_planned_only_for_non_diffuse_materials() {
    let scene = repo("scenes/cornell-spheres.toml");
    let out = twopass(&["info", scene.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    decision(&v, "specular", true, "glass (dielectric), mirror (mirror)");
    // The spheres face the walls: light through them goes to the radiosity elements.
    let why = "mirror-sphere, glass-sphere face diffuse surfaces";
    decision(&v, "specular_transfer", true, why);
    // The glass sphere focuses light: the hybrids show that caustic per pixel.
    decision(&v, "caustics", true, "focused through glass-sphere");
}

/// Asserts that `info --json`'s plan has pass `pass` required or not, for a reason that
/// contains `because`.
fn decision(v: &serde_json::Value, pass: &str, required: bool, because: &str) {
    assert_eq!(v["plan"][pass]["required"], required, "{pass}");
    let reason = v["plan"][pass]["reason"].as_str().unwrap();
    assert!(reason.contains(because), "{pass}: {reason}");
}

#[test]
fn bad_input_exits_1_naming_the_file() {
    let scene = repo("tests/data/unknown-material.toml");
    let out = twopass(&["info", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown-material.toml:") && err.contains("chalk"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn usage_error_exits_2() {
    assert_eq!(twopass(&["info"]).status.code(), Some(2));
    assert_eq!(twopass(&["frobnicate"]).status.code(), Some(2));
    assert_eq!(
        twopass(&["info", "x.toml", "--width", "0"]).status.code(),
        Some(2)
    );
}

/// The JSON report of `twopass bench <kind> <scene> --json <flags>`, `scene` relative to the
/// repository root.
fn bench(kind: &str, scene: &str, flags: &str) -> serde_json::Value {
    let line = cli("bench").words(kind).arg(repo(scene)).words("--json");
    common::ok_json(&line.words(flags).run())
}

#[test]
fn bench_rays_reports_every_query_kind() {
    let v = bench("rays", BOX, "--seconds 0.01 --rays 1000 --width 32");
    let rows = v["rows"].as_array().unwrap();
    let queries: Vec<&str> = rows.iter().map(|r| r["query"].as_str().unwrap()).collect();
    assert_eq!(queries, ["camera (coherent)", "incoherent", "occlusion"]);
    // One camera ray per pixel of the 32 x 32 image, then the --rays batch.
    let rays: Vec<u64> = rows.iter().map(|r| r["rays"].as_u64().unwrap()).collect();
    assert_eq!(rays, [32 * 32, 1000, 1000]);
    let (loaded, _) = twopass_scene::load(repo(BOX)).unwrap();
    assert_eq!(
        v["triangles"].as_u64(),
        Some(loaded.mesh.triangle_count() as u64)
    );
    // The tree's memory is its nodes (256 bytes each, each starting on a 64-byte line) and
    // packets (160 bytes each, four triangles at most, every triangle in one).
    let (nodes, packets) = (
        v["bvh_nodes"].as_u64().unwrap(),
        v["bvh_packets"].as_u64().unwrap(),
    );
    let triangles = v["triangles"].as_u64().unwrap();
    assert!(
        nodes >= 1 && 4 * packets >= triangles && packets <= triangles,
        "{v}"
    );
    let bytes = v["bvh_mib"].as_f64().unwrap() * f64::from(1 << 20);
    let least = (256 * nodes + 160 * packets) as f64;
    assert!(
        bytes >= least && bytes <= least + 32.0 * nodes as f64,
        "{bytes} bytes"
    );
    for r in rows {
        let (one, all) = (
            r["mrays_1"].as_f64().unwrap(),
            r["mrays_n"].as_f64().unwrap(),
        );
        assert!(one.is_finite() && one > 0.0 && all.is_finite() && all > 0.0);
        let speedup = r["speedup"].as_f64().unwrap();
        assert!((speedup - all / one).abs() <= 1e-9 * speedup, "{r}");
        for key in ["many_mrays_1", "many_mrays_n"] {
            let rate = r[key].as_f64().unwrap();
            assert!(rate.is_finite() && rate > 0.0, "{r}");
        }
        let hit = r["hit_fraction"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&hit), "{r}");
    }
    // The camera looks into the box: most camera rays hit it, and some occlusion rays are
    // blocked between two points on its walls.
    assert!(rows[0]["hit_fraction"].as_f64().unwrap() > 0.5);
    assert!(rows[2]["hit_fraction"].as_f64().unwrap() > 0.0);
}

#[test]
fn bench_radiosity_reports_each_mesh_with_the_dense_check() {
    let rows = bench("radiosity", BOX, "--elements 300,600 --unshot 1e-2");
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    let elements: Vec<u64> = rows
        .iter()
        .map(|r| r["elements"].as_u64().expect("an element count"))
        .collect();
    assert!(elements[1] > elements[0], "more elements asked, more made");
    let targets: Vec<u64> = rows
        .iter()
        .map(|r| r["target_elements"].as_u64().unwrap())
        .collect();
    assert_eq!(targets, [300, 600]);
    for r in rows {
        assert!(r["unshot_fraction"].as_f64().unwrap() <= 1e-2);
        assert!(r["rays"].as_u64().unwrap() > 0);
        // Small meshes are checked against the dense solve. What is still unshot, u, becomes
        // at most u / (1 - rho_max) of the radiosity once interreflected (rho_max = 0.725).
        assert!(r["dense_relative_rms"].as_f64().unwrap() < 1e-2 / (1.0 - 0.725));
    }
}

#[test]
fn bench_render_times_every_method_and_the_bake_frame_rate() {
    let v = bench("render", SPHERES, "--width 24 --spp 1 --frames 2");
    let methods = common::row_methods(&v);
    assert_eq!(
        methods,
        [
            "whitted",
            "radiosity",
            "hybrid",
            "hybrid-classic",
            "hybrid-direct",
            "reference"
        ]
    );
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(24), Some(24))
    );
    assert!(v["frames_per_second"].as_f64().unwrap() > 0.0);
    assert!(
        v["rows"]
            .as_array()
            .unwrap()
            .iter()
            .all(|r| r["non_finite"] == 0)
    );
}

#[test]
fn render_exr_says_how_it_was_made() {
    // The EXR of `render` carries the final image as plain R, G, B, A (every layer too with
    // `--layers`) and the render's method, samples, seed and version in its header, read back
    // here by the exr crate itself.
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("box.exr");
    let out = common::render_box("whitted", 16, 2)
        .words("--seed 7 -o")
        .arg(&exr_path)
        .words("--quiet")
        .run();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let raw = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let layer = &raw.layer_data[0];
    let names = channel_names(layer);
    assert_eq!(names, ["A", "B", "G", "R"]);
    let attr = |name: &str| twopass_tests::exr_text(&layer.attributes, name);
    assert_eq!(attr("twopass:method"), "whitted");
    assert_eq!(attr("twopass:spp"), "2");
    assert_eq!(attr("twopass:seed"), "7");
    assert!(attr("twopass:seconds").parse::<f64>().unwrap() > 0.0);
    assert_eq!(attr("twopass:version"), env!("CARGO_PKG_VERSION"));
    // With --layers: the passes beside the plain image, and the same header.
    let out = common::render_box("whitted", 16, 2)
        .words("--seed 7 --layers -o")
        .arg(&exr_path)
        .words("--quiet")
        .run();
    assert!(out.status.success());
    let raw = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let layer = &raw.layer_data[0];
    let names = channel_names(layer);
    for c in ["R", "G", "B", "image.R"] {
        assert!(names.iter().any(|n| n == c), "no channel {c} in {names:?}");
    }
    assert_eq!(
        twopass_tests::exr_text(&layer.attributes, "twopass:method"),
        "whitted"
    );
}

#[test]
fn render_says_when_the_specular_transfer_does_not_run() {
    let scene = repo("scenes/cornell-spheres.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("h.exr");
    let args = |extra: &str| {
        let a = cli("render")
            .arg(&scene)
            .words("--method hybrid --width 16 --spp 1 --json -o")
            .arg(&out)
            .words(extra);
        let v = common::ok_json(&a.run());
        v["skipped"].to_string()
    };
    // By default the spheres get the transfer: nothing is skipped.
    assert_eq!(args(""), "[]");
    // The hierarchical solver carries it too.
    assert_eq!(args("--solver hierarchical"), "[]");
    let off = args("--specular-rays 0");
    assert!(off.contains("--specular-rays 0"), "{off}");
}

/// The channel names of an EXR layer, in the file's (alphabetical) order.
fn channel_names(
    layer: &exr::prelude::Layer<exr::prelude::AnyChannels<exr::prelude::FlatSamples>>,
) -> Vec<String> {
    layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect()
}
