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
        // Issue 43, finding 14: below f32's precision the refinement never ends.
        (
            vec![
                "bake",
                s,
                "--solver",
                "hierarchical",
                "--link-tolerance",
                "5e-324",
                "-o",
                o,
            ],
            vec![
                "--link-tolerance",
                "5e-324",
                "at least 1.1920928955078125e-7",
            ],
        ),
        (
            vec![
                "bake",
                s,
                "--solver",
                "hierarchical",
                "--link-tolerance",
                "1e-8",
                "-o",
                o,
            ],
            vec!["--link-tolerance", "1e-8", "at least 1.1920928955078125e-7"],
        ),
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
        // Issue 43, finding 13: few enough elements for memory, but progressive refinement's
        // pair loop (patches x vertices a sweep) would run for hours: refused with the estimate.
        (
            vec!["bake", s, "--element-size", "1.41"],
            vec![
                "element_size",
                "at least 3.500e8 form factors a sweep",
                "3.116e2 patches x 1.123e6 vertices",
                "hierarchical solver",
            ],
        ),
        (
            vec![
                "bake",
                s,
                "--solver",
                "progressive",
                "--element-size",
                "1.07",
            ],
            vec!["element_size", "at least 6.078e8 form factors a sweep"],
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

/// Runs `twopass args`, killing it after 60 s (a test of a hang must not hang), and checks
/// its exit code and that stderr holds every one of `words`.
fn expect_soon(args: &[&str], code: i32, words: &[&str]) {
    let out = common::run_soon(args);
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
}

/// Makes a FIFO at `path`.
#[cfg(unix)]
fn mkfifo(path: &std::path::Path) {
    let status = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", path.display());
}

/// Issue 43, finding 7: a FIFO named as any input (the scene, an OBJ, its MTL, a `.bake`, a
/// lightmap's `.glb` or EXR) is refused at once, naming it, as devices are: opening one for
/// reading would wait for a writer that never comes.
#[cfg(unix)]
#[test]
fn fifos_are_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let path = |name: &str| dir.join(name).display().to_string();
    let refused = "not a regular file";
    // The scene file, and a bare OBJ.
    for name in ["fifo.toml", "fifo.obj"] {
        mkfifo(&dir.join(name));
        expect_soon(&["info", &path(name)], 1, &[name, refused]);
    }
    // An OBJ a scene names.
    std::fs::write(
        dir.join("mesh.toml"),
        "version = 1\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n\
         [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.5\n\n\
         [[object]]\nname = \"mesh\"\nmaterial = \"white\"\n\
         shape = { type = \"obj\", file = \"fifo.obj\" }\n",
    )
    .unwrap();
    expect_soon(&["info", &path("mesh.toml")], 1, &["fifo.obj", refused]);
    // The MTL library an OBJ names.
    mkfifo(&dir.join("fifo.mtl"));
    std::fs::write(
        dir.join("lib.obj"),
        "mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    expect_soon(&["info", &path("lib.obj")], 1, &["fifo.mtl", refused]);
    // A bake file.
    mkfifo(&dir.join("fifo.bake"));
    let scene = cornell();
    // `render --bake bake`, refused naming the file `named`.
    let render = |bake: &str, named: &str| {
        expect_soon(
            &[
                "render",
                &scene,
                "--method",
                "radiosity",
                "--bake",
                bake,
                "--width",
                "8",
                "--height",
                "8",
                "--quiet",
                "-o",
                &path("x.exr"),
            ],
            1,
            &[named, refused],
        );
    };
    render(&path("fifo.bake"), "fifo.bake");
    // A lightmap's `.glb`, and the EXR beside a good `.glb`.
    mkfifo(&dir.join("fifo.lightmap.glb"));
    render(&path("fifo.lightmap.glb"), "fifo.lightmap.glb");
    let baked = dir.join("baked");
    common::bake_cornell_lightmap(&baked);
    let exr = baked.join("cornell-box.lightmap.exr");
    std::fs::remove_file(&exr).unwrap();
    mkfifo(&exr);
    let glb = baked.join("cornell-box.lightmap.glb").display().to_string();
    render(&glb, "cornell-box.lightmap.exr");
    // Behind a manifest that does not list the EXR (whose check would refuse it first), the
    // lightmap reader meets the FIFO itself.
    common::reseal(&baked, "cornell-box", |name| !name.ends_with(".exr"));
    render(&glb, "cornell-box.lightmap.exr");
}

/// Issue 43, finding 16: the Cornell OBJ scene with the back wall's `f` line repeated 100
/// times (an export glitch) renders at once: the 99 copies of its two triangles are dropped
/// at load with a warning naming the object and the triangles.
#[test]
fn repeated_faces_are_dropped_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::create_dir(dir.join("meshes")).unwrap();
    std::fs::copy(
        repo("scenes/cornell-obj.toml"),
        dir.join("cornell-obj.toml"),
    )
    .unwrap();
    std::fs::copy(
        repo("scenes/meshes/cornell-box.mtl"),
        dir.join("meshes/cornell-box.mtl"),
    )
    .unwrap();
    let obj = std::fs::read_to_string(repo("scenes/meshes/cornell-box.obj")).unwrap();
    let wall = "f 13 14 15 16\n";
    assert!(obj.contains(wall), "the back wall's face line");
    let repeated = obj.replacen(wall, &wall.repeat(100), 1);
    std::fs::write(dir.join("meshes/cornell-box.obj"), repeated).unwrap();
    let scene = dir.join("cornell-obj.toml").display().to_string();
    let out = dir.join("x.exr").display().to_string();
    // The quad is two triangles (0 and 1 of the object); the second face line's are 2 and 3.
    expect(
        &[
            "render", &scene, "--width", "16", "--height", "16", "--spp", "1", "-o", &out,
        ],
        0,
        &[
            "back-wall",
            "dropped 198 triangle(s) that repeat another of the object exactly",
            "the first is triangle 2, a copy of triangle 0",
        ],
    );
}

/// Issue 43, finding 12: a bare OBJ whose triangles all collapse to one point is refused
/// naming the degenerate triangles (the file, the line of the first face), not the camera
/// the loader would have made up to frame them.
#[test]
fn an_obj_collapsed_to_a_point_names_its_triangles() {
    let tmp = tempfile::tempdir().unwrap();
    let obj = tmp.path().join("point.obj");
    std::fs::write(
        &obj,
        "# every corner at one point\nv 1 2 3\nv 1 2 3\nv 1 2 3\nv 1 2 3\nf 1 2 3\nf 2 3 4\n",
    )
    .unwrap();
    let obj = obj.display().to_string();
    expect(
        &["info", &obj],
        1,
        &["point.obj:6", "all 2 triangles are degenerate"],
    );
    let out = twopass(&["info", &obj]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("camera"));
}

/// Issue 43, finding 1: 5,000 copies of one floor triangle under a light, baked with the
/// hierarchical solver (which aborted on a stack overflow walking a chain of 5,000
/// clusters): the copies are dropped at load, with a warning, and the bake completes.
#[test]
fn a_floor_of_coincident_copies_bakes_hierarchically() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let scene = lit_floor(dir, &"f 1 2 3\n".repeat(5000));
    let out = dir.join("out").display().to_string();
    expect_soon(
        &["bake", &scene, "--solver", "hierarchical", "-o", &out],
        0,
        &["dropped 4999 triangle(s) that repeat another of the object exactly"],
    );
}

/// Writes `floor.obj` into `dir`: a floor triangle's corners and `faces` (white), under a
/// light triangle, with its library `lit.mtl`; returns the OBJ's path. The reproducers of
/// issue 43, finding 1.
fn lit_floor(dir: &std::path::Path, faces: &str) -> String {
    let mut obj = String::from(
        "mtllib lit.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 -1\nv 0 1 0\nv 0 1 -1\nv 1 1 0\nusemtl white\n",
    );
    obj.push_str(faces);
    obj.push_str("o light\nusemtl light\nf 4 5 6\n");
    std::fs::write(dir.join("floor.obj"), obj).unwrap();
    std::fs::write(
        dir.join("lit.mtl"),
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n",
    )
    .unwrap();
    dir.join("floor.obj").display().to_string()
}

/// `lit_floor` with `copies` copies of the floor triangle, each in an `o` group of its own.
fn floor_of_objects(dir: &std::path::Path, copies: usize) -> String {
    let faces: String = (0..copies).map(|i| format!("o c{i}\nf 1 2 3\n")).collect();
    lit_floor(dir, &faces)
}

/// Issue 43, finding 1 across objects: 1,000 copies of one floor triangle, each an object of
/// its own, under a light (the bake was quadratic in the copies' shared BVH box, then created
/// power): the copies of the first are dropped at load with one warning naming both objects
/// and their lines, the 999 emptied objects removed, and the bake completes with both solvers.
#[test]
fn a_floor_of_coincident_objects_bakes() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = floor_of_objects(tmp.path(), 1000);
    // `o c0` is on line 9 and its face on line 10; each copy 2 lines further.
    let warning = "floor.obj: dropped 999 triangle(s) in 999 object(s) that repeat a triangle of \
                   an earlier object exactly (same corners, same winding); 999 object(s) left \
                   with no triangle were removed; the first is triangle 0 of object `c1` \
                   (line 12), a copy of triangle 0 of object `c0` (line 10)";
    for solver in ["progressive", "hierarchical"] {
        let out = tmp.path().join(solver).display().to_string();
        expect_soon(
            &["bake", &scene, "--solver", solver, "-o", &out],
            0,
            &[warning],
        );
    }
}

/// Issue 43, findings 1 and 2: 10^5 coincident triangles, each an object of its own, load at
/// once as one triangle (one hash look-up per triangle), with the warning. The BVH of 10^5
/// coincident triangles that reach it (copies of one box built as one and expanded into a
/// balanced subtree) is `accel::tests::collapse::coincident_triangles_build_a_shallow_valid_tree`.
#[test]
fn a_hundred_thousand_coincident_objects_load_as_one() {
    let tmp = tempfile::tempdir().unwrap();
    let obj = floor_of_objects(tmp.path(), 100_000);
    let out = twopass(&["info", &obj]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("2 triangles"), "{stdout}");
    assert!(stdout.contains("2 objects"), "{stdout}");
    assert!(
        stderr.contains(
            "dropped 99999 triangle(s) in 99999 object(s) that repeat a triangle of an earlier object"
        ),
        "{stderr}"
    );
}

#[test]
fn a_render_larger_than_the_memory_allows_is_refused_up_front() {
    // Under a 100 MB allowance a 1024 x 1024 image (about 336 MB at 336 bytes per pixel) is
    // refused before anything is computed or written; 256 x 256 (22 MB) renders.
    let dir = tempfile::tempdir().unwrap();
    let run = |width: &str, out: &str| {
        Command::new(env!("CARGO_BIN_EXE_twopass"))
            .env("TWOPASS_MEMORY_LIMIT", "100000000")
            .args([
                "render",
                &cornell(),
                "--method",
                "whitted",
                "--spp",
                "1",
                "--width",
                width,
            ])
            .arg("-o")
            .arg(dir.path().join(out))
            .output()
            .unwrap()
    };
    let big = run("1024", "big.exr");
    common::assert_exit(&big, 2);
    let err = String::from_utf8_lossy(&big.stderr);
    assert!(err.contains("1024 x 1024") && err.contains("GiB"), "{err}");
    assert!(!dir.path().join("big.exr").exists());
    common::assert_ok(&run("256", "small.exr"));
}

/// Issue 43, the memory ceiling: a lightmap whose texels cannot fit the command's allowance
/// (here 300 MB) is refused before the solve, naming the texel size and the memory.
#[test]
fn a_lightmap_larger_than_the_memory_allows_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_twopass"))
        .env("TWOPASS_MEMORY_LIMIT", "300000000")
        .args(["bake", &cornell(), "--lightmap", "--texel-size", "0.3"])
        .arg("-o")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    common::assert_exit(&out, 2);
    let err = String::from_utf8_lossy(&out.stderr);
    // The box's 1.934346e6 mm^2 at 0.3 mm: 2.149e7 texels, 0.9 GiB at 46 bytes each.
    assert!(
        err.contains("--texel-size 0.3")
            && err.contains("at least 2.149e7 texels")
            && err.contains("about 0.9 GiB")
            && err.contains("0.3 GiB a command may take"),
        "{err}"
    );
    assert!(
        !dir.path()
            .join("out")
            .join("cornell-box.manifest.json")
            .exists()
    );
}
