//! Issue 41: the per-vertex bake is on exactly the user's vertex list. An OBJ without normals
//! (its `v` statements written in another order than its faces first use them, one group by
//! negative indices) comes back with as many vertices as `v` statements, in their order, each
//! at its statement's position bit for bit; a group whose `vn` split a vertex keeps the split,
//! and `_TWOPASS_SOURCE_INDEX` names the `v` statement of every vertex.

use twopass_bake::{self as bake, ColorMapping, SOURCE_INDEX};

use crate::common::solve;
use crate::validator::assert_valid;

/// A floor of 2 x 2 quads whose nine `v` are written backwards, a lamp facing down (negative
/// indices), neither with normals; and, with `fold`, two quads at an angle sharing an edge,
/// each with its own `vn` (the edge's vertices split in two).
fn obj(fold: bool) -> String {
    let mut s = String::from("mtllib room.mtl\no Floor\nusemtl white\n");
    // v 1..9 hold the grid points (i, j) = (2 - k / 3, 2 - k % 3) for k = 0..9: backwards.
    for k in 0..9 {
        let (i, j) = (2 - k / 3, 2 - k % 3);
        s += &format!("v {} 0 {}\n", i as f32 - 1.0, j as f32 - 1.0);
    }
    // The v statement of grid point (i, j), 1-based.
    let at = |i: i32, j: i32| (2 - i) * 3 + (2 - j) + 1;
    for i in 0..2 {
        for j in 0..2 {
            // Counter-clockwise seen from +y: (i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j).
            s += &format!(
                "f {} {} {} {}\n",
                at(i, j),
                at(i, j + 1),
                at(i + 1, j + 1),
                at(i + 1, j)
            );
        }
    }
    s += "o Lamp\nusemtl lamp\nv -0.25 1.5 -0.25\nv 0.25 1.5 -0.25\nv 0.25 1.5 0.25\nv -0.25 1.5 0.25\n";
    s += "f -4 -3 -2 -1\n";
    if fold {
        s += "o Fold\nusemtl white\n";
        s += "v 0.5 0.2 0.5\nv 0.5 0.2 0.8\nv 0.7 0.4 0.8\nv 0.7 0.4 0.5\nv 0.9 0.2 0.8\nv 0.9 0.2 0.5\n";
        s += "vn -0.7071 0.7071 0\nvn 0.7071 0.7071 0\n";
        s += "f 14//1 15//1 16//1 17//1\nf 17//2 16//2 18//2 19//2\n";
    }
    s
}

/// The OBJ's `v` statements, parsed as the loader reads them (f32).
fn v_statements(text: &str) -> Vec<[f32; 3]> {
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect()
}

/// Per mesh of the per-vertex `.glb`: its name, positions and source indices.
fn meshes(glb: &[u8]) -> Vec<(String, Vec<[f32; 3]>, Vec<u32>)> {
    let gltf = gltf::Gltf::from_slice(glb).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let semantic = gltf::Semantic::Extras(SOURCE_INDEX.trim_start_matches('_').into());
    gltf.meshes()
        .map(|m| {
            let p = m.primitives().next().unwrap();
            let positions = p.reader(|_| Some(blob)).read_positions().unwrap().collect();
            let (_, acc) = p.attributes().find(|(s, _)| *s == semantic).unwrap();
            // Integers below 2^24 as floats, exactly.
            assert_eq!(acc.data_type(), gltf::accessor::DataType::F32);
            let sources = gltf::accessor::Iter::<f32>::new(acc, |_| Some(blob))
                .unwrap()
                .map(|f| {
                    assert_eq!(f.fract(), 0.0);
                    f as u32
                })
                .collect();
            (m.name().unwrap().to_owned(), positions, sources)
        })
        .collect()
}

/// Writes the OBJ (and its MTL) to `dir`, solves it and bakes the per-vertex `.glb`.
fn bake(dir: &std::path::Path, text: &str) -> Vec<u8> {
    std::fs::write(
        dir.join("room.mtl"),
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n",
    )
    .unwrap();
    let path = dir.join("room.obj");
    std::fs::write(&path, text).unwrap();
    let (scene, _) = twopass_scene::load(&path).unwrap();
    let solution = solve(&scene, 0.2);
    let glb =
        bake::encode_vertex_glb(&solution, &scene, ColorMapping { exposure: 1.0 }, None).unwrap();
    glb.bytes
}

#[test]
fn an_obj_without_normals_comes_back_on_its_own_vertex_list() {
    let dir = tempfile::tempdir().unwrap();
    let text = obj(false);
    let v = v_statements(&text);
    assert_eq!(v.len(), 13);
    let glb = bake(dir.path(), &text);
    assert_valid("room.vertex.glb", &glb);
    let meshes = meshes(&glb);
    // As many vertices as `v` statements, in their order, each at its statement bit for bit
    // (the OBJ is in metres, the .glb too).
    let sources: Vec<u32> = meshes.iter().flat_map(|m| m.2.clone()).collect();
    assert_eq!(sources, (0..13).collect::<Vec<u32>>());
    let positions: Vec<[f32; 3]> = meshes.iter().flat_map(|m| m.1.clone()).collect();
    assert_eq!(positions, v);
}

#[test]
fn a_vertex_split_by_the_users_normals_names_its_v_statement() {
    let dir = tempfile::tempdir().unwrap();
    let text = obj(true);
    let v = v_statements(&text);
    let glb = bake(dir.path(), &text);
    assert_valid("fold.vertex.glb", &glb);
    let meshes = meshes(&glb);
    let (_, positions, sources) = meshes.iter().find(|m| m.0 == "Fold").unwrap();
    // Six v statements (0-based 13 to 18); the two on the shared edge (16 and 17, 0-based 15
    // and 16) have two normals each, so two vertices each, both naming their statement.
    assert_eq!(*sources, [13, 14, 15, 15, 16, 16, 17, 18]);
    for (p, &s) in positions.iter().zip(sources) {
        assert_eq!(*p, v[s as usize], "vertex of v statement {s}");
    }
}
