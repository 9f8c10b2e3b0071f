//! Multi-file outputs stay consistent or visibly incomplete, and what a killed run left
//! behind is cleaned up (issue 12).

use crate::common;

use std::time::{Duration, SystemTime};

use crate::common::{bake_box, render_box};
use twopass_bake::Manifest;

/// A coarse radiosity mesh solved loosely: seconds, not minutes.
const COARSE: &str = "--element-size 80 --patch-size 200 --unshot 5e-2";

fn bake(dir: &std::path::Path, extra: &[&str]) -> std::process::Output {
    bake_box(dir).words("-q").words(COARSE).args(extra).run()
}

#[test]
fn the_manifest_seals_the_bake_set() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("set");
    let out = bake(&dir, &[]);
    common::assert_ok(&out);
    let manifest_path = dir.join("cornell-box.manifest.json");
    let manifest: Manifest =
        serde_json::from_slice(&std::fs::read(&manifest_path).unwrap()).unwrap();
    assert_eq!(manifest.files.len(), 3);
    for f in &manifest.files {
        let bytes = std::fs::read(&f.path).unwrap();
        assert_eq!(f.bytes, bytes.len() as u64, "{}", f.path.display());
        assert_eq!(
            f.crc32,
            Some(crc32fast::hash(&bytes)),
            "{}",
            f.path.display()
        );
    }

    // A bake from other settings, copied over this set's .bake (what a bake killed after its
    // .bake and before its manifest leaves): rendering from it is refused.
    let other = tmp.path().join("other");
    let out = bake(&other, &["--seed", "7"]);
    assert_eq!(out.status.code(), Some(0));
    let bake_file = dir.join("cornell-box.bake");
    std::fs::copy(other.join("cornell-box.bake"), &bake_file).unwrap();
    // `render --bake` from the set, refused: its standard error.
    let refused = || {
        let render = render_box("radiosity", 8, 1)
            .words("--bake")
            .arg(&bake_file)
            .output(tmp.path().join("r.exr"))
            .run();
        let stderr = String::from_utf8_lossy(&render.stderr).into_owned();
        assert_eq!(render.status.code(), Some(1), "{stderr}");
        stderr
    };
    let stderr = refused();
    assert!(stderr.contains("does not match its manifest"), "{stderr}");

    // A bake that fails between its files leaves no manifest: the set is visibly incomplete.
    let ply = dir.join("cornell-box.ply");
    std::fs::remove_file(&ply).unwrap();
    std::fs::create_dir(&ply).unwrap(); // the .ply cannot be renamed into place now
    let out = bake(&dir, &[]);
    common::assert_exit(&out, 1);
    let why = "the old manifest must not survive beside a partial new set";
    common::assert_absent(&manifest_path, why);
    // Issue 43: rendering from that unsealed set is refused, naming the folder, the file and
    // the missing manifest, and how to mend it.
    let stderr = refused();
    let d = dir.display();
    assert_eq!(
        stderr.trim_end(),
        format!(
            "error: {d}: cornell-box.bake has no manifest beside it ({d}/cornell-box.manifest.json \
             is missing): a bake writes its manifest last, so this set is incomplete or its seal \
             was removed; bake again into {d}"
        )
    );
    common::assert_absent(
        &tmp.path().join("r.exr"),
        "nothing rendered from an unsealed set",
    );
}

#[test]
fn stale_temporaries_of_a_killed_run_are_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let stale = dir.join(".twopass-composite-killed.tmp");
    let fresh = dir.join(".twopass-composite-live.tmp");
    let foreign = dir.join(".other-tool.tmp");
    for p in [&stale, &fresh, &foreign] {
        std::fs::write(p, b"partial").unwrap();
    }
    let hour_ago = SystemTime::now() - Duration::from_secs(3600);
    for p in [&stale, &foreign] {
        std::fs::File::options()
            .write(true)
            .open(p)
            .unwrap()
            .set_modified(hour_ago)
            .unwrap();
    }
    let out = render_box("whitted", 8, 1).output(dir.join("x.exr")).run();
    common::assert_ok(&out);
    common::assert_absent(&stale, "a leftover of a killed run is removed");
    assert!(fresh.exists(), "a temporary file that may be live is kept");
    assert!(foreign.exists(), "other programs' files are not touched");
}

/// Issue 43: `render --bake X` checks the whole set its manifest seals, not only X: a damaged
/// `.ply` beside a good `.bake`, or a missing one, is refused naming it.
#[test]
fn render_from_a_bake_checks_every_file_of_its_set() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("set");
    common::assert_ok(&bake(&dir, &[]));
    let ply = dir.join("cornell-box.ply");
    let render = |name: &str| {
        render_box("radiosity", 8, 1)
            .words("--bake")
            .arg(dir.join("cornell-box.bake"))
            .output(tmp.path().join(name))
            .run()
    };
    common::assert_ok(&render("good.exr"));
    // One byte changed, the size kept.
    let mut bytes = std::fs::read(&ply).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0xff;
    std::fs::write(&ply, &bytes).unwrap();
    for (name, problem) in [
        ("damaged.exr", "its CRC-32 differs"),
        ("missing.exr", "missing"),
    ] {
        if name == "missing.exr" {
            std::fs::remove_file(&ply).unwrap();
        }
        let out = render(name);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains("cornell-box.ply: does not match its manifest")
                && stderr.contains(problem),
            "{stderr}"
        );
        assert!(!tmp.path().join(name).exists());
    }
}
