//! The architecture invariants of ARCHITECTURE.md, checked (rust-analyzer's `tidy` style): the
//! test reads every crate's `Cargo.toml` and its `src/` files and fails, naming the crate, the
//! file and the line, when
//!
//! - a crate depends on a workspace crate that its row of the crate table does not allow (the
//!   one-way graph: brdf at the bottom, the CLI at the top), or a crate is missing from the
//!   table;
//! - twopass-brdf depends on anything but glam;
//! - twopass-radiosity or twopass-composite imports a renderer (twopass-trace; for the
//!   compositor, any physics crate but brdf's colour);
//! - twopass-trace reaches twopass-radiosity other than through
//!   `twopass_scene::DiffuseRadiance` (a normal dependency, or a mention in `src/`; its tests
//!   and examples may build a solution through a dev-dependency);
//! - a physics crate (brdf, radiosity, trace) or the plain-data image crate touches the file
//!   system (`std::fs`, `File`, `tempfile`) or depends on a file-format crate.
//!
//! The checks are pure functions of the manifest and source text, and each is also run on a
//! small counter-example, so a check that could never fire fails too.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Crates that touch no file (ARCHITECTURE.md, "Architecture invariants"): the physics crates
/// (pure computation) and `twopass-image`, the plain pixel data the tracer fills and the
/// compositor writes.
const NO_FILES: [&str; 4] = [
    "twopass-brdf",
    "twopass-radiosity",
    "twopass-trace",
    "twopass-image",
];

/// Crates that read or write a file format (or the file system) and so belong at the I/O edge.
const FILE_CRATES: [&str; 13] = [
    "tempfile",
    "serde_json",
    "postcard",
    "gltf",
    "gltf-json",
    "ply-rs-bw",
    "crc32fast",
    "exr",
    "png",
    "toml",
    "tobj",
    "csv",
    "plotters",
];

/// The crate table of ARCHITECTURE.md: each workspace crate and the workspace crates its normal
/// dependencies may name.
const ALLOWED: [(&str, &[&str]); 8] = [
    ("twopass-brdf", &[]),
    ("twopass-image", &["twopass-brdf"]),
    ("twopass-scene", &["twopass-brdf"]),
    ("twopass-radiosity", &["twopass-brdf", "twopass-scene"]),
    (
        "twopass-bake",
        &[
            "twopass-brdf",
            "twopass-scene",
            "twopass-radiosity",
            "twopass-composite",
        ],
    ),
    (
        "twopass-trace",
        &["twopass-brdf", "twopass-scene", "twopass-image"],
    ),
    ("twopass-composite", &["twopass-brdf", "twopass-image"]),
    (
        "twopass",
        &[
            "twopass-brdf",
            "twopass-scene",
            "twopass-radiosity",
            "twopass-bake",
            "twopass-trace",
            "twopass-image",
            "twopass-composite",
        ],
    ),
];

/// A crate's manifest: its name and its dependencies by kind.
struct Manifest {
    name: String,
    normal: BTreeSet<String>,
    all: BTreeSet<String>,
}

fn parse_manifest(text: &str) -> Manifest {
    let doc: toml::Table = text.parse().expect("Cargo.toml parses as TOML");
    let name = doc["package"]["name"]
        .as_str()
        .expect("package.name")
        .to_owned();
    let keys = |section: &str| -> BTreeSet<String> {
        doc.get(section)
            .and_then(|d| d.as_table())
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default()
    };
    let normal = keys("dependencies");
    let mut all = normal.clone();
    all.extend(keys("dev-dependencies"));
    all.extend(keys("build-dependencies"));
    Manifest { name, normal, all }
}

/// One source line that breaks a rule: file, 1-based line, what.
type Violation = (PathBuf, usize, String);

/// The code of a line: everything before a `//` (comments and doc comments are prose, and may
/// name what the code must not use).
fn code(line: &str) -> &str {
    line.find("//").map_or(line, |i| &line[..i])
}

/// Lines of `text` (the file `path`) whose code contains one of `needles`.
fn find_uses(path: &Path, text: &str, needles: &[&str]) -> Vec<Violation> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let c = code(line);
        for n in needles {
            if c.contains(n) {
                out.push((
                    path.to_owned(),
                    i + 1,
                    format!("uses `{n}`: {}", line.trim()),
                ));
            }
        }
    }
    out
}

/// Everything `manifest` breaks: workspace dependencies outside its row of [`ALLOWED`], brdf's
/// glam-only rule, and file-format dependencies of a physics crate.
fn manifest_violations(manifest: &Manifest) -> Vec<String> {
    let mut out = Vec::new();
    let name = manifest.name.as_str();
    let Some((_, allowed)) = ALLOWED.iter().find(|(n, _)| *n == name) else {
        return vec![format!(
            "{name} is not in ARCHITECTURE.md's crate table (add it there and to ALLOWED)"
        )];
    };
    for dep in &manifest.normal {
        if dep.starts_with("twopass") && !allowed.contains(&dep.as_str()) {
            out.push(format!(
                "{name} depends on {dep}, which its layer may not use"
            ));
        }
    }
    if name == "twopass-brdf" {
        for dep in manifest.normal.iter().filter(|d| *d != "glam") {
            out.push(format!(
                "twopass-brdf depends on {dep}: it may depend on glam only"
            ));
        }
    }
    if matches!(name, "twopass-radiosity" | "twopass-composite")
        && manifest.all.contains("twopass-trace")
    {
        out.push(format!("{name} imports the renderer twopass-trace"));
    }
    if NO_FILES.contains(&name) {
        for dep in manifest
            .normal
            .iter()
            .filter(|d| FILE_CRATES.contains(&d.as_str()))
        {
            out.push(format!(
                "{name} touches no file but depends on the file crate {dep}: file I/O belongs \
                 to scene, composite, bake or the CLI"
            ));
        }
    }
    out
}

/// Everything the source file `path` of crate `name` breaks.
fn source_violations(name: &str, path: &Path, text: &str) -> Vec<Violation> {
    let mut out = Vec::new();
    if NO_FILES.contains(&name) {
        out.extend(find_uses(
            path,
            text,
            &["std::fs", "fs::", "File::", "OpenOptions", "tempfile"],
        ));
    }
    if name == "twopass-trace" {
        out.extend(find_uses(path, text, &["twopass_radiosity"]));
    }
    if matches!(name, "twopass-radiosity" | "twopass-composite") {
        out.extend(find_uses(path, text, &["twopass_trace"]));
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

fn crate_dirs() -> Vec<PathBuf> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("../crates");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .expect("crates/")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    dirs.sort();
    dirs
}

#[test]
fn the_workspace_keeps_its_architecture() {
    let dirs = crate_dirs();
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    for dir in &dirs {
        let text = std::fs::read_to_string(dir.join("Cargo.toml")).expect("Cargo.toml");
        let manifest = parse_manifest(&text);
        let folder = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        assert_eq!(
            manifest.name, folder,
            "folder = package name (ARCHITECTURE.md, \"Crates\")"
        );
        problems.extend(manifest_violations(&manifest));
        let mut files = Vec::new();
        rust_files(&dir.join("src"), &mut files);
        assert!(!files.is_empty(), "{} has no sources", manifest.name);
        for f in files {
            let text = std::fs::read_to_string(&f).expect("source file");
            for (path, line, what) in source_violations(&manifest.name, &f, &text) {
                problems.push(format!("{}:{line}: {what}", path.display()));
            }
        }
        seen.insert(manifest.name);
    }
    for (name, _) in ALLOWED {
        assert!(
            seen.contains(name),
            "{name} is in the table but not in crates/"
        );
    }
    assert!(
        problems.is_empty(),
        "architecture invariants broken (ARCHITECTURE.md):\n{}",
        problems.join("\n")
    );
}

#[test]
fn every_check_fires_on_a_counter_example() {
    let manifest = |name: &str, deps: &str, dev: &str| {
        parse_manifest(&format!(
            "[package]\nname = \"{name}\"\n[dependencies]\n{deps}\n[dev-dependencies]\n{dev}\n"
        ))
    };
    let count = |m: &Manifest| manifest_violations(m).len();
    // The real rows pass with what they are meant to hold.
    assert_eq!(count(&manifest("twopass-brdf", "glam = \"0.34\"", "")), 0);
    assert_eq!(
        count(&manifest(
            "twopass-trace",
            "twopass-scene = {}\nrayon = \"1\"",
            "twopass-radiosity = {}"
        )),
        0
    );
    // brdf with a second dependency.
    assert_eq!(
        count(&manifest(
            "twopass-brdf",
            "glam = \"0.34\"\nrand = \"0.9\"",
            ""
        )),
        1
    );
    // Radiosity or the compositor importing the renderer, even for tests.
    assert!(count(&manifest("twopass-radiosity", "", "twopass-trace = {}")) >= 1);
    assert!(count(&manifest("twopass-composite", "twopass-trace = {}", "")) >= 1);
    // The tracer depending on the solver directly.
    assert_eq!(
        count(&manifest("twopass-trace", "twopass-radiosity = {}", "")),
        1
    );
    // A physics crate with a file format.
    assert_eq!(
        count(&manifest(
            "twopass-radiosity",
            "twopass-scene = {}\npostcard = \"1\"",
            ""
        )),
        1
    );
    // The image crate with an image format.
    assert_eq!(
        count(&manifest(
            "twopass-image",
            "twopass-brdf = {}\nexr = \"1\"",
            ""
        )),
        1
    );
    // A crate nobody placed in the table.
    assert_eq!(count(&manifest("twopass-utils", "", "")), 1);

    let p = Path::new("src/x.rs");
    let fs = "use std::fs;\nfn f() { let _ = std::fs::read(\"a\"); }\n";
    assert_eq!(source_violations("twopass-radiosity", p, fs).len(), 3);
    assert_eq!(source_violations("twopass-image", p, fs).len(), 3);
    assert_eq!(source_violations("twopass-scene", p, fs).len(), 0);
    let solver = "use twopass_radiosity::Solution;\n";
    let hits = source_violations("twopass-trace", p, solver);
    assert_eq!(hits.len(), 1);
    assert_eq!(hits[0].1, 1, "the line is named");
    assert_eq!(
        source_violations("twopass-composite", p, "use twopass_trace::Image;").len(),
        1
    );
    // Prose may name what code must not use.
    assert!(
        source_violations("twopass-trace", p, "/// see `twopass_radiosity::Solution`").is_empty()
    );
}
