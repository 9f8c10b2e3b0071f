//! A scene for instancing tests: grey boxes on a floor under an emissive square, written as
//! glTF with every box node showing one mesh (instancing) or each its own copy of it.

use std::path::{Path, PathBuf};

use crate::gltf::{GltfWriter, MaterialSpec, Trs};

/// A closed box from (0, 0, 0) to (1, 1, 1): 8 corners, 12 outward-facing triangles.
pub fn unit_box() -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    #[rustfmt::skip]
    let idx = vec![
        0, 2, 1, 1, 2, 3, // z = 0, facing -z
        4, 5, 6, 5, 7, 6, // z = 1
        0, 1, 4, 1, 5, 4, // y = 0
        2, 6, 3, 3, 6, 7, // y = 1
        0, 4, 2, 2, 4, 6, // x = 0
        1, 3, 5, 3, 7, 5, // x = 1
    ];
    (p, idx)
}

/// A quaternion (x, y, z, w) of `degrees` about unit `axis`.
pub fn turn(axis: [f32; 3], degrees: f32) -> [f32; 4] {
    let l = axis.iter().map(|a| a * a).sum::<f32>().sqrt();
    let h = degrees.to_radians() / 2.0;
    let s = h.sin() / l;
    [axis[0] * s, axis[1] * s, axis[2] * s, h.cos()]
}

/// The placements of the boxes: turned about tilted axes, scaled unevenly, one mirrored.
pub fn placements(n: usize) -> Vec<Trs> {
    (0..n)
        .map(|i| {
            let f = i as f32;
            Trs {
                t: [
                    -4.0 + 1.7 * (i % 5) as f32,
                    // Off the floor: no face of a box lies in the floor's plane.
                    0.1 + 0.3 * (i % 3) as f32,
                    -4.0 + 1.9 * (i / 5 % 5) as f32,
                ],
                r: turn([0.3, 1.0, 0.1 * f], 17.0 * f),
                s: [
                    0.5 + 0.1 * (i % 4) as f32,
                    if i % 7 == 3 { -0.8 } else { 0.8 },
                    0.6 + 0.05 * f,
                ],
            }
        })
        .collect()
}

/// A room of grey boxes on a floor under an emissive square: with `shared`, every box node
/// shows one mesh; without, each has its own mesh of the same data.
pub fn boxes_room(dir: &Path, copies: usize, shared: bool) -> PathBuf {
    let mut w = GltfWriter::new();
    let grey = w.material(
        "Grey",
        MaterialSpec {
            base: [0.6, 0.6, 0.6],
            ..MaterialSpec::default()
        },
    );
    let lamp = w.material(
        "Lamp",
        MaterialSpec {
            base: [0.0, 0.0, 0.0],
            emissive: [1.0, 1.0, 1.0],
            strength: Some(20.0),
            ..MaterialSpec::default()
        },
    );
    let floor = [
        [-6.0, 0.0, -6.0],
        [-6.0, 0.0, 6.0],
        [6.0, 0.0, 6.0],
        [6.0, 0.0, -6.0],
    ];
    let floor = w.mesh(
        "Floor",
        &floor,
        None,
        None,
        None,
        &[0, 1, 2, 0, 2, 3],
        Some(grey),
    );
    let light = [
        [-1.0, 6.0, -1.0],
        [1.0, 6.0, -1.0],
        [1.0, 6.0, 1.0],
        [-1.0, 6.0, 1.0],
    ];
    let light = w.mesh(
        "Light",
        &light,
        None,
        None,
        None,
        &[0, 1, 2, 0, 2, 3],
        Some(lamp),
    );
    let (p, idx) = unit_box();
    let mut roots = vec![
        w.node("Floor", Some(floor), None, Trs::default(), vec![]),
        w.node("Light", Some(light), None, Trs::default(), vec![]),
    ];
    let shared_box = w.mesh("Box", &p, None, None, None, &idx, Some(grey));
    for (i, trs) in placements(copies).into_iter().enumerate() {
        let mesh = if shared {
            shared_box
        } else {
            w.mesh(&format!("Box{i}"), &p, None, None, None, &idx, Some(grey))
        };
        roots.push(w.node(&format!("Box {i}"), Some(mesh), None, trs, vec![]));
    }
    let camera = w.camera(0.9, Some(1.0));
    roots.push(w.node(
        "Eye",
        None,
        Some(camera),
        Trs {
            t: [0.0, 4.0, 12.0],
            r: turn([1.0, 0.0, 0.0], -15.0),
            ..Trs::default()
        },
        vec![],
    ));
    let path = dir.join(if shared { "shared.glb" } else { "copied.glb" });
    std::fs::write(&path, w.glb(roots)).unwrap();
    path
}
