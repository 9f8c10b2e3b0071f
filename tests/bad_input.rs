//! Every bad input is a clear error (variant and context asserted), never a panic.

use twopass_scene::{CameraProblem, SceneError, Warning, load};

use crate::data;

fn err(name: &str) -> SceneError {
    match load(data(name)) {
        Ok(_) => panic!("{name} loaded but must fail"),
        Err(e) => e,
    }
}

#[test]
fn missing_file_names_the_path() {
    match err("does-not-exist.toml") {
        SceneError::Io { path, source } => {
            assert!(path.ends_with("does-not-exist.toml"));
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        e => panic!("wrong error: {e:?}"),
    }
    assert!(matches!(
        err("README.md"),
        SceneError::UnsupportedFormat { .. }
    ));
}

#[test]
fn toml_syntax_error_has_line_and_column() {
    match err("syntax-error.toml") {
        SceneError::Toml { path, line, .. } => {
            assert!(path.ends_with("syntax-error.toml"));
            // The unclosed array opens on line 6; the parser notices at the next table header.
            assert!((6..=8).contains(&line), "line {line}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn unknown_key_is_refused_with_its_line() {
    match err("unknown-key.toml") {
        SceneError::Toml { line, message, .. } => {
            assert_eq!(line, 11, "the line of `albedo`");
            assert!(message.contains("albedo"), "{message}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn unknown_unit_is_refused_with_its_line_and_the_known_units() {
    match err("unknown-unit.toml") {
        SceneError::Toml {
            path,
            line,
            message,
            ..
        } => {
            assert!(path.ends_with("unknown-unit.toml"));
            assert_eq!(line, 3, "the line of `unit`");
            assert!(message.contains("furlong"), "{message}");
            for known in ["mm", "cm", "m", "in", "ft"] {
                assert!(message.contains(&format!("`{known}`")), "{message}");
            }
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn unknown_material_names_object_and_line() {
    match err("unknown-material.toml") {
        SceneError::UnknownMaterial {
            line,
            object,
            material,
            ..
        } => {
            assert_eq!((object.as_str(), material.as_str()), ("floor", "chalk"));
            assert!((12..=14).contains(&line), "line {line} is not the object's");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn reflectance_of_one_is_refused() {
    match err("reflectance-one.toml") {
        SceneError::Material {
            material,
            source,
            line,
            ..
        } => {
            assert_eq!(material, "white");
            assert_eq!(source.parameter, "diffuse");
            assert_eq!(source.value, 1.0);
            assert!(line.is_some());
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn zero_roughness_is_refused() {
    match err("zero-roughness.toml") {
        SceneError::Material {
            material, source, ..
        } => {
            assert_eq!(material, "rough");
            assert_eq!(source.parameter, "roughness");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn negative_emission_names_the_channel() {
    match err("negative-emission.toml") {
        SceneError::NegativeEmission {
            object,
            channel,
            value,
            ..
        } => assert_eq!((object.as_str(), channel, value), ("floor", 1, -2.0)),
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn nan_vertex_in_toml_is_refused() {
    match err("nan-vertex.toml") {
        // The key as written (`origin = [-1, nan, 0]`), before any arithmetic on it.
        SceneError::NonFinite { object, what, .. } => {
            assert_eq!((object.as_str(), what), ("floor", "`origin` component"))
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn nan_vertex_in_obj_names_file_and_line() {
    let e = match err("nan-obj.toml") {
        SceneError::InObject { object, source, .. } => {
            assert_eq!(object, "mesh");
            *source
        }
        e => panic!("not located at the scene's object: {e:?}"),
    };
    match e {
        SceneError::NonFinite {
            path,
            line,
            what,
            value,
            ..
        } => {
            assert!(path.ends_with("nan-vertex.obj"));
            assert_eq!(line, Some(4));
            assert_eq!(what, "vertex");
            assert!(value.is_nan());
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn broken_obj_face_names_the_line() {
    match err("broken-face.obj") {
        SceneError::Statement {
            path,
            line,
            problem,
        } => {
            assert!(path.ends_with("broken-face.obj"));
            assert_eq!(line, 6);
            assert!(problem.contains("vertex index `9`"), "{problem}");
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn degenerate_shape_is_refused() {
    match err("degenerate-quad.toml") {
        SceneError::Shape { object, .. } => assert_eq!(object, "floor"),
        e => panic!("wrong error: {e:?}"),
    }
    match err("all-degenerate.obj") {
        SceneError::DegenerateObject { triangles, .. } => assert_eq!(triangles, 1),
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn degenerate_obj_triangles_are_dropped_with_a_warning() {
    let (scene, warnings) = load(data("degenerate-obj.toml")).unwrap();
    assert_eq!(scene.mesh.triangle_count(), 1);
    let dropped = warnings.iter().find_map(|w| match w {
        Warning::DegenerateTriangles {
            object,
            dropped,
            first,
            ..
        } => Some((object.clone(), *dropped, *first)),
        _ => None,
    });
    assert_eq!(dropped, Some(("mesh".to_owned(), 2, 1)));
}

#[test]
fn missing_mtl_is_an_error_when_the_scene_relies_on_it() {
    match err("missing-mtl.toml") {
        SceneError::InObject {
            path,
            line,
            object,
            source,
        } => {
            assert!(path.ends_with("missing-mtl.toml"));
            assert!((7..=8).contains(&line), "line {line} is not the object's");
            assert_eq!(object, "mesh");
            match *source {
                SceneError::MissingMtl { path, mtl, .. } => {
                    assert!(path.ends_with("missing-mtl.obj"));
                    assert!(mtl.unwrap().ends_with("nowhere.mtl"));
                }
                e => panic!("wrong inner error: {e:?}"),
            }
        }
        e => panic!("wrong error: {e:?}"),
    }
    // Loaded bare, the OBJ falls back to the default grey with a warning.
    let (scene, warnings) = load(data("missing-mtl.obj")).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| matches!(w, Warning::MissingMtl { .. }))
    );
    assert_eq!(
        scene.materials[0].material.diffuse_albedo(),
        glam::Vec3::splat(0.5)
    );
}

#[test]
fn missing_obj_names_the_mesh_file() {
    // The mesh's path, and the scene file and line of the object that names it.
    match err("missing-obj.toml") {
        SceneError::InObject {
            path,
            line,
            object,
            source,
        } => {
            assert!(path.ends_with("missing-obj.toml"));
            assert!((12..=13).contains(&line), "line {line} is not the object's");
            assert_eq!(object, "mesh");
            match *source {
                SceneError::Io { path, .. } => assert!(path.ends_with("nowhere.obj")),
                e => panic!("wrong inner error: {e:?}"),
            }
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn empty_scene_is_refused() {
    assert!(matches!(err("empty.toml"), SceneError::EmptyScene { .. }));
}

#[test]
fn camera_up_parallel_to_view_is_refused() {
    match err("camera-up-parallel.toml") {
        SceneError::Camera { problem, line, .. } => {
            assert_eq!(problem, CameraProblem::UpParallelToView);
            assert_eq!(line, Some(2));
        }
        e => panic!("wrong error: {e:?}"),
    }
}

#[test]
fn unsupported_version_and_duplicates_are_refused() {
    assert!(matches!(
        err("version.toml"),
        SceneError::Version {
            found: 7,
            supported: 1,
            line: 1,
            ..
        }
    ));
    match err("duplicate-object.toml") {
        SceneError::DuplicateName { kind, name, .. } => {
            assert_eq!((kind, name.as_str()), ("object", "floor"))
        }
        e => panic!("wrong error: {e:?}"),
    }
}
