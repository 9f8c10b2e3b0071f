//! Mutation fuzzing of what `render --bake` reads (issue 43): a real bake set of the Cornell
//! box (`.bake`, `.ply`, `.glb`, `.lightmap.glb` with its PNG, the lightmap EXR, the
//! manifest) is mutated byte by byte (bytes flipped, the file cut short, a run of its own
//! bytes spliced elsewhere, a word overwritten with a huge or special number, a number of the
//! manifest's JSON replaced by an extreme one) and read back. Every outcome must be a load or
//! an error naming the file, never a panic or an abort, and every case ends in bounded time.
//!
//! The readers run in-process (`twopass_bake::read_bake`, `read_lightmap_glb`, the manifest's
//! JSON as the CLI parses it), many cases cheaply; a few cases run `twopass render --bake`
//! itself on a mutated set, where the manifest's seal is checked too, with the mutated member
//! re-sealed in every other case so the reader behind the seal meets it.
//!
//! CI runs a bounded number of cases from a fixed seed (the `TWOPASS_FUZZ_CASES` and
//! `TWOPASS_FUZZ_SEED` of the workspace's fuzz tests: the in-process readers run that many
//! cases, the CLI a sixty-fourth of them, four at least). A long run, by hand:
//! `TWOPASS_FUZZ_CASES=100000 cargo test --release -p twopass --test integration -- fuzz_bake::`.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use twopass_brdf::random::SplitMix64;

use crate::common::{self, assert_ok, bake_box, repo};

/// Cases to run and the seed: the workspace fuzz tests' variables, 48 cases and seed 12 by
/// default.
fn budget() -> (u64, u64) {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    (
        env("TWOPASS_FUZZ_CASES").unwrap_or(48),
        env("TWOPASS_FUZZ_SEED").unwrap_or(12),
    )
}

/// Values written over a word of a binary file: boundaries of the integer and float types a
/// header or an array may hold.
const HUGE: &[u64] = &[
    u64::MAX,
    u32::MAX as u64,
    0x7fff_ffff,
    0x8000_0000,
    0,
    0x7f80_0000,           // f32 infinity
    0x7fc0_0000,           // f32 NaN
    0x7f7f_ffff,           // f32 max
    0x7ff0_0000_0000_0000, // f64 infinity
    0x4415_af1d_78b5_8c40, // 1e20 as f64
];

/// Numbers written over a number of a text (JSON) file.
const NUMBERS: &[&str] = &[
    "-1",
    "1e400",
    "-1e400",
    "18446744073709551616",
    "1.5",
    "0",
    "4294967296",
    "NaN",
    "\"x\"",
    "null",
];

/// One mutation of `bytes`, drawn from `rng`, applied within `range` (the whole file, or the
/// PNG inside a `.glb`).
fn mutate(bytes: &mut Vec<u8>, range: std::ops::Range<usize>, rng: &mut SplitMix64) {
    if range.is_empty() {
        return;
    }
    let len = range.len();
    let at = |rng: &mut SplitMix64| range.start + (rng.next_u64() % len as u64) as usize;
    match rng.next_u64() % 5 {
        // A few bytes flipped.
        0 => {
            for _ in 0..1 + rng.next_u64() % 4 {
                let i = range.start + (rng.next_u64() % len as u64) as usize;
                bytes[i] ^= 1 << (rng.next_u64() % 8);
            }
        }
        // Cut short.
        1 => {
            let cut = at(rng);
            bytes.truncate(cut);
        }
        // A run of the file's own bytes copied over another place.
        2 => {
            let from = at(rng);
            let to = at(rng);
            let n = (rng.next_u64() % 64) as usize + 1;
            let n = n.min(range.end - from).min(range.end - to);
            let run = bytes[from..from + n].to_vec();
            bytes[to..to + n].copy_from_slice(&run);
        }
        // A word overwritten with a huge or special value.
        3 => {
            let value = HUGE[(rng.next_u64() % HUGE.len() as u64) as usize];
            let width = if rng.next_u64().is_multiple_of(2) {
                4
            } else {
                8
            };
            let to = (at(rng) & !3).max(range.start);
            let end = (to + width).min(range.end);
            bytes[to..end].copy_from_slice(&value.to_le_bytes()[..end - to]);
        }
        // A number of a text replaced by an extreme one (or a flip, where there is none).
        _ => {
            let digits: Vec<usize> = (range.clone())
                .filter(|&i| bytes[i].is_ascii_digit())
                .collect();
            if digits.is_empty() {
                let i = at(rng);
                bytes[i] ^= 0x20;
                return;
            }
            let start = digits[(rng.next_u64() % digits.len() as u64) as usize];
            let mut end = start;
            while end < range.end && (bytes[end].is_ascii_digit() || b".eE+-".contains(&bytes[end]))
            {
                end += 1;
            }
            let number = NUMBERS[(rng.next_u64() % NUMBERS.len() as u64) as usize];
            bytes.splice(start..end, number.bytes());
        }
    }
}

/// The byte range of the PNG inside a `.glb` (from its signature to its `IEND` chunk's end).
fn png_range(glb: &[u8]) -> std::ops::Range<usize> {
    let find = |needle: &[u8]| glb.windows(needle.len()).position(|w| w == needle);
    let start = find(b"\x89PNG\r\n\x1a\n").expect("the lightmap .glb embeds a PNG");
    let end = find(b"IEND").expect("the PNG ends") + 8;
    start..end
}

/// The Cornell box's bake set (every format, a coarse lightmap, no gather), baked once into
/// a folder the fuzz tests copy from.
fn baked_set() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("set");
    let words = "--format glb,ply,bake --lightmap --texel-size 20 --gather off --quiet";
    assert_ok(&bake_box(&dir).words(words).run());
    (tmp, dir)
}

/// The members of the set: (file name, whether the PNG inside it is the target).
const MEMBERS: &[(&str, bool)] = &[
    ("cornell-box.bake", false),
    ("cornell-box.lightmap.glb", false),
    ("cornell-box.lightmap.glb", true),
    ("cornell-box.lightmap.exr", false),
    ("cornell-box.manifest.json", false),
    ("cornell-box.ply", false),
    ("cornell-box.glb", false),
];

/// Copies the set in `from` into `to` (emptied first).
fn copy_set(from: &Path, to: &Path) {
    let _ = std::fs::remove_dir_all(to);
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// Mutates member `which` of the set in `dir` with the case's stream; returns its path.
fn mutate_member(dir: &Path, which: usize, rng: &mut SplitMix64) -> PathBuf {
    let (name, in_png) = MEMBERS[which];
    let path = dir.join(name);
    let mut bytes = std::fs::read(&path).unwrap();
    let range = if in_png {
        png_range(&bytes)
    } else {
        0..bytes.len()
    };
    for _ in 0..1 + rng.next_u64() % 3 {
        let range = range.start..range.end.min(bytes.len());
        mutate(&mut bytes, range, rng);
    }
    std::fs::write(&path, &bytes).unwrap();
    path
}

#[test]
fn mutated_bake_files_read_or_fail_cleanly() {
    let (cases, seed) = budget();
    let (_keep, good) = baked_set();
    let (scene, _) = twopass_scene::load(repo("scenes/cornell-box.toml")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("case");
    let folder = dir.display().to_string();
    for case in 0..cases {
        copy_set(&good, &dir);
        let mut rng = SplitMix64::new(seed ^ twopass_brdf::random::hash(case));
        let which = (rng.next_u64() % MEMBERS.len() as u64) as usize;
        let path = mutate_member(&dir, which, &mut rng);
        let started = Instant::now();
        let message = match MEMBERS[which].0 {
            "cornell-box.bake" => twopass_bake::read_bake(&path, &scene)
                .err()
                .map(|e| e.to_string()),
            "cornell-box.manifest.json" => {
                let text = std::fs::read(&path).unwrap();
                // As the CLI parses it; its error gets the file's name there.
                let _ = serde_json::from_slice::<twopass_bake::Manifest>(&text);
                None
            }
            "cornell-box.ply" | "cornell-box.glb" => None,
            _ => twopass_bake::read_lightmap_glb(&dir.join("cornell-box.lightmap.glb"), &scene)
                .err()
                .map(|e| e.to_string()),
        };
        if let Some(m) = message {
            assert!(
                m.starts_with(&folder),
                "case {case} ({}): the error names no file of the set: {m}",
                MEMBERS[which].0
            );
        }
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "case {case} ({}): {:?}",
            MEMBERS[which].0,
            started.elapsed()
        );
    }
}

/// Runs `twopass render --bake` on the set in `dir` with a 60 s limit; returns the exit code
/// and the standard error.
fn render_from(dir: &Path, file: &str) -> (Option<i32>, String) {
    let scene = repo("scenes/cornell-box.toml");
    let (bake, out) = (dir.join(file), dir.join("out.exr"));
    let mut args: Vec<&OsStr> = [
        "render",
        "--method",
        "radiosity",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--quiet",
    ]
    .iter()
    .map(OsStr::new)
    .collect();
    args.extend([
        scene.as_os_str(),
        OsStr::new("--bake"),
        bake.as_os_str(),
        OsStr::new("-o"),
        out.as_os_str(),
    ]);
    let out = common::run_soon(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn mutated_bake_sets_render_or_fail_cleanly() {
    let (cases, seed) = budget();
    let (_keep, good) = baked_set();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("case");
    let folder = dir.display().to_string();
    for case in 0..(cases / 64).max(4) {
        copy_set(&good, &dir);
        let mut rng = SplitMix64::new(seed ^ twopass_brdf::random::hash(!case));
        let which = (rng.next_u64() % MEMBERS.len() as u64) as usize;
        mutate_member(&dir, which, &mut rng);
        // Every other case, the mutated member is sealed again, so what reads it behind the
        // manifest's check meets it (a mutated manifest cannot be sealed: it is the seal).
        let resealed = case % 2 == 1 && MEMBERS[which].0 != "cornell-box.manifest.json";
        if resealed {
            common::reseal(&dir, "cornell-box", |_| true);
        }
        for file in ["cornell-box.bake", "cornell-box.lightmap.glb"] {
            let (code, stderr) = render_from(&dir, file);
            let what = format!(
                "case {case} ({}, resealed {resealed}) --bake {file}",
                MEMBERS[which].0
            );
            match code {
                Some(0) => {}
                Some(1) => assert!(
                    stderr.contains(&folder) && !stderr.contains("panicked"),
                    "{what}: the error names no file of the set: {stderr}"
                ),
                other => panic!("{what}: exit {other:?}: {stderr}"),
            }
        }
    }
}

/// The error `read_lightmap_glb` gives for the Cornell box's lightmap `.glb` edited by
/// `edit`, and the path of that `.glb`.
fn refused_lightmap_glb(edit: impl FnOnce(&mut Vec<u8>)) -> (String, String) {
    let (_keep, dir) = baked_set();
    let (scene, _) = twopass_scene::load(repo("scenes/cornell-box.toml")).unwrap();
    let glb = dir.join("cornell-box.lightmap.glb");
    let mut bytes = std::fs::read(&glb).unwrap();
    edit(&mut bytes);
    std::fs::write(&glb, &bytes).unwrap();
    let err = twopass_bake::read_lightmap_glb(&glb, &scene)
        .expect_err("refused")
        .to_string();
    (err, glb.display().to_string())
}

/// Found by the long run of `mutated_bake_files_read_or_fail_cleanly`: a lightmap `.glb`
/// whose index accessors say floats (component type 5126) made the gltf crate's index reader
/// panic (`unreachable!`); it is refused, naming the file and the accessor.
#[test]
fn a_lightmap_glb_with_float_indices_is_refused() {
    let (err, glb) = refused_lightmap_glb(|bytes| {
        // Unsigned int and short component types become float, the JSON chunk's length
        // unchanged.
        let mut changed = 0;
        for from in [
            &b"\"componentType\":5125"[..],
            &b"\"componentType\":5123"[..],
        ] {
            while let Some(at) = bytes.windows(from.len()).position(|w| w == from) {
                bytes[at + from.len() - 1] = b'6';
                changed += 1;
            }
        }
        assert!(changed > 0, "the .glb has integer index accessors");
    });
    assert!(
        err.starts_with(&glb) && err.contains("indices accessor") && err.contains("F32"),
        "{err}"
    );
}

/// Found by the long run of `mutated_bake_files_read_or_fail_cleanly`: a lightmap `.glb`
/// whose image lost its mimeType (glTF requires one with a buffer view) made the gltf crate's
/// `Image::source` panic; it is refused, naming the file and the image's problem.
#[test]
fn a_lightmap_glb_whose_image_has_no_mime_type_is_refused() {
    let (err, glb) = refused_lightmap_glb(|bytes| {
        let from = &b"\"mimeType\""[..];
        let at = bytes
            .windows(from.len())
            .position(|w| w == from)
            .expect("the lightmap image has a mimeType");
        // Renamed, the JSON chunk's length unchanged.
        bytes[at + 8] = b'X';
    });
    assert!(
        err.starts_with(&glb)
            && err.contains("its lightmap image has a bufferView but no mimeType"),
        "{err}"
    );
}
