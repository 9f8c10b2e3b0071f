//! The scene's camera as a glTF camera node: in the lightmap `.glb` (the Cornell box, its
//! camera at the eye, its rotation taking the glTF camera's -Z to the view the asset extras
//! record) and in the user's asset written back (added when the scene was framed by the default
//! camera, the user's own camera node kept as it was and not repeated).

use glam::{Quat, Vec3};
use serde_json::Value;
use twopass_bake::ColorMapping;
use twopass_bake::lightmap::{CAMERA_NAME, LightmapSettings, TexelSource, bake_lightmap};
use twopass_tests::gltf::Trs;

use crate::asset::{baked, room, room_document};
use crate::common::cornell;
use crate::validator::assert_valid;

/// The JSON chunk of a `.glb`.
fn json_of(glb: &[u8]) -> Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

fn vec3(v: &Value) -> Vec3 {
    Vec3::from_array([0, 1, 2].map(|k| v[k].as_f64().unwrap() as f32))
}

/// The nodes of the document's scene that show a camera, as (node, camera) JSON.
fn camera_nodes(doc: &Value) -> Vec<(usize, Value)> {
    let shown = doc["scene"].as_u64().unwrap_or(0) as usize;
    let roots = doc["scenes"][shown]["nodes"].as_array().unwrap();
    doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, n)| n.get("camera").is_some())
        .map(|(i, n)| {
            // Every camera node here is a root of the scene shown (none is orphaned).
            assert!(roots.contains(&Value::from(i)), "{i}: {n}");
            (i, n.clone())
        })
        .collect()
}

/// The rotation of a node (identity without one).
fn rotation(node: &Value) -> Quat {
    match node.get("rotation") {
        Some(r) => Quat::from_array([0, 1, 2, 3].map(|k| r[k].as_f64().unwrap() as f32)),
        None => Quat::IDENTITY,
    }
}

#[test]
fn the_lightmap_glb_holds_the_scene_camera_as_a_gltf_camera_node() {
    let (scene, solution) = cornell(100.0);
    let settings = LightmapSettings {
        texel_size: Some(10.0),
        ..LightmapSettings::default()
    };
    let lm = bake_lightmap(
        TexelSource::Solution(&solution),
        &scene,
        &settings,
        ColorMapping::auto(&solution),
    )
    .unwrap();
    assert_valid("cornell-box.lightmap.glb", &lm.glb);
    let doc = json_of(&lm.glb);
    let nodes = camera_nodes(&doc);
    assert_eq!(nodes.len(), 1, "{doc}");
    let (_, node) = &nodes[0];
    assert_eq!(node["name"], CAMERA_NAME);
    let camera = &doc["cameras"][node["camera"].as_u64().unwrap() as usize];
    assert_eq!(camera["type"], "perspective");
    let p = &camera["perspective"];
    // The record the viewer reads (degrees, metres) and the camera node say the same.
    let record = &doc["asset"]["extras"]["twopass"]["camera"];
    let fov = record["vertical_fov_degrees"]
        .as_f64()
        .unwrap()
        .to_radians();
    assert!((p["yfov"].as_f64().unwrap() - fov).abs() < 1e-6, "{p}");
    let aspect = record["width"].as_f64().unwrap() / record["height"].as_f64().unwrap();
    assert!(
        (p["aspectRatio"].as_f64().unwrap() - aspect).abs() < 1e-6,
        "{p}"
    );
    // The scene's box fits between the planes: its 0.55 m box gives znear 0.55 mm or so.
    let diagonal = f64::from(scene.bounds.diagonal()) * scene.unit.metres();
    let znear = p["znear"].as_f64().unwrap();
    assert!((znear - diagonal / 1000.0).abs() < 1e-9, "{p}");
    assert!(p["zfar"].as_f64().unwrap() > diagonal, "{p}");
    let eye = vec3(&record["position"]);
    assert!((vec3(&node["translation"]) - eye).length() < 1e-6, "{node}");
    // The node's rotation takes the camera's -Z to the view direction and +Y to up.
    let q = rotation(node);
    let view = (vec3(&record["target"]) - eye).normalize();
    assert!((q * Vec3::NEG_Z - view).length() < 1e-5, "{node} vs {view}");
    assert!(
        (q * Vec3::Y - vec3(&record["up"])).length() < 1e-5,
        "{node}"
    );
    assert!((q * Vec3::NEG_Z - scene.camera.forward).length() < 1e-5);
}

#[test]
fn the_asset_gets_the_default_camera_once_and_keeps_the_users_own() {
    let dir = tempfile::tempdir().unwrap();
    // Without a camera of its own: the framing camera is added, one node at the root.
    let (scene, lm) = baked(&room(false), dir.path());
    let asset = lm.asset.as_ref().unwrap();
    let doc = json_of(asset);
    let nodes = camera_nodes(&doc);
    assert_eq!(nodes.len(), 1, "{doc}");
    let (index, node) = &nodes[0];
    assert_eq!(node["name"], CAMERA_NAME);
    assert_eq!(doc["asset"]["extras"]["twopass"]["camera_node"], *index);
    let q = rotation(node);
    assert!((q * Vec3::NEG_Z - scene.camera.forward).length() < 1e-5);
    assert!((vec3(&node["translation"]) - scene.camera.position).length() < 1e-5);

    // With the user's camera (turned a quarter about y under its node, so it looks down -x):
    // that node is the scene's camera, and comes back untouched, with no second one.
    let (mut w, mut roots) = room_document(false);
    let camera = w.camera(0.7, Some(2.0));
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let eye = w.node(
        "Eye",
        None,
        Some(camera),
        Trs {
            t: [1.5, 0.8, 0.1],
            r: [0.0, h, 0.0, h],
            ..Trs::default()
        },
        vec![],
    );
    roots.push(eye);
    let input = w.glb(roots);
    let (scene, lm) = baked(&input, dir.path());
    assert!((scene.camera.forward - Vec3::NEG_X).length() < 1e-6);
    let asset = lm.asset.as_ref().unwrap();
    assert_valid("room-camera.lightmapped.glb", asset);
    let (before, after) = (json_of(&input), json_of(asset));
    assert_eq!(before["cameras"], after["cameras"]);
    let nodes = camera_nodes(&after);
    assert_eq!(nodes.len(), 1, "{after}");
    let (index, node) = &nodes[0];
    assert_eq!(*node, before["nodes"][*index]);
    assert_eq!(node["name"], "Eye");
    assert_eq!(after["asset"]["extras"]["twopass"]["camera_node"], *index);
}
