//! The bake file: a radiosity [`Solution`] that loads back bit for bit (layout in the crate
//! docs).

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_radiosity::element::{ElementMesh, Node, Vertex};
use twopass_scene::Scene;

use crate::error::{BakeError, BakeProblem};
use crate::fingerprint::{Fingerprint, geometry_fingerprint, lighting_fingerprint};

/// Version of the bake file layout written by [`encode_bake`]; readers refuse other versions.
/// Version 2 added the focused caustic part ([`Solution::focused_caustics`]).
pub const BAKE_FORMAT_VERSION: u32 = 2;

const MAGIC: [u8; 8] = *b"\x89TPBAKE\n";
const HEADER_LEN: usize = 24;

#[derive(Serialize, Deserialize)]
struct VertexRecord {
    position: [f32; 3],
    normal: [f32; 3],
    triangle: u32,
    object: u32,
}

#[derive(Serialize, Deserialize)]
struct NodeRecord {
    vertices: [u32; 3],
    uv: [[f32; 2]; 3],
    children: Option<[u32; 2]>,
    scene_triangle: u32,
    patch: u32,
    area: f32,
}

#[derive(Serialize, Deserialize)]
struct BakePayload {
    geometry: u64,
    lighting: u64,
    vertices: Vec<VertexRecord>,
    nodes: Vec<NodeRecord>,
    roots: Vec<u32>,
    patches: Vec<u32>,
    radiosity: Vec<[f32; 3]>,
    direct: Vec<[f32; 3]>,
    indirect: Vec<[f32; 3]>,
    ambient: Vec<[f32; 3]>,
    /// Empty when the solve did not separate the focused caustics.
    focused: Vec<[f32; 3]>,
}

fn rgb_records(values: &[Rgb]) -> Vec<[f32; 3]> {
    values.iter().map(|v| v.to_array()).collect()
}

/// Encodes a solution of `scene` as a bake file (layout in the module docs).
pub fn encode_bake(solution: &Solution, scene: &Scene) -> Result<Vec<u8>, BakeError> {
    let mesh = solution.mesh();
    let payload = BakePayload {
        geometry: geometry_fingerprint(scene),
        lighting: lighting_fingerprint(scene),
        vertices: mesh
            .vertices
            .iter()
            .map(|v| VertexRecord {
                position: v.position.to_array(),
                normal: v.normal.to_array(),
                triangle: v.triangle,
                object: v.object,
            })
            .collect(),
        nodes: mesh
            .nodes
            .iter()
            .map(|n| NodeRecord {
                vertices: n.vertices,
                uv: n.uv.map(|c| c.to_array()),
                children: n.children,
                scene_triangle: n.scene_triangle,
                patch: n.patch,
                area: n.area,
            })
            .collect(),
        roots: mesh.roots.clone(),
        patches: mesh.patches.clone(),
        radiosity: rgb_records(solution.shot_radiosity()),
        direct: rgb_records(solution.direct()),
        indirect: rgb_records(solution.indirect()),
        ambient: rgb_records(solution.ambient()),
        focused: rgb_records(solution.focused_caustics().unwrap_or_default()),
    };
    let body = postcard::to_stdvec(&payload).map_err(|e| BakeError::Encode {
        path: PathBuf::from("bake"),
        message: e.to_string(),
    })?;
    let mut out = Vec::with_capacity(HEADER_LEN + body.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&BAKE_FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
    out.extend_from_slice(&body);
    Ok(out)
}

fn le_u32(b: &[u8]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fn rgb_values(what: &'static str, v: Vec<[f32; 3]>, n: usize) -> Result<Vec<Rgb>, BakeProblem> {
    if v.len() != n {
        return Err(BakeProblem::Values {
            what,
            index: v.len(),
            problem: "length differs from the vertex count",
        });
    }
    v.into_iter()
        .enumerate()
        .map(|(i, c)| {
            let c = Vec3::from_array(c);
            if c.is_finite() {
                Ok(c)
            } else {
                Err(BakeProblem::Values {
                    what,
                    index: i,
                    problem: "not finite",
                })
            }
        })
        .collect()
}

/// Decodes a bake file for `scene`, checking its header, checksum, fingerprints and mesh. The
/// result equals the encoded solution bit for bit.
pub fn decode_bake(bytes: &[u8], scene: &Scene) -> Result<Solution, BakeProblem> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return Err(BakeProblem::NotABakeFile);
    }
    if bytes.len() < HEADER_LEN {
        return Err(BakeProblem::Truncated {
            expected: HEADER_LEN as u64,
            found: bytes.len() as u64,
        });
    }
    let version = le_u32(&bytes[8..12]);
    if version != BAKE_FORMAT_VERSION {
        return Err(BakeProblem::UnsupportedVersion {
            found: version,
            supported: BAKE_FORMAT_VERSION,
        });
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 header bytes"));
    let stored = le_u32(&bytes[20..24]);
    let body = &bytes[HEADER_LEN..];
    let found = body.len() as u64;
    if found < len {
        return Err(BakeProblem::Truncated {
            expected: HEADER_LEN as u64 + len,
            found: bytes.len() as u64,
        });
    }
    if found > len {
        return Err(BakeProblem::TrailingBytes { extra: found - len });
    }
    let computed = crc32fast::hash(body);
    if computed != stored {
        return Err(BakeProblem::Checksum { stored, computed });
    }
    let p: BakePayload = postcard::from_bytes(body).map_err(|e| BakeProblem::Decode {
        message: e.to_string(),
    })?;
    for (what, bake, scene) in [
        (
            Fingerprint::Geometry,
            p.geometry,
            geometry_fingerprint(scene),
        ),
        (
            Fingerprint::Lighting,
            p.lighting,
            lighting_fingerprint(scene),
        ),
    ] {
        if bake != scene {
            return Err(BakeProblem::SceneMismatch { what, scene, bake });
        }
    }
    if p.roots.len() != scene.mesh.triangle_count() {
        return Err(BakeProblem::Values {
            what: "roots",
            index: p.roots.len(),
            problem: "length differs from the scene's triangle count",
        });
    }
    let n = p.vertices.len();
    let mut vertices = Vec::with_capacity(n);
    for (i, v) in p.vertices.into_iter().enumerate() {
        if v.object as usize >= scene.objects.len() {
            return Err(BakeProblem::Values {
                what: "vertices",
                index: i,
                problem: "object index out of range",
            });
        }
        vertices.push(Vertex {
            position: Vec3::from_array(v.position),
            normal: Vec3::from_array(v.normal),
            triangle: v.triangle,
            object: v.object,
        });
    }
    let nodes = p
        .nodes
        .into_iter()
        .map(|r| Node {
            vertices: r.vertices,
            uv: r.uv.map(Vec2::from_array),
            children: r.children,
            scene_triangle: r.scene_triangle,
            patch: r.patch,
            area: r.area,
        })
        .collect();
    let mesh =
        ElementMesh::from_parts(vertices, nodes, p.roots, p.patches).map_err(BakeProblem::Mesh)?;
    let focused = if p.focused.is_empty() {
        Vec::new()
    } else {
        rgb_values("focused", p.focused, n)?
    };
    Ok(Solution::new(
        mesh,
        rgb_values("radiosity", p.radiosity, n)?,
        rgb_values("direct", p.direct, n)?,
        rgb_values("indirect", p.indirect, n)?,
        rgb_values("ambient", p.ambient, n)?,
    )
    .with_focused_caustics(focused))
}

/// Largest bake file read, bytes (4 GiB: far above the bake of
/// [`twopass_radiosity::MAX_ELEMENTS`]).
pub const MAX_BAKE_BYTES: u64 = 4 << 30;

/// Reads the bake file at `path` for `scene` (see [`decode_bake`]).
pub fn read_bake(path: &Path, scene: &Scene) -> Result<Solution, BakeError> {
    let bytes =
        twopass_scene::read_bounded(path, MAX_BAKE_BYTES).map_err(|e| BakeError::io(path, e))?;
    decode_bake(&bytes, scene).map_err(|problem| BakeError::Invalid {
        path: path.to_owned(),
        problem,
    })
}
