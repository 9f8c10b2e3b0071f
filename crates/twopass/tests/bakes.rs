//! `twopass bench bakes`: one small room end to end, its report's fields, and the cached
//! reference reused (and renewed when its key changes).

use crate::common;

use crate::common::cli;

use std::path::Path;
use std::process::Output;

use serde_json::Value;

/// The terminator room at 32 x 32, a 16-spp reference, regions of 20 pixels, into `out`.
fn bench(out: &Path, extra: &str) -> Output {
    cli("bench bakes --rooms terminator --size 32 --reference-spp 16 --min-region-pixels 20")
        .words("--out")
        .arg(out)
        .words(extra)
        .run()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn a_room_is_baked_rendered_measured_and_its_reference_cached() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let first = common::ok_json(&bench(out, "--json"));
    assert_eq!(first["size"], 32);
    assert_eq!(first["reference_spp"], 16);
    let rooms = first["rooms"].as_array().unwrap();
    assert_eq!(rooms.len(), 1);
    let room = &rooms[0];
    assert_eq!(room["room"], "terminator");
    // Six walls, the sphere and the light; 6 x 2 x 2 x 2 wall triangles, 320 for the sphere,
    // 2 for the light.
    assert_eq!(room["objects"], 8);
    assert_eq!(room["triangles"], 48 + 320 + 2);
    assert_eq!(room["reference"]["cached"], false);
    assert!(f(&room["reference"]["mean_luminance"]) > 0.0);
    // The noise row is half the reference's samples against it: its relative RMSE is the
    // reference's own noise figure.
    let noise = &room["reference"]["noise"];
    let floor = f(&room["reference"]["noise_rel_rmse"]);
    assert!(
        floor > 0.0 && (f(&noise["rel_rmse"]) - floor).abs() < 1e-3 * floor,
        "{noise}"
    );
    let bakes = room["bakes"].as_array().unwrap();
    assert_eq!(bakes.len(), 1);
    assert!(f(&bakes[0]["seconds"]) > 0.0);
    assert!(f(&bakes[0]["peak_memory_mib"]) > 1.0);
    // The bake's default gathers the lightmap.
    assert!(bakes[0]["gather_rays"].as_u64().unwrap() > 0);
    let images = room["images"].as_array().unwrap();
    let sources: Vec<&str> = images
        .iter()
        .map(|i| i["source"].as_str().unwrap())
        .collect();
    assert_eq!(sources, ["lightmap", "element bake"]);
    for i in images {
        for field in ["rel_rmse", "share_off", "p95_deviation"] {
            let x = f(&i[field]);
            assert!(x.is_finite() && x >= 0.0, "{field} = {x}");
        }
        assert!(f(&i["mean_error"]) > -1.0);
        assert!(f(&i["share_off"]) <= 1.0);
        // The sphere fills much of the frame; regions come worst first.
        let regions = i["regions"].as_array().unwrap();
        assert!(
            regions.iter().any(|r| r["object"] == "room/sphere"),
            "{regions:?}"
        );
        let errors: Vec<f64> = regions.iter().map(|r| f(&r["error"]).abs()).collect();
        assert!(errors.windows(2).all(|w| w[0] >= w[1]), "{errors:?}");
        assert!(regions.iter().all(|r| f(&r["pixels"]) >= 20.0));
        assert!(Path::new(i["exr"].as_str().unwrap()).is_file());
    }
    let room_dir = out.join("terminator");
    for file in [
        "terminator.toml",
        "terminator.obj",
        "reference-16spp.exr",
        "reference-16spp-half0.exr",
        "reference-16spp.json",
        "lightmap.exr",
        "element-bake.exr",
    ] {
        assert!(room_dir.join(file).is_file(), "{file} missing");
    }
    let saved: Value =
        serde_json::from_slice(&std::fs::read(out.join("bench-bakes.json")).unwrap()).unwrap();
    assert_eq!(saved, first);

    // Again, as a person would run it: the tables, and the reference from the cache,
    // untouched.
    let exr = room_dir.join("reference-16spp.exr");
    let stamp = std::fs::metadata(&exr).unwrap().modified().unwrap();
    let second = bench(out, "");
    common::assert_ok(&second);
    let text = String::from_utf8(second.stdout).unwrap();
    assert!(
        text.contains("terminator: 370 triangles, 8 objects; reference cached"),
        "{text}"
    );
    assert!(
        text.contains(
            "\nsummary: rooms 32 x 32 (scene files at their own camera's size), reference 16 spp"
        ),
        "{text}"
    );
    for row in [
        "\nlightmap ",
        "\nelement bake ",
        "\n(ref. noise) ",
        "\nterminator  (ref. noise) ",
    ] {
        assert!(text.contains(row), "no row {row:?} in {text}");
    }
    assert_eq!(std::fs::metadata(&exr).unwrap().modified().unwrap(), stamp);
    let saved: Value =
        serde_json::from_slice(&std::fs::read(out.join("bench-bakes.json")).unwrap()).unwrap();
    assert_eq!(saved["rooms"][0]["reference"]["cached"], true);

    // Another seed is another reference.
    let third = common::ok_json(&bench(out, "--seed 1 --json"));
    assert_eq!(third["rooms"][0]["reference"]["cached"], false);
}

#[test]
fn gathers_bakes_once_per_setting_and_measures_each() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let report = common::ok_json(&bench(out, "--gathers off,8 --json"));
    let room = &report["rooms"][0];
    let bakes = room["bakes"].as_array().unwrap();
    let settings: Vec<&str> = bakes
        .iter()
        .map(|b| b["gather"].as_str().unwrap())
        .collect();
    assert_eq!(settings, ["off", "8"]);
    // No gather, no gather rays; eight rays at most per texel (and the shadow rays) for the
    // other.
    assert!(bakes[0]["gather_rays"].is_null(), "{}", bakes[0]);
    assert!(bakes[1]["gather_rays"].as_u64().unwrap() > 0);
    assert!(
        out.join("terminator/bake-gather-8/terminator.lightmap.glb")
            .is_file()
    );
    let images = room["images"].as_array().unwrap();
    let sources: Vec<(&str, u64)> = images
        .iter()
        .map(|i| (i["source"].as_str().unwrap(), i["bake"].as_u64().unwrap()))
        .collect();
    assert_eq!(
        sources,
        [
            ("lightmap g=off", 0),
            ("element bake g=off", 0),
            ("lightmap g=8", 1),
            ("element bake g=8", 1)
        ]
    );
    for name in ["lightmap-gather-off.exr", "lightmap-gather-8.exr"] {
        assert!(out.join("terminator").join(name).is_file(), "{name}");
    }
    // A setting that is not one is a usage error before anything is baked.
    let o = cli("bench bakes --rooms terminator --gathers 0 --out")
        .arg(out)
        .run();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("`0` is not off, auto or a ray count"), "{err}");
}

#[test]
fn an_image_size_other_than_size_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let o = cli("bench bakes --rooms terminator --width 64 --out")
        .arg(dir.path())
        .run();
    common::assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bench bakes: --width/--height do not apply; every room's camera is --size pixels square"),
        "{err}"
    );
}

/// A `--scene` file that cannot be read is refused before any room is baked (it used to be
/// found missing after the rooms' minutes of work), naming the file.
#[test]
fn a_missing_scene_file_is_refused_before_the_rooms() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.toml");
    let o = cli("bench bakes --rooms terminator --size 32 --reference-spp 16 --out")
        .arg(dir.path().join("out"))
        .words("--scene")
        .arg(&missing)
        .run();
    common::assert_exit(&o, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing.toml"), "{err}");
    assert!(!dir.path().join("out").join("terminator").exists());
}

/// `--rooms`'s help is written by hand: it must name every room the bench knows.
#[test]
fn the_help_names_every_room() {
    let o = cli("bench bakes --help").run();
    common::assert_exit(&o, 0);
    let help = String::from_utf8_lossy(&o.stdout);
    for kind in twopass_scene::workload::RoomKind::ALL {
        assert!(
            help.contains(kind.name()),
            "{} missing from:\n{help}",
            kind.name()
        );
    }
}

#[test]
fn an_unknown_room_is_a_usage_error_naming_the_rooms() {
    let dir = tempfile::tempdir().unwrap();
    let o = cli("bench bakes --rooms kitchen --out")
        .arg(dir.path())
        .run();
    common::assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(
            "no room `kitchen`; the rooms are spheres, grazing, near-light, two-lights, terminator, \
             chrome"
        ),
        "{err}"
    );
}

#[test]
fn a_scene_file_is_measured_at_its_own_camera_in_a_folder_of_its_stem() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("lamp.toml");
    std::fs::write(
        &scene,
        "version = 1\n[camera]\nposition = [0, 1, 3]\nlook_at = [0, 0.5, 0]\nfov_y = 60\n\
         resolution = [24, 16]\n\
         [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"floor\"\nmaterial = \"w\"\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n\
         [[object]]\nname = \"lamp\"\nmaterial = \"w\"\nemission = 5\n\
         shape = { type = \"quad\", origin = [-0.5, 2, -0.5], edge_u = [1, 0, 0], edge_v = [0, 0, 1] }\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let report = common::ok_json(
        &cli("bench bakes --reference-spp 8 --min-region-pixels 20 --json")
            .words("--scene")
            .arg(&scene)
            .words("--out")
            .arg(&out)
            .run(),
    );
    let rooms = report["rooms"].as_array().unwrap();
    assert_eq!(rooms.len(), 1, "only the scene, no room");
    assert_eq!(rooms[0]["room"], "lamp");
    assert_eq!(rooms[0]["objects"], 2);
    assert!(out.join("lamp").join("lightmap.exr").is_file());
    assert!(
        out.join("lamp")
            .join("bake")
            .join("lamp.lightmap.glb")
            .is_file()
    );
}
