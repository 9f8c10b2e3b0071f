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

/// Rewrites the manifest `dir/<stem>.manifest.json` so it seals its files as they are now
/// (their sizes and CRC-32), keeping only the records whose file name `keep` accepts: for the
/// tests of the readers' own checks behind a manifest that lets a changed file through.
pub fn reseal(dir: &Path, stem: &str, keep: impl Fn(&str) -> bool) {
    let path = dir.join(format!("{stem}.manifest.json"));
    let mut manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let files = manifest["files"]
        .as_array_mut()
        .expect("a manifest lists files");
    files.retain(|f| {
        let name = Path::new(f["path"].as_str().unwrap()).file_name().unwrap();
        keep(&name.to_string_lossy())
    });
    for f in files.iter_mut() {
        let name = Path::new(f["path"].as_str().unwrap()).file_name().unwrap();
        let member = dir.join(name);
        // A special file (a FIFO) keeps its record: the check refuses it before reading.
        if std::fs::metadata(&member).is_ok_and(|m| m.is_file()) {
            let bytes = std::fs::read(&member).unwrap();
            f["bytes"] = bytes.len().into();
            f["crc32"] = crc32fast::hash(&bytes).into();
        }
    }
    std::fs::write(&path, serde_json::to_vec_pretty(&manifest).unwrap()).unwrap();
}

/// Runs `twopass args` with standard error captured, killing it after 60 s (a test of a hang
/// must not hang: it panics naming the command).
pub fn run_soon<S: AsRef<OsStr> + std::fmt::Debug>(args: &[S]) -> Output {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let mut child = Command::new(env!("CARGO_BIN_EXE_twopass"))
        .args(args)
        .env("CI", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("twopass {args:?} still running after 60 s");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}
