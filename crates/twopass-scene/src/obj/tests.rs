//! Reading OBJ text: smooth groups, and the lines of bad statements found.

use super::lines::{find_bad_line, find_non_finite_line};
use super::model::ObjFile;
use super::read::load;
use crate::input::ReadPolicy;

/// Loads `obj` (and `mtl` as `m.mtl`) from a scratch folder.
fn load_text(name: &str, obj: &str, mtl: &str) -> ObjFile {
    let dir = std::env::temp_dir().join(format!("twopass-obj-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    std::fs::write(dir.join("x.obj"), obj).unwrap();
    let file = load(&dir.join("x.obj"), &ReadPolicy::default()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    file
}

#[test]
fn groups_are_smooth_only_when_every_corner_names_a_normal() {
    // Group a: all corners have normals. Group b: none, while the file has normals (tobj
    // would invent them). Then a material change splits b's faces into a third model, and
    // a face with normals on some corners only (group c) stays flat.
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\n\
               g a\nf 1//1 2//1 3//1\n\
               g b\nusemtl red\nf 2 4 3\nusemtl blue\nf 1 2 4\n\
               g c\nf 1//1 2 3//1\n";
    let mtl = "newmtl red\nKd 0.5 0 0\nnewmtl blue\nKd 0 0 0.5\n";
    let file = load_text("smooth", obj, mtl);
    let smooth: Vec<(&str, bool)> = file
        .models
        .iter()
        .map(|m| (m.name.as_str(), !m.mesh.normal_indices.is_empty()))
        .collect();
    assert_eq!(
        smooth,
        [("a", true), ("b", false), ("b", false), ("c", false)]
    );
    let materials: Vec<Option<usize>> = file.models.iter().map(|m| m.material).collect();
    assert_eq!(materials, [None, Some(0), Some(1), Some(1)]);
    assert_eq!(file.models[1].usemtl.as_ref().map(|u| u.1), Some(10));
}

#[test]
fn bad_lines_are_found() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n";
    assert_eq!(
        find_bad_line(text, tobj::LoadError::PositionParseError),
        Some(3)
    );
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
    assert_eq!(
        find_bad_line(text, tobj::LoadError::FaceVertexOutOfBounds),
        Some(5)
    );
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 -1 -3\nf 1 2\n";
    assert_eq!(
        find_bad_line(text, tobj::LoadError::FaceParseError),
        Some(5)
    );
    assert_eq!(find_non_finite_line("v 0 0 0\nv nan 0 0\n", "v"), Some(2));
}

/// Loads `x.obj` from a scratch folder that also holds `files` (name, text).
fn load_with(name: &str, obj: &str, files: &[(&str, &str)]) -> ObjFile {
    let dir = std::env::temp_dir().join(format!("twopass-obj-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    std::fs::write(dir.join("x.obj"), obj).unwrap();
    let file = load(&dir.join("x.obj"), &ReadPolicy::default());
    std::fs::remove_dir_all(&dir).unwrap();
    file.unwrap()
}

/// Issue 43, findings 8 and 17: valid OBJ statements tobj misreads are loaded as written.
#[test]
fn valid_variants_tobj_misreads_are_loaded() {
    // `vt u`: v defaults to 0.
    let file = load_with(
        "vt1",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nvt 0.25\nvt 1\nf 1/1 2/2 3/3\n",
        &[],
    );
    let uv: Vec<[f32; 2]> = file.models[0]
        .mesh
        .texcoords
        .iter()
        .map(|t| t.to_array())
        .collect();
    assert_eq!(uv, [[0.5, 0.0], [0.25, 0.0], [1.0, 0.0]]);
    // One vertex with a colour among plain ones.
    let file = load_with(
        "colour",
        "v 0 0 0 1 0.5 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        &[],
    );
    let p: Vec<[f32; 3]> = file.models[0]
        .mesh
        .positions
        .iter()
        .map(|p| p.to_array())
        .collect();
    assert_eq!(p, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    // A tab after `mtllib` and `usemtl`.
    let red = "newmtl red\nKd 0.5 0 0\n";
    let file = load_with(
        "tab",
        "mtllib\tm.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\tred\nf 1 2 3\n",
        &[("m.mtl", red)],
    );
    assert_eq!(file.models[0].material, Some(0));
    assert_eq!(file.materials.unwrap()[0].name, "red");
    assert_eq!(file.missing_mtl, None);
    // Several libraries on one `mtllib` line: each is loaded, their materials merged.
    let file = load_with(
        "libs",
        "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
         usemtl red\nf 1 2 3\nusemtl blue\nf 2 4 3\n",
        &[("a.mtl", red), ("b.mtl", "newmtl blue\nKd 0 0 0.5\n")],
    );
    let names: Vec<String> = file
        .materials
        .unwrap()
        .iter()
        .map(|m| m.name.clone())
        .collect();
    assert_eq!(names, ["red", "blue"]);
    let used: Vec<Option<usize>> = file.models.iter().map(|m| m.material).collect();
    assert_eq!(used, [Some(0), Some(1)]);
    assert_eq!(file.mtllibs.len(), 2);
    assert_eq!(file.missing_mtl, None);
}
