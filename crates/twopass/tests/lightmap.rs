//! `twopass bake --lightmap` and `--format vertex-glb`: the files, each listed in the manifest with its size and
//! CRC-32, the final gather's record, `--gather`'s values, and `--texel-size` only with
//! `--lightmap`.

use crate::common;

use crate::common::{cli, repo};

#[test]
fn lightmap_bake_writes_its_files_into_the_manifest() {
    let out_dir = tempfile::tempdir().unwrap();
    let dir = out_dir.path();
    let out = common::bake_box(dir)
        .words("--format glb,vertex-glb --lightmap --texel-size 10")
        .words("--element-size 100 --unshot 1e-2 --json")
        .run();
    let manifest = common::ok_json(&out);
    let files = manifest["files"].as_array().unwrap();
    let mut names: Vec<&str> = files
        .iter()
        .map(|f| f["format"].as_str().unwrap())
        .collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "glb",
            "lightmap-exr",
            "lightmap-glb",
            "lightmap-png",
            "lightmap-rgbm.png",
            "vertex.glb"
        ]
    );
    for f in files {
        let bytes = std::fs::read(f["path"].as_str().unwrap()).unwrap();
        assert_eq!(f["bytes"].as_u64().unwrap(), bytes.len() as u64);
        assert_eq!(
            f["crc32"].as_u64().unwrap(),
            u64::from(crc32fast::hash(&bytes))
        );
    }
    let lm = &manifest["lightmap"];
    assert_eq!(lm["texel_size"], 10.0);
    // The box is about 556 x 549 x 559 mm: its six sides alone need about 5 x 55 x 55 texels
    // of 10 mm, so the atlas holds at least that.
    let texels = lm["width"].as_u64().unwrap() * lm["height"].as_u64().unwrap();
    assert!(texels >= 5 * 55 * 55, "{lm}");
    assert!(
        lm["covered_texels"].as_u64().unwrap() >= 5 * 54 * 54,
        "{lm}"
    );
    assert!(dir.join("cornell-box.lightmap.png").exists());
    // The HDR texture the .glb names for engines (the default encoding), with its multiplier.
    assert!(dir.join("cornell-box.lightmap.rgbm.png").exists());
    assert_eq!(lm["encoding"], "rgbm", "{lm}");
    assert!(lm["rgbm_multiplier"].as_f64().unwrap() > 0.0, "{lm}");
    // The default final gather ran and says what it did.
    let g = &lm["gather"];
    assert_eq!(g["min_rays"], 64, "{g}");
    assert_eq!(g["max_rays"], 256, "{g}");
    assert!(g["rays"].as_u64().unwrap() >= 64 * 5 * 54 * 54, "{g}");
    assert!(g["shadow_rays"].as_u64().unwrap() > 0, "{g}");
    assert_eq!(g["late_points"], 0, "{g}");
}

#[test]
fn gather_takes_off_auto_or_a_ray_count() {
    let out_dir = tempfile::tempdir().unwrap();
    let dir = out_dir.path();
    let off = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 20 --gather off")
        .words("--element-size 100 --unshot 1e-2 --json")
        .run();
    assert!(common::ok_json(&off)["lightmap"]["gather"].is_null());
    let sixteen = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 20 --gather 16")
        .words("--element-size 100 --unshot 1e-2 --json")
        .run();
    let g = &common::ok_json(&sixteen)["lightmap"]["gather"];
    assert_eq!(
        (g["min_rays"].as_u64(), g["max_rays"].as_u64()),
        (Some(16), Some(16)),
        "{g}"
    );
    let scene = repo("scenes/cornell-box.toml");
    for bad in ["0", "-3", "65537", "many", "1.5"] {
        let out = cli("bake")
            .arg(&scene)
            .words("--lightmap")
            .arg(format!("--gather={bad}"))
            .run();
        common::assert_exit(&out, 2);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--gather"), "{bad}: {err}");
    }
}

#[test]
fn a_texel_size_no_atlas_can_hold_is_refused_before_the_solve() {
    // The box's 5 walls, floor, ceiling and blocks are about 2.2 million mm^2: at 1e-7 mm a
    // texel, no 8192 x 8192 atlas holds them. Refused at once (no solve), the set already in
    // the folder untouched.
    let out_dir = tempfile::tempdir().unwrap();
    let dir = out_dir.path();
    let first = common::bake_box(dir)
        .words("--format bake --element-size 100 --unshot 1e-2 --quiet")
        .run();
    common::assert_ok(&first);
    let manifest = dir.join("cornell-box.manifest.json");
    let before = std::fs::read(&manifest).unwrap();
    let out = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 1e-7")
        .run();
    common::assert_exit(&out, 2);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--texel-size") && err.contains("smallest texel size"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&manifest).unwrap(),
        before,
        "the old set untouched"
    );
    assert!(!dir.join("cornell-box.lightmap.glb").exists());
    // Above that area bound (0.17 mm) but too small for the charts once packed with their
    // padding: refused before the solve as well, by the layout itself.
    let out = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 0.2")
        .run();
    common::assert_exit(&out, 2);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--texel-size 0.2")
            && err.contains("the charts need more than 8192 x 8192 texels"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&manifest).unwrap(),
        before,
        "the old set untouched"
    );
}

#[test]
fn texel_size_needs_lightmap() {
    let scene = repo("scenes/cornell-box.toml");
    for words in ["--texel-size 5", "--lightmap --texel-size -1"] {
        let out = cli("bake").arg(&scene).words(words).run();
        common::assert_exit(&out, 2);
    }
}

#[test]
fn a_gather_ends_at_the_time_budget_with_every_texel_filled() {
    // A 2 mm lightmap of the box is about 400,000 texels: minutes of gathering. Under a 3 s
    // budget the gather stops where the budget does, the late texels show the solution, and the
    // manifest counts them. The solve before it is kept short (100 mm elements: a quarter of a
    // second alone, against a second by default), so that the gather has time left for some
    // texels even when the tests beside it load the machine.
    let out_dir = tempfile::tempdir().unwrap();
    let dir = out_dir.path();
    let out = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 2 --time-budget 3 --element-size 100")
        .words("--json")
        .run();
    let manifest = common::ok_json(&out);
    let lm = &manifest["lightmap"];
    let late = lm["gather"]["late_points"].as_u64().unwrap();
    let covered = lm["covered_texels"].as_u64().unwrap();
    assert!(late > 0 && late < covered, "{late} of {covered} late");
    // The budget bounds the process; writing a 400,000-texel set after it takes well under the
    // slack allowed here.
    let total = manifest["timings"]["total_s"].as_f64().unwrap();
    assert!(total < 3.0 + 5.0, "{total} s");
}

#[test]
fn lightmap_encoding_srgb_writes_no_rgbm_and_needs_lightmap() {
    let out_dir = tempfile::tempdir().unwrap();
    let dir = out_dir.path();
    let out = common::bake_box(dir)
        .words("--format bake --lightmap --texel-size 20 --gather off")
        .words("--lightmap-encoding srgb --element-size 100 --unshot 1e-2 --json")
        .run();
    let manifest = common::ok_json(&out);
    assert_eq!(manifest["lightmap"]["encoding"], "srgb");
    assert!(manifest["lightmap"]["rgbm_multiplier"].is_null());
    common::assert_absent(
        &dir.join("cornell-box.lightmap.rgbm.png"),
        "no RGBM texture with --lightmap-encoding srgb",
    );
    // The encoding without a lightmap is a usage error; an unknown one too.
    let out = common::bake_box(dir)
        .words("--format bake --lightmap-encoding rgbm")
        .run();
    common::assert_exit(&out, 2);
    let out = common::bake_box(dir)
        .words("--format bake --lightmap --lightmap-encoding rgbe")
        .run();
    common::assert_exit(&out, 2);
}
