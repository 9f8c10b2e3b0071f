//! The resource-limit matrix: every size, count and special file a user can give is bounded,
//! with exit code 2 for an option and 1 for an input, a message naming the problem, and never
//! a panic (101), an abort (134) or unbounded work.

use crate::common;

use std::process::{Command, Stdio};

use crate::common::{repo, twopass};

/// Runs `twopass args` and checks its exit code and that stderr holds every one of `words`.
fn expect(args: &[&str], code: i32, words: &[&str]) {
    let out = twopass(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(code),
        "twopass {args:?}: exit {:?}, stderr:\n{stderr}",
        out.status.code()
    );
    for w in words {
        assert!(
            stderr.contains(w),
            "twopass {args:?}: stderr lacks `{w}`:\n{stderr}"
        );
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}

fn cornell() -> String {
    repo("scenes/cornell-box.toml").display().to_string()
}

fn data(name: &str) -> String {
    repo("tests/data").join(name).display().to_string()
}

#[test]
fn options_out_of_range_are_usage_errors() {
    let scene = cornell();
    let s = scene.as_str();
    let out = std::env::temp_dir().join("twopass-limits-never-written.exr");
    let o = out.to_str().unwrap();
    for (args, words) in [
        (
            vec!["render", s, "--exposure", "nan", "--png", "-o", o],
            vec!["--exposure"],
        ),
        (
            vec!["render", s, "--exposure", "inf", "-o", o],
            vec!["--exposure"],
        ),
        (
            vec!["render", s, "--exposure", "-1e30", "-o", o],
            vec!["--exposure"],
        ),
        (vec!["render", s, "--width", "65537"], vec!["--width"]),
        (
            vec![
                "render", s, "--width", "65536", "--height", "65536", "-o", o,
            ],
            vec!["65536 x 65536", "33554432 pixels"],
        ),
        // One side alone keeps the square scene's aspect: 8192 x 8192 is too many pixels.
        (vec!["info", s, "--width", "8192"], vec!["8192 x 8192"]),
        (vec!["bake", s, "--unshot", "nan"], vec!["--unshot"]),
        (vec!["bake", s, "--unshot", "1"], vec!["--unshot"]),
        (vec!["bake", s, "--patch-size", "0"], vec!["--patch-size"]),
        (vec!["bake", s, "--patch-size", "nan"], vec!["--patch-size"]),
        (
            vec!["bake", s, "--element-size", "0"],
            vec!["--element-size"],
        ),
        (
            vec!["bake", s, "--visibility-rays", "4294967295,4294967295"],
            vec!["--visibility-rays", "4096"],
        ),
        (
            vec!["bake", s, "--residual-samples", "4294967295"],
            vec!["--residual-samples", "100000"],
        ),
        (
            vec!["bench", "rays", s, "--seconds", "1e300"],
            vec!["--seconds"],
        ),
        // Valid syntax, but the scene's area makes it too many elements: refused up front.
        (
            vec!["bake", s, "--element-size", "1e-9"],
            vec!["element_size", "4000000"],
        ),
    ] {
        expect(&args, 2, &words);
    }
    common::assert_absent(&out, "no render was written");
}

#[test]
fn inputs_beyond_the_limits_are_input_errors() {
    for (file, words) in [
        (
            "huge-resolution.toml",
            vec!["huge-resolution.toml", "100000 x 100000"],
        ),
        (
            "huge-sphere.toml",
            vec!["huge-sphere.toml", "`ball`", "1e19"],
        ),
        ("huge-power.toml", vec!["huge-power.toml", "emitted power"]),
        ("huge-vertex.obj", vec!["huge-vertex.obj", "1e19"]),
        (
            "device-obj.toml",
            vec!["device-obj.toml", "/dev/zero", "not a regular file"],
        ),
        ("no-faces.obj", vec!["no-faces.obj", "no faces"]),
        (
            "face-two-corners.obj",
            vec!["face-two-corners.obj:6", "corner"],
        ),
        (
            "usemtl-undefined.obj",
            vec!["usemtl-undefined.obj:6", "usemtl nowhere"],
        ),
        ("mtl-two-values.obj", vec!["mtl-two-values.mtl:2", "`Kd`"]),
        (
            "mtl-negative-ke.obj",
            vec!["mtl-negative-ke.mtl:5", "MTL material `glow`"],
        ),
    ] {
        expect(&["info", &data(file)], 1, &words);
    }
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_as_scenes() {
    let dir = tempfile::tempdir().unwrap();
    for device in ["/dev/zero", "/dev/urandom"] {
        let link = dir.path().join(format!(
            "{}.toml",
            std::path::Path::new(device)
                .file_name()
                .unwrap()
                .to_str()
                .unwrap()
        ));
        std::os::unix::fs::symlink(device, &link).unwrap();
        expect(
            &["info", link.to_str().unwrap()],
            1,
            &["not a regular file"],
        );
    }
    // Every other file a command reads: a bake, a presets file.
    let scene = cornell();
    expect(
        &[
            "render",
            &scene,
            "--method",
            "radiosity",
            "--bake",
            "/dev/zero",
        ],
        1,
        &["/dev/zero", "not a regular file"],
    );
    expect(
        &[
            "render",
            &scene,
            "--preset",
            "preview",
            "--presets",
            "/dev/zero",
        ],
        1,
        &["/dev/zero", "not a regular file"],
    );
}

#[test]
fn an_output_under_a_file_names_the_problem() {
    let scene = cornell();
    let bad = format!("{scene}/x.exr");
    expect(
        &["render", &scene, "--width", "8", "--spp", "1", "-o", &bad],
        1,
        &["cornell-box.toml", "not a directory"],
    );
}

#[test]
fn confined_reads_refuse_a_mesh_outside_the_folder() {
    let scene = data("outside-folder.toml");
    expect(
        &["info", &scene, "--confine"],
        1,
        &["outside the scene's folder"],
    );
    let out = twopass(&["info", &scene, "-q"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "unconfined, the same scene loads"
    );
}

#[test]
fn control_characters_never_reach_the_terminal() {
    let out = twopass(&["info", &data("control-name.toml")]);
    assert_eq!(out.status.code(), Some(0));
    // The emitter's name is printed, escaped.
    assert!(String::from_utf8_lossy(&out.stdout).contains("a\\u{1b}[2Jb"));
    for stream in [&out.stdout, &out.stderr] {
        assert!(
            !stream.contains(&0x1b),
            "an escape character was printed raw: {}",
            String::from_utf8_lossy(stream)
        );
    }
}

#[cfg(unix)]
#[test]
fn a_closed_or_full_stdout_is_no_panic() {
    // The reader goes away at once (`| head -0`): stop quietly.
    let mut child = Command::new(env!("CARGO_BIN_EXE_twopass"))
        .args(["info", &cornell()])
        .env("CI", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("error"),
        "{stderr}"
    );
    // A full device: the write error is reported, exit 1.
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    if let Ok(full) = full {
        let out = Command::new(env!("CARGO_BIN_EXE_twopass"))
            .args(["info", &cornell()])
            .env("CI", "1")
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("standard output"), "{stderr}");
    }
}

#[test]
fn a_presets_file_cannot_ask_for_more_than_the_options() {
    let text = std::fs::read_to_string(repo("scenes/cornell-box.presets.toml")).unwrap();
    let first = text.find("depth = ").expect("a preset has a depth");
    let end = first + text[first..].find('\n').unwrap();
    let bad = format!("{}depth = 4000000000{}", &text[..first], &text[end..]);
    let dir = tempfile::tempdir().unwrap();
    let presets = dir.path().join("bad.presets.toml");
    std::fs::write(&presets, bad).unwrap();
    let name_at = text[..first].rfind("name = \"").unwrap() + 8;
    let name = &text[name_at..name_at + text[name_at..].find('"').unwrap()];
    expect(
        &[
            "render",
            &cornell(),
            "--preset",
            name,
            "--presets",
            presets.to_str().unwrap(),
            "-o",
            dir.path().join("x.exr").to_str().unwrap(),
        ],
        1,
        &["bad.presets.toml", name, "depth 4000000000", "at most 64"],
    );
}
