//! The red-team findings of issue 12, one test each: inputs that panicked, ran without bound
//! or loaded silently wrong are now clear errors (variant, file, line asserted) or load right.

use glam::Vec3;
use twopass_scene::{CameraProblem, MAX_COORDINATE, ReadPolicy, SceneError, load, load_with};

use crate::data;

fn err(name: &str) -> SceneError {
    match load(data(name)) {
        Ok(_) => panic!("{name} loaded but must fail"),
        Err(e) => e,
    }
}

/// The error inside an [`SceneError::InObject`], after checking it names `object`.
fn inner(e: SceneError, object: &str) -> SceneError {
    match e {
        SceneError::InObject {
            object: o, source, ..
        } => {
            assert_eq!(o, object);
            *source
        }
        e => panic!("expected an error located at object `{object}`: {e:?}"),
    }
}

#[test]
fn one_value_mtl_colours_mean_grey() {
    // `Kd 0.5` is r = g = b = 0.5 in the MTL format; tobj panicked on it.
    let (scene, _) = load(data("mtl-one-value.obj")).unwrap();
    let by_name = |n: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name.ends_with(n))
            .unwrap_or_else(|| panic!("no material {n}"))
    };
    assert_eq!(by_name(":lamp").material.diffuse_albedo(), Vec3::splat(0.2));
    // `Ks 0.25` with `Ns` makes a Blinn-Phong whose diffuse part is `Kd`.
    assert_eq!(by_name(":grey").material.diffuse_albedo(), Vec3::splat(0.5));
    let lamp = scene
        .objects
        .iter()
        .find(|o| o.emission.max_element() > 0.0)
        .unwrap();
    assert_eq!(lamp.emission.to_array(), [2.0; 3]);
    // And through a scene that overrides the OBJ's materials.
    let (scene, _) = load(data("mtl-one-value.toml")).unwrap();
    assert_eq!(scene.objects.len(), 2);
}

#[test]
fn mtl_errors_name_the_library_line_and_material() {
    match inner_or_self(err("mtl-two-values.obj")) {
        SceneError::Statement {
            path,
            line,
            problem,
        } => {
            assert!(path.ends_with("mtl-two-values.mtl"));
            assert_eq!(line, 2);
            assert!(problem.contains("`Kd` needs 1 or 3 numbers"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
    match err("mtl-negative-ke.obj") {
        SceneError::MtlMaterial {
            path,
            line,
            material,
            problem,
        } => {
            assert!(path.ends_with("mtl-negative-ke.mtl"));
            assert_eq!(line, Some(5), "the line of `Ke`");
            assert_eq!(material, "glow");
            assert!(problem.contains("negative"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
    match err("usemtl-undefined.obj") {
        SceneError::Statement { line, problem, .. } => {
            assert_eq!(line, 6);
            assert!(problem.contains("usemtl nowhere"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

fn inner_or_self(e: SceneError) -> SceneError {
    match e {
        SceneError::InObject { source, .. } => *source,
        e => e,
    }
}

#[test]
fn malformed_faces_are_errors_with_their_line() {
    for (file, line, words) in [
        ("face-two-corners.obj", 6, "2 corner(s)"),
        ("face-one-corner.obj", 6, "1 corner(s)"),
        ("face-bad-texcoord.obj", 6, "texture coordinate index `9`"),
    ] {
        match err(file) {
            SceneError::Statement {
                path,
                line: l,
                problem,
            } => {
                assert!(path.ends_with(file));
                assert_eq!(l, line, "{file}");
                assert!(problem.contains(words), "{file}: {problem}");
            }
            e => panic!("{file}: wrong error: {e:?}"),
        }
    }
}

#[test]
fn an_obj_without_faces_says_so() {
    match err("no-faces.obj") {
        SceneError::Input { path, problem } => {
            assert!(path.ends_with("no-faces.obj"));
            assert!(problem.contains("no faces"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
    // A group after the last face is no object (it was "all 0 triangles are degenerate").
    let (scene, _) = load(data("trailing-group.obj")).unwrap();
    assert_eq!(scene.objects.len(), 1);
}

#[test]
fn an_unreferenced_normal_does_not_smooth_the_faces() {
    let (scene, _) = load(data("unreferenced-normal.obj")).unwrap();
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangle_count(), 2);
    for t in 0..2u32 {
        for b in [[1.0, 0.0, 0.0], [0.2, 0.3, 0.5]] {
            let n = mesh.shading_normal(t, b);
            let g = mesh.geometric_normal(t);
            assert!(
                n.dot(g) > 1.0 - 1e-6,
                "triangle {t}: shading normal {n} is not the geometric {g}"
            );
        }
    }
}

#[test]
fn coordinates_beyond_the_range_are_refused_with_the_object() {
    for (file, object, words) in [
        ("huge-sphere.toml", "ball", "`radius` value 1e19"),
        ("huge-scale.toml", "floor", "in the world"),
        ("huge-vertex.obj", "unnamed_object", "coordinate 1e19"),
    ] {
        match err(file) {
            SceneError::Range {
                path,
                object: o,
                problem,
                ..
            } => {
                assert!(path.ends_with(file));
                assert_eq!(o, object, "{file}");
                assert!(problem.contains(words), "{file}: {problem}");
                assert!(
                    problem.contains("1e12"),
                    "{file}: names the range: {problem}"
                );
            }
            e => panic!("{file}: wrong error: {e:?}"),
        }
    }
    assert_eq!(MAX_COORDINATE, 1e12);
    // 1e39 does not fit an f32: it is named as the value it became, not as a zero area.
    match err("huge-polygon.toml") {
        SceneError::NonFinite {
            object,
            what,
            index,
            value,
            ..
        } => {
            assert_eq!(
                (object.as_str(), what, index),
                ("floor", "polygon vertex", 1)
            );
            assert_eq!(value, f32::INFINITY);
        }
        e => panic!("wrong error: {e:?}"),
    }
}

/// The Cornell box scaled by `s` (objects and camera), as scene text.
fn scaled_cornell(s: f32) -> String {
    let text = std::fs::read_to_string(crate::scene_path("cornell-box.toml")).unwrap();
    text.replace(
        "[[object]]\n",
        &format!("[[object]]\ntransform = {{ scale = {s:e} }}\n"),
    )
    .replace(
        "position = [278, 273, -800]",
        &format!(
            "position = [{:e}, {:e}, {:e}]",
            278.0 * s,
            273.0 * s,
            -800.0 * s
        ),
    )
    .replace(
        "look_at = [278, 273, 0]",
        &format!("look_at = [{:e}, {:e}, 0]", 278.0 * s, 273.0 * s),
    )
}

#[test]
fn a_scene_near_the_range_limit_renders_as_at_unit_scale() {
    // Radiance does not depend on the scene's scale: the same Whitted image at 1 and 1e9.
    let render = |s: f32| {
        let (scene, _) =
            twopass_scene::load_toml(&scaled_cornell(s), &crate::scene_path("big.toml")).unwrap();
        let camera = scene.camera.with_resolution(Some(24), Some(24));
        let settings = twopass_trace::RenderSettings {
            samples_per_pixel: 1,
            jitter: false,
            ..Default::default()
        };
        let whitted = twopass_trace::Whitted::new(
            &scene,
            twopass_brdf::Rgb::ZERO,
            twopass_trace::WhittedSettings::default(),
        );
        let out = twopass_trace::render(
            &scene,
            &camera,
            &whitted,
            &settings,
            &twopass_trace::RenderProgress::new(),
        );
        assert_eq!(out.stats.non_finite, 0, "scale {s}");
        out.layers.composite()
    };
    let (unit, big) = (render(1.0), render(1e9));
    let mean = |img: &twopass_image::Image| {
        img.pixels()
            .iter()
            .fold(Vec3::ZERO, |a, p| a + Vec3::from_array(p.to_array()))
            / img.pixels().len() as f32
    };
    let (a, b) = (mean(&unit), mean(&big));
    assert!(a.min_element() > 0.01, "the unit-scale image is lit: {a}");
    assert!(
        ((a - b).abs() / a).max_element() < 0.01,
        "mean radiance {a} at scale 1 but {b} at scale 1e9"
    );
}

#[test]
fn a_scene_near_the_range_limit_loads_and_traces() {
    // The view ray's first hit, at scale 1 and near the range's edge: the same object, at
    // the distance scaled.
    let first_hit = |s: f32| {
        let (scene, _) =
            twopass_scene::load_toml(&scaled_cornell(s), &crate::scene_path("big.toml")).unwrap();
        let ray = twopass_scene::Ray::new(scene.camera.position, scene.camera.forward);
        let hit = scene.intersect(&ray).expect("the view ray hits the box");
        (hit.object, hit.t, scene.bounds.max.max_element())
    };
    let s = 1e9_f32;
    let (unit, (object, t, extent)) = (first_hit(1.0), first_hit(s));
    assert!(
        extent > 0.5 * MAX_COORDINATE,
        "the scene reaches near the limit"
    );
    assert_eq!(object, unit.0);
    let expected = unit.1 * s;
    assert!(
        (t - expected).abs() < 1e-5 * expected,
        "hit at {t} instead of {expected}"
    );
}

#[test]
fn emitted_power_that_overflows_is_refused() {
    match err("huge-power.toml") {
        SceneError::Range {
            object, problem, ..
        } => {
            assert_eq!(object, "light");
            assert!(problem.contains("emitted power"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn an_image_too_large_to_hold_is_refused() {
    match err("huge-resolution.toml") {
        SceneError::Camera { problem, line, .. } => {
            assert_eq!(
                problem,
                CameraProblem::Resolution {
                    width: 100_000,
                    height: 100_000
                }
            );
            assert!(line.is_some());
        }
        e => panic!("wrong error: {e:?}"),
    }
    let camera = twopass_scene::Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 1.0, 8, 8).unwrap();
    assert!(camera.try_with_resolution(Some(7680), Some(4320)).is_ok());
    assert!(
        camera
            .try_with_resolution(Some(65536), Some(65536))
            .is_err()
    );
    // One side alone keeps the aspect ratio: a square 8192 is too many pixels.
    assert!(camera.try_with_resolution(Some(8192), None).is_err());
}

#[cfg(unix)]
#[test]
fn a_device_is_not_read_as_a_mesh() {
    match inner(err("device-obj.toml"), "mesh") {
        SceneError::Input { path, problem } => {
            assert_eq!(path, std::path::Path::new("/dev/zero"));
            assert!(problem.contains("not a regular file"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn confined_reads_refuse_files_outside_the_scene_folder() {
    let path = data("outside-folder.toml");
    // By default the scene's own choice of path is followed...
    assert!(load(&path).is_ok());
    // ...and confined, the mesh outside the folder is refused.
    let policy = ReadPolicy::confined(&path).unwrap();
    match load_with(&path, &policy) {
        Err(e) => match inner(e, "box") {
            SceneError::Input { problem, .. } => {
                assert!(problem.contains("outside the scene's folder"), "{problem}")
            }
            e => panic!("wrong error: {e:?}"),
        },
        Ok(_) => panic!("a mesh outside the folder was read"),
    }
    // Files inside the folder still load confined.
    let inside = data("mtl-one-value.toml");
    assert!(load_with(&inside, &ReadPolicy::confined(&inside).unwrap()).is_ok());
}

#[test]
fn control_characters_in_names_are_escaped() {
    let (scene, _) = load(data("control-name.toml")).unwrap();
    assert_eq!(scene.objects[0].name, "a\\u{1b}[2Jb");
    assert_eq!(scene.emitters.len(), 1);
}

#[test]
fn sizes_that_cost_without_bound_are_refused_before_the_work() {
    // 40 spheres of 20 * 4^8 triangles: counted before any is built.
    match err("many-spheres.toml") {
        SceneError::Input { problem, .. } => {
            assert!(
                problem.contains(&(40u64 * 20 * 4u64.pow(8)).to_string()),
                "{problem}"
            );
            assert!(
                problem.contains(&twopass_scene::MAX_TRIANGLES.to_string()),
                "{problem}"
            );
        }
        e => panic!("wrong error: {e:?}"),
    }
    // A polygon too long to ear-clip in bounded time.
    let n = twopass_scene::shape::MAX_POLYGON_VERTICES + 1;
    let vertices: Vec<String> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            format!("[{}, {}, 0]", a.cos(), a.sin())
        })
        .collect();
    let text = format!(
        "version = 1\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
         [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"disc\"\nmaterial = \"w\"\n\
         shape = {{ type = \"polygon\", vertices = [{}] }}\n",
        vertices.join(", ")
    );
    match twopass_scene::load_toml(&text, std::path::Path::new("disc.toml")) {
        Err(SceneError::Shape {
            object, problem, ..
        }) => {
            assert_eq!(object, "disc");
            assert!(problem.contains("at most 1024 vertices"), "{problem}");
        }
        Err(e) => panic!("wrong error: {e:?}"),
        Ok(_) => panic!("a {n}-vertex polygon loaded"),
    }
}

#[test]
fn a_radiosity_mesh_too_fine_for_memory_is_refused_before_meshing() {
    // A 1000 x 1000 square: element size 0.1 needs at least 1e6 / (sqrt(3)/4 * 0.01) = 2.3e8
    // elements (the largest triangle with edges <= 0.1 has area sqrt(3)/4 * 0.01).
    let text = "version = 1\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
                [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
                [[object]]\nname = \"square\"\nmaterial = \"w\"\nemission = 1\n\
                shape = { type = \"quad\", origin = [0, 0, 0], edge_u = [1000, 0, 0], edge_v = [0, 1000, 0] }\n";
    let (scene, _) = twopass_scene::load_toml(text, std::path::Path::new("square.toml")).unwrap();
    let options = |size: f32| twopass_radiosity::Options {
        patch_size: Some(2000.0),
        element_size: Some(size),
        ..Default::default()
    };
    match twopass_radiosity::Solver::new(&scene, options(0.1)) {
        Err(twopass_radiosity::SolveError::Option { name, problem }) => {
            assert_eq!(name, "element_size");
            let expected = 1e6 / (3f64.sqrt() / 4.0 * 0.01);
            assert!(problem.contains(&format!("{expected:.3e}")), "{problem}");
        }
        Err(e) => panic!("wrong error: {e}"),
        Ok(_) => panic!("a mesh of 2.3e8 elements was started"),
    }
    // A size the mesh can hold is accepted.
    assert!(twopass_radiosity::Solver::new(&scene, options(100.0)).is_ok());
}

#[test]
fn a_needle_triangle_is_dropped_and_the_solve_ends() {
    // Found by the fuzz test: the radiosity mesher bisected this needle without end.
    let (scene, warnings) = load(data("fuzz-needle.obj")).unwrap();
    let dropped: Vec<&str> = warnings
        .iter()
        .filter_map(|w| match w {
            twopass_scene::Warning::DegenerateTriangles { object, .. } => Some(object.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(dropped, ["ceiling"]);
    let options = twopass_radiosity::Options {
        adaptive: None,
        stop: twopass_radiosity::Stop {
            max_shots: Some(4),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut solver = twopass_radiosity::Solver::new(&scene, options).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    assert!(solver.progress().shots >= 4);
}
