//! Every `.glb` the bake writes passes the Khronos glTF-Validator (the npm package
//! `gltf-validator`, installed by `npm ci --prefix tests/node`) with 0 errors and 0 warnings.
//!
//! With `CI` set, a missing `node` or validator package fails the test; elsewhere the test
//! prints a note and passes without validating, so `cargo test` works on a machine without
//! Node.

use std::process::Command;
use std::sync::OnceLock;

use twopass_bake::{self as bake, BakeError, ColorMapping, Glb};
use twopass_radiosity::Solution;
use twopass_scene::Scene;

use crate::common::{cornell, repo};

/// The Cornell box, solved coarsely (the validator checks structure, not accuracy).
fn solved() -> &'static (Scene, Solution) {
    static SOLVED: OnceLock<(Scene, Solution)> = OnceLock::new();
    SOLVED.get_or_init(|| cornell(100.0))
}

/// The validator's report of `bytes`, or `None` (after a note) when the validator is not
/// installed and `CI` is not set.
fn validate(name: &str, bytes: &[u8]) -> Option<serde_json::Value> {
    let script = repo().join("tests/node/validate.mjs");
    let package = repo().join("tests/node/node_modules/gltf-validator/package.json");
    let node = Command::new("node").arg("--version").output();
    let missing = match (&node, package.exists()) {
        (Ok(out), true) if out.status.success() => None,
        (Ok(out), _) if out.status.success() => Some(format!(
            "the gltf-validator package is not installed ({} missing; run `npm ci --prefix \
             tests/node`)",
            package.display()
        )),
        _ => Some("`node` is not on PATH".to_owned()),
    };
    if let Some(why) = missing {
        if std::env::var_os("CI").is_some() {
            panic!("glTF-Validator cannot run in CI: {why}");
        }
        eprintln!("note: {name} not validated: {why}");
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let out = Command::new("node")
        .arg(&script)
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "validator failed on {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// Validates `bytes` (as [`validate`]) and asserts the report has no error and no warning,
/// printing it otherwise; returns the report for further checks.
pub(crate) fn assert_valid(name: &str, bytes: &[u8]) -> Option<serde_json::Value> {
    let report = validate(name, bytes)?;
    let issues = &report["issues"];
    let errors = issues["numErrors"].as_u64().unwrap();
    let warnings = issues["numWarnings"].as_u64().unwrap();
    assert!(
        errors == 0 && warnings == 0,
        "{name}: {errors} errors, {warnings} warnings:\n{}",
        serde_json::to_string_pretty(&report).unwrap()
    );
    // The validator did read the file: it counted the meshes' vertices.
    assert!(
        report["info"]["totalVertexCount"].as_u64().unwrap() > 0,
        "{report}"
    );
    Some(report)
}

#[test]
fn element_mesh_and_per_vertex_glbs_pass_the_khronos_validator() {
    type Encode = fn(&Solution, &Scene, ColorMapping) -> Result<Glb, BakeError>;
    let (scene, solution) = solved();
    let encoders: [(&str, Encode); 2] = [
        ("cornell-box.glb", bake::encode_glb),
        ("cornell-box.vertex.glb", |s, scene, m| {
            bake::encode_vertex_glb(s, scene, m, None)
        }),
    ];
    for (name, encode) in encoders {
        let glb = encode(solution, scene, ColorMapping::auto(solution)).unwrap();
        assert_valid(name, &glb.bytes);
    }
}

#[test]
fn lightmap_glb_passes_the_khronos_validator() {
    let (scene, solution) = solved();
    let settings = twopass_bake::LightmapSettings {
        texel_size: Some(10.0),
        padding: 2,
        quantity: None,
        ..Default::default()
    };
    let lm = bake::bake_lightmap(
        bake::TexelSource::Solution(solution),
        scene,
        &settings,
        ColorMapping::auto(solution),
    )
    .unwrap();
    if let Some(report) = assert_valid("cornell-box.lightmap.glb", &lm.glb) {
        assert_eq!(report["info"]["hasTextures"], true, "{report}");
        assert_eq!(report["info"]["maxUVs"], 2, "{report}");
    }
}

#[test]
fn validator_reports_a_broken_glb() {
    // The check can fail: an index past the vertex count is an error the validator reports.
    let (scene, solution) = solved();
    let glb = bake::encode_glb(solution, scene, ColorMapping::auto(solution)).unwrap();
    let mut bytes = glb.bytes.clone();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin = 20 + json_len + 8;
    // The last four bytes of the binary chunk are the last mesh's last index (u32).
    let end = bytes.len();
    assert!(end > bin + 4);
    bytes[end - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
    if let Some(report) = validate("broken.glb", &bytes) {
        assert!(
            report["issues"]["numErrors"].as_u64().unwrap() > 0,
            "{}",
            serde_json::to_string_pretty(&report).unwrap()
        );
    }
}
