//! Every `twopass ...` line in README.md's ```sh blocks runs and exits 0, so the examples
//! cannot rot: a new README line is picked up and run without touching this file.
//!
//! Each line runs in README order (a `bake` line makes the bake file a later `render --bake`
//! line loads) from the repository root, on the built binary, with every output sent to one
//! temporary directory: the value of `-o`/`--output`/`--plot` and every path under a
//! command's default output folder (`bake/`, `compare/`, `tradeoff/`, `brdf-check/`) are
//! moved into it, and a command that writes without `--output` gets `--output TMP/<its
//! default folder>`. Each command is shrunk to a few seconds by [`SHRINK`] (flags the README
//! line already sets are left as written); a command without an entry runs as written. A
//! `view` line needs three.js (`npm ci --prefix crates/twopass/view`): without it the line is
//! skipped with a note, unless `CI` is set.

use std::path::Path;
use std::process::Command;

use crate::common::repo;

/// How one command is made small: the flags added (each unless the line sets it already) and,
/// for list-valued flags whose README values take minutes, the values run instead.
struct Shrink {
    /// The words after `twopass` that name the command.
    command: &'static [&'static str],
    /// Flags and values added, as (flag, value or "" for a switch).
    add: &'static [(&'static str, &'static str)],
    /// (flag, value used instead of the README's).
    replace: &'static [(&'static str, &'static str)],
    /// The folder the command writes into without `--output` (None: it writes nothing there).
    default_output: Option<&'static str>,
}

/// A coarse radiosity mesh solved to 1 %: seconds instead of minutes on the Cornell box.
const COARSE_SOLVE: [(&str, &str); 3] = [
    ("--element-size", "80"),
    ("--patch-size", "150"),
    ("--unshot", "1e-2"),
];

const SHRINK: &[Shrink] = &[
    Shrink {
        command: &["info"],
        add: &[],
        replace: &[],
        default_output: None,
    },
    // Draft quality, 24 pixels wide, 1 spp (4 for the reference).
    Shrink {
        command: &["compare"],
        add: &[
            ("--quick", ""),
            ("--width", "24"),
            ("--spp", "1"),
            ("--reference-spp", "4"),
        ],
        replace: &[],
        default_output: Some("compare"),
    },
    Shrink {
        command: &["bake"],
        add: &COARSE_SOLVE,
        replace: &[],
        default_output: Some("bake"),
    },
    // 24 pixels wide; 1 spp unless a preset sets it (a preset conflicts with --spp).
    Shrink {
        command: &["render"],
        add: &[("--width", "24")],
        replace: &[],
        default_output: Some(""),
    },
    // A coarse quadrature (the default 1024 cells proves 1e-3 accuracy and takes ~10 s).
    Shrink {
        command: &["brdf-check"],
        add: &[("--resolution", "64")],
        replace: &[],
        default_output: Some("brdf-check"),
    },
    // The smoke-test sweep, 16 pixels wide, a 16 spp reference.
    Shrink {
        command: &["bench", "tradeoff"],
        add: &[
            ("--quick", ""),
            ("--width", "16"),
            ("--reference-spp", "16"),
        ],
        replace: &[],
        default_output: Some("tradeoff"),
    },
    // Two small element counts (instead of up to 200k) solved to 1 %; generated scenes of 500
    // and 1000 triangles instead of up to a million.
    Shrink {
        command: &["bench", "radiosity"],
        add: &[("--unshot", "1e-2"), ("--elements", "200,400")],
        replace: &[("--generate", "500,1000"), ("--elements", "200,400")],
        default_output: None,
    },
    Shrink {
        command: &["bench", "render"],
        add: &[("--spp", "1"), ("--frames", "2"), ("--width", "24")],
        replace: &[],
        default_output: None,
    },
    // The README's line is small already (one room, 32 pixels, a 16-spp reference); its
    // folder goes to the temporary directory.
    Shrink {
        command: &["bench", "bakes"],
        add: &[],
        replace: &[],
        default_output: Some("bench-bakes"),
    },
    // 1000 rays measured for 10 ms; a generated scene of 10k triangles instead of 100k.
    Shrink {
        command: &["bench", "rays"],
        add: &[("--rays", "1000"), ("--seconds", "0.01")],
        replace: &[("--generate", "10000")],
        default_output: None,
    },
];

/// Flags whose value is a file or folder the command writes.
const OUTPUT_FLAGS: [&str; 3] = ["-o", "--output", "--plot"];

/// The `twopass` lines of README.md's ```sh blocks, comments removed, as words.
fn readme_commands() -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(repo("README.md")).expect("README.md reads");
    let mut in_sh = false;
    let mut commands = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        let Some(rest) = line.strip_prefix("twopass ").filter(|_| in_sh) else {
            continue;
        };
        let words: Vec<String> = rest
            .split_whitespace()
            .take_while(|w| !w.starts_with('#'))
            .map(str::to_owned)
            .collect();
        assert!(
            !words
                .iter()
                .any(|w| w.contains(['"', '\'', '\\', '$', '|', '>', '<', ';', '&'])),
            "README line `{line}`: quoting and shell syntax are not parsed here"
        );
        commands.push(words);
    }
    commands
}

/// The shrink rule of a command line: the longest command prefix that matches.
fn shrink_of(words: &[String]) -> Option<&'static Shrink> {
    SHRINK
        .iter()
        .filter(|s| {
            s.command.len() <= words.len() && s.command.iter().zip(words).all(|(a, b)| a == b)
        })
        .max_by_key(|s| s.command.len())
}

/// The arguments a README line runs with here (see the module documentation).
fn test_args(words: &[String], tmp: &Path) -> Vec<String> {
    let shrink = shrink_of(words);
    let default_dirs: Vec<&str> = SHRINK.iter().filter_map(|s| s.default_output).collect();
    let in_tmp = |w: &str| tmp.join(w).to_string_lossy().into_owned();
    let mut args: Vec<String> = Vec::with_capacity(words.len() + 8);
    let mut has_output = false;
    let mut i = 0;
    while i < words.len() {
        let w = &words[i];
        if OUTPUT_FLAGS.contains(&w.as_str()) && i + 1 < words.len() {
            has_output |= w != "--plot";
            args.extend([w.clone(), in_tmp(&words[i + 1])]);
            i += 2;
            continue;
        }
        if let Some(&(flag, value)) = shrink.and_then(|s| s.replace.iter().find(|r| r.0 == w)) {
            args.extend([flag.to_owned(), value.to_owned()]);
            i += 2;
            continue;
        }
        let under_output = default_dirs
            .iter()
            .any(|d| !d.is_empty() && w.starts_with(&format!("{d}/")));
        args.push(if under_output { in_tmp(w) } else { w.clone() });
        i += 1;
    }
    if let Some(s) = shrink {
        let preset = words.iter().any(|w| w == "--preset");
        // The planner chooses the samples itself (`--spp` conflicts with its target).
        let planned = words.iter().any(|w| w == "--target-error");
        // A render that solves (no bake, no preset) gets the coarse mesh.
        let solves = s.command == ["render"] && !preset && !words.iter().any(|w| w == "--bake");
        let mut add: Vec<(&str, &str)> = s.add.to_vec();
        if s.command == ["render"] && !preset && !planned {
            add.push(("--spp", "1"));
        }
        if solves {
            add.extend(COARSE_SOLVE);
        }
        for (flag, value) in add {
            if words.iter().any(|w| w == flag) {
                continue;
            }
            args.push(flag.to_owned());
            if !value.is_empty() {
                args.push(value.to_owned());
            }
        }
        if let (Some(dir), false) = (s.default_output, has_output) {
            let mut dir = in_tmp(dir);
            if !dir.ends_with('/') {
                dir.push('/');
            }
            args.extend(["--output".to_owned(), dir]);
        }
    }
    args
}

#[test]
fn every_readme_command_runs() {
    let commands = readme_commands();
    assert!(
        commands.len() >= 10,
        "README.md's usage block lost its examples: {commands:?}"
    );
    let tmp = tempfile::tempdir().unwrap();
    let three = repo("crates/twopass/view/node_modules/three/package.json");
    for words in &commands {
        // `view` copies three.js from its npm package: .ci/run installs it; elsewhere a
        // checkout without it skips the line with a note.
        if words.first().is_some_and(|w| w == "view") && !three.exists() {
            assert!(
                std::env::var_os("CI").is_none(),
                "{}: missing; .ci/run installs it (npm ci --prefix crates/twopass/view)",
                three.display()
            );
            eprintln!(
                "note: README `twopass {}` not run: npm ci --prefix crates/twopass/view installs three.js",
                words.join(" ")
            );
            continue;
        }
        let args = test_args(words, tmp.path());
        let started = std::time::Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_twopass"))
            .args(&args)
            .current_dir(repo(""))
            .env("CI", "1")
            .output()
            .expect("the binary runs");
        assert_eq!(
            out.status.code(),
            Some(0),
            "README: `twopass {}`\nran as: twopass {}\nstderr: {}",
            words.join(" "),
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
        eprintln!(
            "{:5.1} s  twopass {}",
            started.elapsed().as_secs_f64(),
            words.join(" ")
        );
    }
}

#[test]
fn outputs_go_to_the_temporary_folder_and_commands_shrink() {
    let tmp = Path::new("/t");
    let words = |s: &str| s.split(' ').map(str::to_owned).collect::<Vec<_>>();
    assert_eq!(
        test_args(&words("bake scenes/a.toml -o bake/"), tmp).join(" "),
        "bake scenes/a.toml -o /t/bake/ --element-size 80 --patch-size 150 --unshot 1e-2"
    );
    assert_eq!(
        test_args(&words("render scenes/a.toml --bake bake/a.bake --png"), tmp).join(" "),
        "render scenes/a.toml --bake /t/bake/a.bake --png --width 24 --spp 1 --output /t/"
    );
    assert_eq!(
        test_args(
            &words("bench radiosity --generate 10000,100000 --plot scale.png"),
            tmp
        )
        .join(" "),
        "bench radiosity --generate 500,1000 --plot /t/scale.png --unshot 1e-2 --elements 200,400"
    );
    assert_eq!(
        test_args(&words("compare scenes/a.toml --quick"), tmp).join(" "),
        "compare scenes/a.toml --quick --width 24 --spp 1 --reference-spp 4 --output /t/compare/"
    );
}
