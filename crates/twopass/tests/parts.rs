//! `render --part`, `bake --from --part` and `merge`: a job split into N parts and merged
//! equals the single-process run bit for bit, for any N; a mixed, incomplete or damaged set is
//! refused by name, and nothing is merged from it.

use std::path::{Path, PathBuf};

use twopass_composite::write::read_exr_layers;

use crate::common::{BOX, SPHERES, assert_absent, assert_exit, assert_ok, cli, repo};

/// A coarse radiosity mesh solved loosely: seconds, not minutes.
const COARSE: &str = "--element-size 80 --patch-size 150 --unshot 1e-2";

/// The render every render test splits: the hybrid over a saved solution, with its light
/// tracing pass through the glass sphere (40 x 40 pixels at 6 samples: 9,600 light paths, three
/// chunks of 4,096 to split), every layer in its EXR (`--layers`).
const RENDER: &str = "--method hybrid --width 40 --spp 6 --seed 5 --png --layers --quiet";

/// Every layer of two EXRs, as bit patterns, and their names.
fn exr_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    let layers = read_exr_layers(path).unwrap();
    layers
        .iter()
        .map(|(name, image)| {
            let bits = image
                .pixels()
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect();
            (name.to_owned(), bits)
        })
        .collect()
}

/// Solves the Cornell spheres coarsely into `dir/cornell-spheres.bake`.
fn spheres_bake(dir: &Path) -> PathBuf {
    let out = cli("bake")
        .arg(repo(SPHERES))
        .words("--format bake --gather off --quiet")
        .words(COARSE)
        .output(dir)
        .run();
    assert_ok(&out);
    dir.join("cornell-spheres.bake")
}

/// `twopass render` of the spheres over `bake` with [`RENDER`], plus `extra` words.
fn render(bake: &Path, extra: &str) -> crate::common::Cli {
    cli("render")
        .arg(repo(SPHERES))
        .words(RENDER)
        .words("--bake")
        .arg(bake)
        .words(extra)
}

/// Renders the `n` parts of [`render`] (seed as given) into `dir`, returning their files.
fn render_parts(bake: &Path, dir: &Path, n: u32, extra: &str) -> Vec<PathBuf> {
    (1..=n)
        .map(|i| {
            let file = dir.join(format!("r.{i}-of-{n}.part"));
            let out = render(bake, &format!("--part {i}/{n} {extra}"))
                .output(&file)
                .run();
            assert_ok(&out);
            file
        })
        .collect()
}

#[test]
fn merged_render_parts_equal_the_single_render_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let bake = spheres_bake(dir.path());
    let single = dir.path().join("single.exr");
    let out = render(&bake, "--json").output(&single).run();
    assert_ok(&out);
    let single_summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let want = exr_bits(&single);
    let want_png = std::fs::read(single.with_extension("png")).unwrap();
    for n in [1, 3, 4] {
        let parts_dir = dir.path().join(format!("parts{n}"));
        let mut parts = render_parts(&bake, &parts_dir, n, "");
        // Any order on the command line.
        parts.reverse();
        let merged = dir.path().join(format!("merged{n}.exr"));
        let out = cli("merge --json").args(&parts).output(&merged).run();
        assert_ok(&out);
        assert_eq!(exr_bits(&merged), want, "{n} parts");
        assert_eq!(
            std::fs::read(merged.with_extension("png")).unwrap(),
            want_png,
            "{n} parts: PNG"
        );
        // The merge reports the whole job's cost: the parts' rays are the single render's.
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(summary["parts"], n);
        for count in ["rays", "shadow_rays"] {
            assert_eq!(summary[count], single_summary[count], "{n} parts: {count}");
        }
    }
}

/// The lightmap and per-vertex gather of the Cornell box: the single bake's flags.
const GATHER: &str = "--lightmap --texel-size 8 --gather 8 --format vertex-glb --quiet";

#[test]
fn merged_gather_parts_equal_the_single_bake_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let single = d.join("single");
    assert_ok(
        &cli("bake")
            .arg(repo(BOX))
            .words(GATHER)
            .output(&single)
            .run(),
    );
    // The solve alone, then 4 shards of the gather over it, then the merge.
    let solved = d.join("solve");
    let solve = "--format bake --gather off --quiet";
    assert_ok(
        &cli("bake")
            .arg(repo(BOX))
            .words(solve)
            .output(&solved)
            .run(),
    );
    let parts: Vec<PathBuf> = (1..=4)
        .map(|i| {
            let file = d.join(format!("parts/b.{i}-of-4.part"));
            let out = cli("bake")
                .arg(repo(BOX))
                .words(GATHER)
                .words("--from")
                .arg(solved.join("cornell-box.bake"))
                .words(&format!("--part {i}/4"))
                .output(&file)
                .run();
            assert_ok(&out);
            file
        })
        .collect();
    let merged = d.join("merged");
    assert_ok(&cli("merge --quiet").args(&parts).output(&merged).run());
    for file in [
        "cornell-box.lightmap.exr",
        "cornell-box.lightmap.png",
        "cornell-box.lightmap.glb",
        "cornell-box.vertex.glb",
    ] {
        let (a, b) = (single.join(file), merged.join(file));
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{file} differs"
        );
    }
    // The manifests agree on everything but the clock and the folder.
    let manifest = |dir: &Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.join("cornell-box.manifest.json")).unwrap())
            .unwrap()
    };
    let (a, b) = (manifest(&single), manifest(&merged));
    for key in ["geometry_fingerprint", "shots", "rays", "counts", "color"] {
        assert_eq!(a[key], b[key], "manifest {key}");
    }
    let gather = |m: &serde_json::Value| m["lightmap"]["gather"].clone();
    for key in ["rays", "shadow_rays", "min_rays", "max_rays", "seed"] {
        assert_eq!(
            gather(&a)[key],
            gather(&b)[key],
            "manifest lightmap.gather.{key}"
        );
    }
    let crcs = |m: &serde_json::Value| -> Vec<serde_json::Value> {
        m["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["crc32"].clone())
            .collect()
    };
    assert_eq!(crcs(&a), crcs(&b));
}

/// A merge of `parts` into `dir/out.exr`: exit 1 with exactly `message` on stderr, and no
/// output written.
#[track_caller]
fn refused(parts: &[&Path], dir: &Path, message: &str) {
    let out_file = dir.join("refused/out.exr");
    let out = cli("merge").args(parts).output(&out_file).run();
    assert_exit(&out, 1);
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        format!("error: {message}\n")
    );
    assert_absent(&out_file, "nothing is merged from a refused set");
}

#[test]
fn a_missing_duplicate_foreign_or_truncated_part_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Whitted needs no solution: small and fast.
    let whitted = |extra: &str| {
        cli("render")
            .arg(repo(SPHERES))
            .words("--method whitted --width 16 --spp 1 --quiet")
            .words(extra)
    };
    let part = |i: u32, seed: u32| {
        let file = d.join(format!("w.{i}-of-3.seed{seed}.part"));
        assert_ok(
            &whitted(&format!("--part {i}/3 --seed {seed}"))
                .output(&file)
                .run(),
        );
        file
    };
    let (p1, p2, p3) = (part(1, 1), part(2, 1), part(3, 1));
    let shown = |p: &Path| p.display().to_string();
    let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
    refused(
        &[&p1, &p3],
        d,
        &format!(
            "part 2/3 is missing; given: 1/3 ({}), 3/3 ({}); nothing merged",
            name(&p1),
            name(&p3)
        ),
    );
    let copy = d.join("copy.part");
    std::fs::copy(&p2, &copy).unwrap();
    refused(
        &[&p1, &p2, &copy, &p3],
        d,
        &format!(
            "{}: part 2/3 again ({} is part 2/3 too); nothing merged",
            shown(&copy),
            shown(&p2)
        ),
    );
    let foreign = part(2, 2);
    refused(
        &[&p1, &foreign, &p3],
        d,
        &format!(
            "{}: another seed: 2, not 1 as in {}; nothing merged",
            shown(&foreign),
            shown(&p1)
        ),
    );
    let bytes = std::fs::read(&p3).unwrap();
    let cut = d.join("cut.part");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    refused(
        &[&p1, &p2, &cut],
        d,
        &format!(
            "{}: truncated: {} bytes, its header says {}",
            shown(&cut),
            bytes.len() - 100,
            bytes.len()
        ),
    );
    // Another scene: the Cornell box's part 2.
    let other = d.join("box.part");
    let out = cli("render")
        .arg(repo(BOX))
        .words("--method whitted --width 16 --spp 1 --seed 1 --quiet --part 2/3")
        .output(&other)
        .run();
    assert_ok(&out);
    let out = cli("merge")
        .arg(&p1)
        .arg(&other)
        .arg(&p3)
        .output(d.join("x.exr"))
        .run();
    assert_exit(&out, 1);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with(&format!(
            "error: {}: a part of another scene (",
            shown(&other)
        )),
        "{err}"
    );
    // The three of one job merge.
    assert_ok(
        &cli("merge --quiet")
            .arg(&p3)
            .arg(&p1)
            .arg(&p2)
            .output(d.join("w.exr"))
            .run(),
    );
}

#[test]
fn parts_of_the_gathered_hybrid_with_other_gather_rays_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bake = spheres_bake(d);
    let part = |i: u32, rays: u32| {
        let file = d.join(format!("g.{i}-of-2.rays{rays}.part"));
        assert_ok(
            &render(&bake, &format!("--part {i}/2 --gather-rays {rays}"))
                .output(&file)
                .run(),
        );
        file
    };
    let (p1, p2) = (part(1, 8), part(2, 2));
    refused(
        &[&p1, &p2],
        d,
        &format!(
            "{}: another gather_rays: 2, not 8 as in {}; nothing merged",
            p2.display(),
            p1.display()
        ),
    );
    // The same count in both merges.
    let p2 = part(2, 8);
    assert_ok(
        &cli("merge --quiet")
            .arg(&p1)
            .arg(&p2)
            .output(d.join("g.exr"))
            .run(),
    );
}

#[test]
fn usage_errors_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = cli("merge").run();
    assert_exit(&out, 2);
    for bad in ["0/3", "4/3", "3"] {
        let out = cli("render")
            .arg(repo(BOX))
            .words("--method whitted --width 8 --part")
            .arg(bad)
            .output(dir.path())
            .run();
        assert_exit(&out, 2);
    }
    let out = cli("render")
        .arg(repo(BOX))
        .words("--method whitted --width 8 --spp 16 --adaptive 4 --part 1/2")
        .output(dir.path())
        .run();
    assert_exit(&out, 2);
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: --part with --adaptive: adaptive sampling refines a pixel by its neighbours' \
         first pass over the whole image, so it cannot be split; render parts without it\n"
    );
    // The gathered hybrid needs at least one gather ray per sample.
    let out = cli("render")
        .arg(repo(BOX))
        .words("--width 8 --gather-rays 0")
        .output(dir.path())
        .run();
    assert_exit(&out, 2);
    // A bake part gathers over a saved solution and needs something to gather.
    let out = cli("bake")
        .arg(repo(BOX))
        .words("--part 1/2")
        .output(dir.path())
        .run();
    assert_exit(&out, 2);
    let out = cli("bake")
        .arg(repo(BOX))
        .words("--format glb --gather off --from x.bake --part 1/2")
        .output(dir.path())
        .run();
    assert_exit(&out, 2);
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: --part splits the final gather, and this bake gathers nothing: drop --gather \
         off\n"
    );
}
