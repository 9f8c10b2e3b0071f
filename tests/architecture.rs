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
//!   system (`std::fs`, `File`, `tempfile`) or depends on a file-format crate;
//! - a source file under `crates/*/src` is longer than [`MAX_FILE_LINES`], its test code
//!   excepted (a file that long holds more than one job: split it into a folder module);
//! - the files of one crate import each other in a circle (the `use crate::` / `use super::`
//!   graph between files, re-exports followed to the file that defines the name).
//!
//! The checks are pure functions of the manifest and source text, and each is also run on a
//! small counter-example, so a check that could never fire fails too.

use std::collections::{BTreeMap, BTreeSet};
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

/// The most lines a file under `crates/*/src` may hold before its first top-level
/// `#[cfg(test)]` (ARCHITECTURE.md, "Invariants": one job per file).
const MAX_FILE_LINES: usize = 700;

/// A module of a crate by its path from the crate root: `[]` for `lib.rs` or `main.rs`,
/// `["accel", "ray"]` for `accel/ray.rs`, `["accel"]` for `accel/mod.rs` or `accel.rs`.
type ModPath = Vec<String>;

/// The module that the file `file` under the crate's `src` folder defines.
fn module_path(src: &Path, file: &Path) -> ModPath {
    let rel = file.strip_prefix(src).expect("a file under src/");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    let root = parts.is_empty() && matches!(stem, "lib" | "main");
    if stem != "mod" && !root {
        parts.push(stem.to_owned());
    }
    parts
}

/// The part of a file that is not test code: everything before its first top-level
/// `#[cfg(test)]` (tests sit at the end of a file, after the code they test).
fn non_test(text: &str) -> &str {
    text.find("\n#[cfg(test)]").map_or(text, |i| &text[..i + 1])
}

/// The files of `files` (module path to text) longer than [`MAX_FILE_LINES`] outside their
/// test code, with their line counts.
fn long_files(files: &BTreeMap<ModPath, String>) -> Vec<(ModPath, usize)> {
    files
        .iter()
        .map(|(m, text)| (m.clone(), non_test(text).lines().count()))
        .filter(|(_, n)| *n > MAX_FILE_LINES)
        .collect()
}

/// The top-level `use` declarations of a file's non-test code, each as the text between `use`
/// and `;`, and whether it is public (`pub`, `pub(crate)`, `pub(super)`: a re-export).
fn use_declarations(text: &str) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    let mut open: Option<(String, bool)> = None;
    for line in non_test(text).lines() {
        let c = code(line);
        if let Some((tree, public)) = open.as_mut() {
            tree.push(' ');
            tree.push_str(c);
            if tree.contains(';') {
                let tree = tree.split(';').next().unwrap_or_default().to_owned();
                out.push((tree, *public));
                open = None;
            }
            continue;
        }
        let (rest, public) = if let Some(r) = c.strip_prefix("use ") {
            (r, false)
        } else if let Some(r) = c.strip_prefix("pub ") {
            match r.strip_prefix("use ") {
                Some(r) => (r, true),
                None => continue,
            }
        } else if c.starts_with("pub(") {
            match c.split_once(") use ") {
                Some((_, r)) => (r, true),
                None => continue,
            }
        } else {
            continue;
        };
        match rest.split_once(';') {
            Some((tree, _)) => out.push((tree.to_owned(), public)),
            None => open = Some((rest.to_owned(), public)),
        }
    }
    out
}

/// A use tree (`crate::a::{b::C, d as E, self}`) expanded into its paths, each with the name
/// it binds: `[("crate::a::b::C", "C"), ("crate::a::d", "E"), ("crate::a", "a")]`.
fn expand_use_tree(tree: &str) -> Vec<(String, String)> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let (path, alias) = match tree.split_once(" as ") {
            Some((p, a)) => (p.trim(), Some(a.trim())),
            None => (tree, None),
        };
        let path: String = path.split_whitespace().collect();
        let name = alias.unwrap_or_else(|| path.rsplit("::").next().unwrap_or_default());
        return vec![(path.clone(), name.to_owned())];
    };
    let prefix: String = tree[..open].split_whitespace().collect();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut items = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, ch) in inner.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items.push(&inner[start..]);
    let mut out = Vec::new();
    for item in items.into_iter().map(str::trim).filter(|i| !i.is_empty()) {
        if item == "self" {
            let path = prefix.trim_end_matches("::").to_owned();
            let name = path.rsplit("::").next().unwrap_or_default().to_owned();
            out.push((path, name));
        } else {
            for (path, name) in expand_use_tree(item) {
                out.push((format!("{prefix}{path}"), name));
            }
        }
    }
    out
}

/// The module a path names, from `module` (the file whose code holds it): `crate::`, `super::`
/// and `self::` paths and paths that start with a child module; `None` for another crate's.
/// Segments are followed down through module files; an item name is then followed through
/// the module's re-exports to the file that defines it.
fn resolve(
    files: &BTreeMap<ModPath, String>,
    module: &ModPath,
    path: &str,
    depth: usize,
) -> Option<ModPath> {
    let mut segments = path.split("::").filter(|s| !s.is_empty()).peekable();
    let mut at: ModPath = match *segments.peek()? {
        "crate" => {
            segments.next();
            Vec::new()
        }
        "self" => {
            segments.next();
            module.clone()
        }
        "super" => {
            let mut at = module.clone();
            while segments.next_if_eq(&"super").is_some() {
                at.pop();
            }
            at
        }
        first => {
            let mut child = module.clone();
            child.push(first.to_owned());
            if !files.contains_key(&child) {
                return None;
            }
            module.clone()
        }
    };
    for segment in segments {
        let mut child = at.clone();
        child.push(segment.to_owned());
        if files.contains_key(&child) {
            at = child;
            continue;
        }
        if depth < 8 {
            let exported = use_declarations(&files[&at])
                .into_iter()
                .filter(|(_, public)| *public)
                .flat_map(|(tree, _)| expand_use_tree(&tree))
                .find(|(_, name)| name == segment);
            if let Some((target, _)) = exported {
                return resolve(files, &at, &target, depth + 1).or(Some(at));
            }
        }
        break;
    }
    Some(at)
}

/// The import graph of one crate's files: for each module, the other modules whose items its
/// non-test code names by `crate::` anywhere or by `super::`/`self::`/child paths in its
/// top-level `use` declarations (`mod x;` declares, it does not import).
fn import_graph(files: &BTreeMap<ModPath, String>) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let mut graph = BTreeMap::new();
    for (module, text) in files {
        let mut paths: Vec<String> = use_declarations(text)
            .into_iter()
            .flat_map(|(tree, _)| expand_use_tree(&tree))
            .map(|(path, _)| path)
            .collect();
        for line in non_test(text).lines() {
            let c = code(line);
            let mut rest = c;
            while let Some(i) = rest.find("crate::") {
                let before = rest[..i].chars().next_back();
                let tail = &rest[i..];
                let end = tail
                    .find(|ch: char| !(ch.is_alphanumeric() || ch == '_' || ch == ':'))
                    .unwrap_or(tail.len());
                // A bare `crate::` opens a grouped `use` whose paths the use tree gives.
                let path = &tail[..end];
                if path != "crate::" && !before.is_some_and(|b| b.is_alphanumeric() || b == '_') {
                    paths.push(path.to_owned());
                }
                rest = &tail[end.max(1)..];
            }
        }
        let targets: BTreeSet<ModPath> = paths
            .iter()
            .filter_map(|p| resolve(files, module, p, 0))
            .filter(|t| t != module)
            .collect();
        graph.insert(module.clone(), targets);
    }
    graph
}

/// The circles of `graph`: each strongly connected set of more than one module (Tarjan).
fn circles(graph: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<Vec<ModPath>> {
    struct Walk<'g> {
        graph: &'g BTreeMap<ModPath, BTreeSet<ModPath>>,
        index: BTreeMap<&'g ModPath, usize>,
        low: BTreeMap<&'g ModPath, usize>,
        stack: Vec<&'g ModPath>,
        on_stack: BTreeSet<&'g ModPath>,
        found: Vec<Vec<ModPath>>,
    }
    impl<'g> Walk<'g> {
        fn visit(&mut self, v: &'g ModPath) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.graph.get(v).into_iter().flatten() {
                if !self.graph.contains_key(w) {
                    continue;
                }
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.on_stack.contains(w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut set = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    set.push(w.clone());
                    if w == v {
                        break;
                    }
                }
                if set.len() > 1 {
                    set.sort();
                    self.found.push(set);
                }
            }
        }
    }
    let mut walk = Walk {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !walk.index.contains_key(v) {
            walk.visit(v);
        }
    }
    walk.found
}

/// A module path as its file-like name for messages (`accel::ray`, `crate root`).
fn module_name(m: &ModPath) -> String {
    if m.is_empty() {
        "crate root".to_owned()
    } else {
        m.join("::")
    }
}

#[test]
fn every_crate_has_short_files_and_no_import_circle() {
    let mut problems = Vec::new();
    for dir in crate_dirs() {
        let src = dir.join("src");
        let mut paths = Vec::new();
        rust_files(&src, &mut paths);
        let files: BTreeMap<ModPath, String> = paths
            .iter()
            .map(|p| {
                let text = std::fs::read_to_string(p).expect("source file");
                (module_path(&src, p), text)
            })
            .collect();
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        for (m, n) in long_files(&files) {
            problems.push(format!(
                "{name}: module {} has {n} lines outside its tests (at most {MAX_FILE_LINES}): \
                 split it by job",
                module_name(&m)
            ));
        }
        for set in circles(&import_graph(&files)) {
            let names: Vec<String> = set.iter().map(module_name).collect();
            problems.push(format!(
                "{name}: these modules import each other in a circle: {}",
                names.join(", ")
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "file invariants broken (ARCHITECTURE.md, \"Invariants\"):\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_file_checks_fire_on_counter_examples() {
    let crate_of = |files: &[(&str, &str)]| -> BTreeMap<ModPath, String> {
        files
            .iter()
            .map(|(m, text)| {
                let path = m.split("::").filter(|s| !s.is_empty());
                (path.map(str::to_owned).collect(), (*text).to_owned())
            })
            .collect()
    };
    let count = |files: &[(&str, &str)]| circles(&import_graph(&crate_of(files))).len();

    // Two files that import each other, directly or by a full path in code.
    assert_eq!(
        count(&[
            ("", "mod a;\nmod b;\n"),
            ("a", "use crate::b::B;\npub struct A;\n"),
            (
                "b",
                "pub struct B;\nfn f() -> crate::a::A { crate::a::A }\n"
            ),
        ]),
        1
    );
    // A child that imports its parent's item while the parent imports the child's.
    assert_eq!(
        count(&[
            ("", "mod walk;\n"),
            ("walk", "mod stack;\nuse stack::Stack;\npub struct Walk;\n"),
            ("walk::stack", "use super::Walk;\npub struct Stack;\n"),
        ]),
        1
    );
    // A circle through a re-export at the root, in a grouped use tree over three files.
    assert_eq!(
        count(&[
            ("", "mod a;\nmod b;\nmod c;\npub use c::C;\n"),
            ("a", "use crate::{C, b::{self, B as Bee}};\npub struct A;\n"),
            ("b", "pub struct B;\n"),
            ("c", "use crate::{\n    a::A,\n};\npub struct C;\n"),
        ]),
        1
    );
    // The same names without a circle: a re-export is followed to the file that defines the
    // name, so using `crate::A` from a sibling, alone or in a group over several lines, does not
    // point at the root.
    assert_eq!(
        count(&[
            ("", "mod a;\nmod b;\npub use a::A;\npub use b::B;\n"),
            ("a", "pub struct A;\n"),
            (
                "b",
                "use crate::{\n    A,\n};\nuse super::a;\npub struct B(A);\n"
            ),
        ]),
        0
    );
    // Tests, prose and other crates' paths are not imports.
    assert_eq!(
        count(&[
            ("", "mod a;\nmod b;\n"),
            (
                "a",
                "use crate::b::B;\n/// Unlike `crate::a::A`.\npub struct A;\n"
            ),
            (
                "b",
                "use twopass_scene::a::A;\n// crate::a::A\npub struct B;\n#[cfg(test)]\nmod \
                 tests {\n    use crate::a::A;\n}\n"
            ),
        ]),
        0
    );

    // A file one line over the bound, and one at it with tests beyond.
    let over = "fn f() {}\n".repeat(MAX_FILE_LINES + 1);
    let at = format!(
        "{}#[cfg(test)]\nmod tests {{\n{}}}\n",
        "fn f() {}\n".repeat(MAX_FILE_LINES),
        "    fn g() {}\n".repeat(100)
    );
    let long = long_files(&crate_of(&[("", "mod a;\n"), ("a", &over), ("b", &at)]));
    assert_eq!(long, vec![(vec!["a".to_owned()], MAX_FILE_LINES + 1)]);
}
