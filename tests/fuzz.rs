//! Mutation fuzzing of the scene loader and what runs on a loaded scene (issue 12).
//!
//! The real scenes of `scenes/` and the OBJ/MTL fixtures of `tests/data/` are mutated token by
//! token (numbers swapped for extreme values, words for control characters, lines deleted,
//! duplicated or truncated) with proptest, and every mutant is loaded. A load must end in a
//! scene or an error that names its file and line ([`assert_located`]); a loaded scene is traced (a few pixels of Whitted, every value finite) and
//! its radiosity solved for a few shots. Any panic fails the test, and proptest shrinks it to
//! a smallest mutation.
//!
//! CI runs a bounded number of cases from a fixed seed, so it is cheap and reproducible. By
//! hand, for a long run: `TWOPASS_FUZZ_CASES=20000 TWOPASS_FUZZ_SEED=$RANDOM cargo test
//! --release -p twopass-tests fuzz`. Every crash ever found becomes a file in `tests/data/`
//! (see its README), and [`every_fixture_loads_or_fails_cleanly`] runs them all. With
//! `TWOPASS_FUZZ_DUMP=FILE`, each case's text is written to FILE before it runs, so a case that
//! hangs can be taken from there.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};
use twopass_radiosity::{Options, Solver, Stop};
use twopass_scene::{Scene, SceneError, Warning};
use twopass_trace::{RenderProgress, RenderSettings, Whitted, WhittedSettings, render};

use crate::{data, scene_path};

/// Values that broke loaders before, or sit on a boundary of what the engine accepts.
const EXTREMES: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "0.999",
    "1e-45",
    "1e-30",
    "1e12",
    "1e13",
    "1e19",
    "1e30",
    "3e38",
    "1e39",
    "-1e39",
    "nan",
    "inf",
    "-inf",
    "4294967295",
    "-2147483649",
    "18446744073709551616",
    "9999999",
    "1/9",
    "1//2",
    "-1/-1/-1",
    "//",
    "\"\"",
    "\"\u{1b}[2J\"",
    "[]",
    "[1]",
    "[1, 2]",
    "{}",
    "\u{85}\u{85}\u{3000}",
    "",
];

/// Statements to insert: each is valid in one of the formats.
const LINES: &[&str] = &[
    "f 1 2",
    "f 1",
    "f 1 2 3 4 5 6 7",
    "vn 0 0 0",
    "vn 0 0 1",
    "v 1e19 0 0",
    "g",
    "o x",
    "usemtl nowhere",
    "mtllib /dev/zero",
    "mtllib ../../../../etc/passwd",
    "newmtl",
    "newmtl x",
    "Kd 0.5",
    "Ke 1e38",
    "Ke -1",
    "illum 99",
    "[[object]]",
    "[camera]",
    "resolution = [100000, 100000]",
    "emission = 1e30",
];

/// One edit of a text.
#[derive(Debug, Clone)]
enum Mutation {
    /// Replace the token with this index (modulo the token count) by an extreme value.
    Replace(usize, &'static str),
    /// Delete the line with this index (modulo the line count).
    DeleteLine(usize),
    /// Repeat the line with this index.
    DuplicateLine(usize),
    /// Insert a statement before the line with this index.
    Insert(usize, &'static str),
    /// Cut the text at this fraction (per mille) of its length, on a character boundary.
    Truncate(u16),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        6 => (any::<usize>(), prop::sample::select(EXTREMES)).prop_map(|(i, v)| Mutation::Replace(i, v)),
        1 => any::<usize>().prop_map(Mutation::DeleteLine),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        2 => (any::<usize>(), prop::sample::select(LINES)).prop_map(|(i, l)| Mutation::Insert(i, l)),
        1 => (0u16..1000).prop_map(Mutation::Truncate),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len().max(1);
    match *m {
        Mutation::Replace(i, value) => {
            // Tokens: maximal runs of characters that are not whitespace, brackets or commas.
            let is_sep = |c: char| c.is_whitespace() || "[]{},=".contains(c);
            let mut spans = Vec::new();
            let mut start = None;
            for (at, c) in text.char_indices() {
                match (is_sep(c), start) {
                    (false, None) => start = Some(at),
                    (true, Some(s)) => {
                        spans.push(s..at);
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(s) = start {
                spans.push(s..text.len());
            }
            if spans.is_empty() {
                return text.to_owned();
            }
            let r = spans[i % spans.len()].clone();
            format!("{}{value}{}", &text[..r.start], &text[r.end..])
        }
        Mutation::DeleteLine(i) => {
            let mut l = lines.clone();
            if !l.is_empty() {
                l.remove(i % n);
            }
            l.join("\n")
        }
        Mutation::DuplicateLine(i) => {
            let mut l = lines.clone();
            if !l.is_empty() {
                l.insert(i % n, lines[i % n]);
            }
            l.join("\n")
        }
        Mutation::Insert(i, line) => {
            let mut l = lines.clone();
            l.insert(i % (l.len() + 1), line);
            l.join("\n")
        }
        Mutation::Truncate(per_mille) => {
            let mut cut = text.len() * usize::from(per_mille) / 1000;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text[..cut].to_owned()
        }
    }
}

/// Writes the case about to run to `TWOPASS_FUZZ_DUMP`, when set.
fn dump(parts: &[&str]) {
    if let Some(path) = std::env::var_os("TWOPASS_FUZZ_DUMP") {
        std::fs::write(path, parts.join("\n=== next file ===\n")).unwrap();
    }
}

fn runner() -> TestRunner {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    TestRunner::new(Config {
        cases: env("TWOPASS_FUZZ_CASES").map_or(48, |c| c as u32),
        rng_seed: RngSeed::Fixed(env("TWOPASS_FUZZ_SEED").unwrap_or(12)),
        failure_persistence: None,
        ..Config::default()
    })
}

/// Panics unless the load error `e` says where it is: its message starts with a file of the
/// case (`origin`, a scene file, or a file in the folder `origin`) and that file's line, as
/// `FILE:LINE:`. An error about a whole file, with no statement to point at (an OBJ without
/// faces, a scene without surfaces, a file refused before it is read), names the file alone.
fn assert_located(e: &SceneError, origin: &Path) {
    let m = e.to_string();
    assert!(!m.is_empty());
    let o = origin.display().to_string();
    let rest = m
        .strip_prefix(&o)
        .unwrap_or_else(|| panic!("the error names no file of the case ({o}): {m}"));
    // In a folder: the file's name, up to the colon after it.
    let rest = match rest.strip_prefix('/') {
        Some(name) => &name[name.find(':').unwrap_or(name.len())..],
        None => rest,
    };
    let whole_file = matches!(e, SceneError::EmptyScene { .. } | SceneError::Input { .. });
    let line = rest
        .strip_prefix(':')
        .map(|r| r.chars().take_while(char::is_ascii_digit).count())
        .unwrap_or(0);
    assert!(
        line > 0 || (whole_file && rest.starts_with(": ")),
        "the error names no line: {m}"
    );
}

/// Whatever a load returned, use it as the CLI would: format the error (which must name its
/// file and line, [`assert_located`]; `origin` is the case's scene file or mesh folder), or
/// trace and solve the scene. Panics (the test's failure) on a non-finite pixel.
fn exercise(result: Result<(Scene, Vec<Warning>), SceneError>, origin: &Path) {
    let (scene, warnings) = match result {
        Err(e) => {
            assert_located(&e, origin);
            return;
        }
        Ok(s) => s,
    };
    for w in &warnings {
        assert!(!w.to_string().is_empty());
    }
    let camera = scene.camera.with_resolution(Some(4), Some(4));
    let whitted = Whitted::new(&scene, twopass_brdf::Rgb::ZERO, WhittedSettings::default());
    let settings = RenderSettings {
        samples_per_pixel: 1,
        ..RenderSettings::default()
    };
    let out = render(&scene, &camera, &whitted, &settings, &RenderProgress::new());
    let image = out.layers.composite();
    assert!(
        image.pixels().iter().all(|p| p.is_finite()),
        "a non-finite pixel reached the image"
    );
    let options = Options {
        adaptive: None,
        stop: Stop {
            max_shots: Some(4),
            ..Stop::default()
        },
        ..Options::default()
    };
    if let Ok(mut solver) = Solver::new(&scene, options) {
        solver.run(|_| std::ops::ControlFlow::Continue(()));
    }
}

#[test]
fn mutated_scenes_load_or_fail_cleanly() {
    let scenes: Vec<(PathBuf, String)> = [
        "cornell-box.toml",
        "cornell-spheres.toml",
        "cornell-materials.toml",
        "cornell-obj.toml",
    ]
    .iter()
    .map(|n| {
        let p = scene_path(n);
        let text = std::fs::read_to_string(&p).unwrap();
        (p, text)
    })
    .collect();
    let strategy = (0..scenes.len(), prop::collection::vec(mutation(), 1..4));
    runner()
        .run(&strategy, |(which, mutations)| {
            let (path, text) = &scenes[which];
            let text = mutations.iter().fold(text.clone(), |t, m| apply(&t, m));
            dump(&[&path.display().to_string(), &text]);
            // Loaded as if from the scene's own path, so its mesh paths resolve.
            exercise(twopass_scene::load_toml(&text, path), path);
            Ok(())
        })
        .unwrap();
}

#[test]
fn mutated_meshes_load_or_fail_cleanly() {
    // An OBJ and its MTL library, mutated together, loaded bare from a scratch folder.
    let read = |p: &Path| std::fs::read_to_string(p).unwrap();
    let uv_dir = tempfile::tempdir().unwrap();
    twopass_tests::write_checker_floor(uv_dir.path(), 4, [255, 255, 255], [0, 0, 0], 0.8);
    let meshes: Vec<(String, String)> = vec![
        (
            read(&scene_path("meshes/cornell-box.obj")),
            read(&scene_path("meshes/cornell-box.mtl")),
        ),
        (
            read(&data("mtl-one-value.obj")),
            read(&data("mtl-one-value.mtl")),
        ),
        (read(&data("unreferenced-normal.obj")), String::new()),
        (read(&data("degenerate.obj")), String::new()),
        // With texture coordinates: the textured floor (its `map_Kd` PNG in the folder), and
        // the box with a `vt` per corner (lightmap atlases are cut from these).
        (
            read(&uv_dir.path().join("floor.obj")),
            read(&uv_dir.path().join("floor.mtl")),
        ),
        (
            with_texcoords(&read(&scene_path("meshes/cornell-box.obj"))),
            read(&scene_path("meshes/cornell-box.mtl")),
        ),
    ];
    let dir = uv_dir;
    let strategy = (
        0..meshes.len(),
        prop::collection::vec(mutation(), 0..3),
        prop::collection::vec(mutation(), 0..3),
    );
    runner()
        .run(&strategy, |(which, obj_edits, mtl_edits)| {
            let (obj, mtl) = &meshes[which];
            let obj = obj_edits.iter().fold(obj.clone(), |t, m| apply(&t, m));
            let mtl = mtl_edits.iter().fold(mtl.clone(), |t, m| apply(&t, m));
            dump(&[&obj, &mtl]);
            // Every library the OBJ may name gets the mutated text.
            for line in obj.lines() {
                if let Some(name) = line.strip_prefix("mtllib ") {
                    let p = dir.path().join(name.trim());
                    if p.starts_with(dir.path()) && p.parent() == Some(dir.path()) {
                        std::fs::write(&p, &mtl).unwrap();
                    }
                }
            }
            let path = dir.path().join("mesh.obj");
            std::fs::write(&path, &obj).unwrap();
            exercise(twopass_scene::load(&path), dir.path());
            Ok(())
        })
        .unwrap();
}

/// `obj` with a texture coordinate per vertex (`vt`, from its x and z) and every face's
/// corners given as `v/vt`.
fn with_texcoords(obj: &str) -> String {
    let mut vt = String::new();
    let mut faces = String::new();
    for line in obj.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f32> = words.filter_map(|w| w.parse().ok()).collect();
                if let [x, _, z, ..] = c[..] {
                    vt += &format!("vt {} {}\n", x / 600.0, z / 600.0);
                }
                faces += line;
            }
            Some("f") => {
                faces += "f";
                for w in words {
                    let v = w.split('/').next().unwrap_or(w);
                    faces += &format!(" {v}/{v}");
                }
            }
            _ => faces += line,
        }
        faces += "\n";
    }
    vt + &faces
}

/// Every fixture (and every crash the fuzzing ever found, kept here) loads or fails with an
/// error, and what loads traces to finite pixels.
#[test]
fn every_fixture_loads_or_fails_cleanly() {
    let mut n = 0;
    for entry in std::fs::read_dir(data("")).unwrap() {
        let path = entry.unwrap().path();
        if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("toml" | "obj")
        ) {
            exercise(twopass_scene::load(&path), path.parent().unwrap());
            n += 1;
        }
    }
    assert!(n > 30, "only {n} fixtures found");
}
