//! Helpers every CLI test file shares: repository paths and running the binary as CI does.
// Each test file is its own crate and uses only some of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A path relative to the repository root.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

/// Runs `twopass` with `args` as CI would (no progress bars) and waits for it.
pub fn twopass(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twopass"))
        .args(args)
        .env("CI", "1")
        .output()
        .expect("the binary runs")
}

/// Runs `twopass render` of the Cornell box (`scenes/cornell-box.toml`) with `method`, `width`
/// pixels across and `spp` samples per pixel, then the `extra` arguments (the output, ...).
pub fn render_box(method: &str, width: u32, spp: u32, extra: &[&str]) -> Output {
    let scene = repo("scenes/cornell-box.toml");
    let (width, spp) = (width.to_string(), spp.to_string());
    let args = ["render", scene.to_str().unwrap(), "--method", method];
    twopass(&[&args[..], &["--width", &width, "--spp", &spp], extra].concat())
}

/// Runs `twopass bake` of the Cornell box (`scenes/cornell-box.toml`) with `--output dir`, then
/// the `extra` arguments (formats, solver settings, ...).
pub fn bake_box(dir: &Path, extra: &[&str]) -> Output {
    let scene = repo("scenes/cornell-box.toml");
    let args = [
        "bake",
        scene.to_str().unwrap(),
        "--output",
        dir.to_str().unwrap(),
    ];
    twopass(&[&args[..], extra].concat())
}

/// Asserts that `out` exited with `code`, showing its stderr when it did not.
#[track_caller]
pub fn assert_exit(out: &Output, code: i32) {
    assert_eq!(
        out.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Asserts that `out` is a successful run (exit code 0), showing its stderr when it is not.
#[track_caller]
pub fn assert_ok(out: &Output) {
    assert_exit(out, 0);
}

/// Asserts that `out` succeeded and parses its standard output as the JSON summary.
#[track_caller]
pub fn ok_json(out: &Output) -> serde_json::Value {
    assert_ok(out);
    serde_json::from_slice(&out.stdout).expect("the summary is JSON")
}

/// The `method` of every row of a JSON report, in order.
pub fn row_methods(report: &serde_json::Value) -> Vec<&str> {
    report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect()
}

/// Bakes the Cornell box with a 5 mm lightmap into `dir` (the `.bake` and the lightmap files
/// of one solve).
pub fn bake_cornell_lightmap(dir: &Path) {
    let lightmap = [
        "--format",
        "bake",
        "--lightmap",
        "--texel-size",
        "5",
        "--quiet",
    ];
    assert_ok(&bake_box(dir, &lightmap));
}
