//! Helpers every CLI test file shares: repository paths and running the binary as CI does.

use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The Cornell box, relative to the repository root (see [`repo`]).
pub const BOX: &str = "scenes/cornell-box.toml";

/// The Cornell box with a mirror and a glass sphere, relative to the repository root.
pub const SPHERES: &str = "scenes/cornell-spheres.toml";

/// A path relative to the repository root.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

/// Runs `twopass` with `args` as CI would (no progress bars) and waits for it.
pub fn twopass<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twopass"))
        .args(args)
        .env("CI", "1")
        .output()
        .expect("the binary runs")
}

/// A `twopass` command line, built in the order it is read: words (subcommands, flags and
/// their values) and paths, run by [`twopass`].
pub struct Cli(Vec<OsString>);

/// The command line `twopass <words>`; see [`Cli::words`].
pub fn cli(words: &str) -> Cli {
    Cli(Vec::new()).words(words)
}

impl Cli {
    /// Appends `words` split at white space: flags and values, never a path (see [`Cli::path`]).
    pub fn words(mut self, words: &str) -> Self {
        self.0.extend(words.split_whitespace().map(OsString::from));
        self
    }

    /// Appends one argument as it is: a path (which may hold spaces) or a computed value.
    pub fn arg(mut self, arg: impl AsRef<OsStr>) -> Self {
        self.0.push(arg.as_ref().to_owned());
        self
    }

    /// Appends `--output path`.
    pub fn output(self, path: impl AsRef<OsStr>) -> Self {
        self.words("--output").arg(path)
    }

    /// Appends each of `args` as it is.
    pub fn args<S: AsRef<OsStr>>(mut self, args: &[S]) -> Self {
        self.0.extend(args.iter().map(|a| a.as_ref().to_owned()));
        self
    }

    /// Runs the command line and waits for it.
    pub fn run(&self) -> Output {
        twopass(&self.0)
    }
}

/// `twopass render` of the Cornell box (`scenes/cornell-box.toml`) with `method`, `width`
/// pixels across and `spp` samples per pixel; the caller adds the rest (the output, ...).
pub fn render_box(method: &str, width: u32, spp: u32) -> Cli {
    cli("render")
        .arg(repo(BOX))
        .words(&format!("--method {method} --width {width} --spp {spp}"))
}

/// `twopass bake` of the Cornell box (`scenes/cornell-box.toml`) with `--output dir`; the caller
/// adds the rest (formats, solver settings, ...).
pub fn bake_box(dir: &Path) -> Cli {
    cli("bake").arg(repo(BOX)).output(dir)
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

/// Asserts that nothing exists at `path`, naming it and `why` it must not when it does.
#[track_caller]
pub fn assert_absent(path: &Path, why: &str) {
    assert!(!path.exists(), "{} exists: {why}", path.display());
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
/// of one solve). Without the final gather: the tests that use it check the files and their
/// read-back against the solution they hold (the gather is checked in `lightmap::` and in the
/// workspace's `gathered_bake` and `terminator` tests).
pub fn bake_cornell_lightmap(dir: &Path) {
    let lightmap = "--format bake --lightmap --texel-size 5 --gather off --quiet";
    assert_ok(&bake_box(dir).words(lightmap).run());
}
