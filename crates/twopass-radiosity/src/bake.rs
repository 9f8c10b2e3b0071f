//! Bake I/O: a radiosity [`Solution`] written in formats that real-time engines and tools read,
//! and in a bake file that loads back into the same `Solution` so a later render needs no
//! solve.
//!
//! | output | what it holds | colour |
//! | --- | --- | --- |
//! | glTF 2.0 binary (`.glb`, [`encode_glb`]) | one mesh and node per scene object: `POSITION`, `NORMAL`, `COLOR_0`, `u32` indices; one unlit material (`KHR_materials_unlit`) so an engine displays `COLOR_0` as it is | `COLOR_0 = min(1, exposure * L)` per linear RGB channel (see [`ColorMapping`]) |
//! | PLY, binary little endian ([`encode_ply`]) | every element vertex (`x y z nx ny nz red green blue`, `float`) and every element (`vertex_indices`, `uint`) | raw radiance `L`, W/(m^2 sr) |
//! | bake file ([`encode_bake`], [`decode_bake`], [`read_bake`]) | the element mesh and the per-vertex radiosity parts, bit for bit, with fingerprints of the scene it belongs to | radiosity `B`, W/m^2 |
//! | manifest (JSON, [`Manifest`]) | settings, timings per phase, rays, counts, unshot fraction, energy, residuals, files | |
//!
//! Units: positions in scene units (not rescaled to metres; the Cornell box is in
//! millimetres), radiance `L = B / pi` in W/(m^2 sr), radiosity `B` in W/m^2 per channel.
//! Every file is written atomically ([`write_atomic`]): a temporary file in the target's folder,
//! synced, then renamed over the target, so a failed write never leaves a partial file.
//!
//! ## The bake file
//! A 24-byte header, then a [postcard](https://docs.rs/postcard) payload:
//!
//! | bytes | field |
//! | --- | --- |
//! | 0..8 | magic `\x89TPBAKE\n` |
//! | 8..12 | format version, `u32` little endian ([`BAKE_FORMAT_VERSION`]) |
//! | 12..20 | payload length in bytes, `u64` little endian |
//! | 20..24 | CRC-32 (IEEE) of the payload, `u32` little endian |
//!
//! The payload holds the scene's geometry and lighting fingerprints ([`geometry_fingerprint`],
//! [`lighting_fingerprint`]), the element mesh (vertices, tree nodes, roots, patches) and the
//! radiosity, direct, indirect and ambient parts per vertex as `f32` bit patterns. Reading checks
//! the header, the length, the checksum, the fingerprints against the scene it is loaded for and
//! every index of the mesh ([`ElementMesh::from_parts`]): a corrupt or foreign file is an
//! error, never a panic. The payload is decoded into private mirror structs rather than serde
//! derives on the solver's types, so the file format changes only when this module says so
//! (and bumps the version), and glam needs no serde feature.

use std::fmt;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use glam::{Vec2, Vec3};
use gltf_json as json;
use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Ply, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use serde::{Deserialize, Serialize};
use twopass_brdf::Rgb;
use twopass_scene::Scene;

use crate::element::{ElementMesh, Node, Vertex};
use crate::progressive::{Finish, Options, Progress, Residuals};
use crate::solution::Solution;

/// Version of the bake file layout written by [`encode_bake`]; readers refuse other versions.
pub const BAKE_FORMAT_VERSION: u32 = 1;

/// Version of the [`Manifest`] JSON layout.
pub const MANIFEST_VERSION: u32 = 1;

const MAGIC: [u8; 8] = *b"\x89TPBAKE\n";
const HEADER_LEN: usize = 24;

// ---------------------------------------------------------------------------------------------
// Errors

/// Which part of an element mesh failed validation (see [`InvalidMesh`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MeshPart {
    /// An entry of `ElementMesh::vertices`.
    Vertex,
    /// An entry of `ElementMesh::nodes`.
    Node,
    /// An entry of `ElementMesh::roots` (indexed by scene triangle).
    Root,
    /// An entry of `ElementMesh::patches` (indexed by patch id).
    Patch,
}

/// An element mesh whose parts do not fit together ([`ElementMesh::from_parts`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct InvalidMesh {
    /// Which array holds the offending entry.
    pub part: MeshPart,
    /// Its index in that array.
    pub index: usize,
    /// What is wrong with it.
    pub problem: &'static str,
}

impl InvalidMesh {
    /// An invalid entry `index` of `part`.
    pub fn new(part: MeshPart, index: usize, problem: &'static str) -> Self {
        Self {
            part,
            index,
            problem,
        }
    }
}

impl fmt::Display for InvalidMesh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let part = match self.part {
            MeshPart::Vertex => "vertex",
            MeshPart::Node => "node",
            MeshPart::Root => "root of scene triangle",
            MeshPart::Patch => "patch",
        };
        write!(f, "element mesh {part} {}: {}", self.index, self.problem)
    }
}

impl std::error::Error for InvalidMesh {}

/// Which scene fingerprint a bake file disagrees with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fingerprint {
    /// The triangles, positions and normals ([`geometry_fingerprint`]).
    Geometry,
    /// The objects' emission and diffuse reflectance ([`lighting_fingerprint`]).
    Lighting,
}

/// Why bytes are not a usable bake file for a scene.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum BakeProblem {
    /// The bytes do not start with the bake file's magic number.
    NotABakeFile,
    /// The file was written in another layout version.
    UnsupportedVersion {
        /// The version in the file.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The file is shorter than its header says.
    Truncated {
        /// Bytes the header announces (header included).
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The file is longer than its header says.
    TrailingBytes {
        /// Bytes after the payload.
        extra: u64,
    },
    /// The payload's CRC-32 differs from the stored one: the file was damaged.
    Checksum {
        /// CRC-32 in the header.
        stored: u32,
        /// CRC-32 of the payload as read.
        computed: u32,
    },
    /// The payload does not decode.
    Decode {
        /// The decoder's message.
        message: String,
    },
    /// The bake belongs to another scene (or a changed one).
    SceneMismatch {
        /// Which fingerprint differs.
        what: Fingerprint,
        /// The scene's fingerprint.
        scene: u64,
        /// The fingerprint stored in the bake.
        bake: u64,
    },
    /// The element mesh is inconsistent.
    Mesh(InvalidMesh),
    /// A per-vertex array has the wrong length or a non-finite value, or a vertex names an
    /// object the scene does not have.
    Values {
        /// Which array.
        what: &'static str,
        /// The offending index (or the length found, for a wrong length).
        index: usize,
        /// What is wrong.
        problem: &'static str,
    },
}

impl fmt::Display for BakeProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotABakeFile => write!(f, "not a twopass bake file (wrong magic number)"),
            Self::UnsupportedVersion { found, supported } => write!(
                f,
                "bake file version {found}, this build reads version {supported}: bake again"
            ),
            Self::Truncated { expected, found } => write!(
                f,
                "truncated bake file: {found} bytes, the header announces {expected}"
            ),
            Self::TrailingBytes { extra } => {
                write!(f, "bake file has {extra} bytes after its payload")
            }
            Self::Checksum { stored, computed } => write!(
                f,
                "damaged bake file: CRC-32 {computed:08x}, the header says {stored:08x}"
            ),
            Self::Decode { message } => write!(f, "bake payload does not decode: {message}"),
            Self::SceneMismatch { what, scene, bake } => {
                let what = match what {
                    Fingerprint::Geometry => "geometry",
                    Fingerprint::Lighting => "emission or diffuse reflectance",
                };
                write!(
                    f,
                    "bake was made for another scene: {what} fingerprint {bake:016x}, \
                     the scene's is {scene:016x}; bake the scene again"
                )
            }
            Self::Mesh(m) => write!(f, "{m}"),
            Self::Values {
                what,
                index,
                problem,
            } => write!(f, "bake {what} [{index}]: {problem}"),
        }
    }
}

impl std::error::Error for BakeProblem {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Mesh(m) => Some(m),
            _ => None,
        }
    }
}

/// A failed bake read or write, naming its file.
#[derive(Debug)]
#[non_exhaustive]
pub enum BakeError {
    /// Reading, writing or renaming the file failed.
    Io {
        /// The file (or folder) concerned.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not a usable bake for the scene.
    Invalid {
        /// The bake file.
        path: PathBuf,
        /// What is wrong with it.
        problem: BakeProblem,
    },
    /// An output could not be encoded.
    Encode {
        /// The file that was being written, or the format's name when encoding to memory.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

impl BakeError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            source,
        }
    }
}

impl fmt::Display for BakeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::Invalid { path, problem } => write!(f, "{}: {problem}", path.display()),
            Self::Encode { path, message } => {
                write!(f, "{}: cannot encode: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for BakeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Invalid { problem, .. } => Some(problem),
            Self::Encode { .. } => None,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Atomic writes

/// Writes `bytes` to `path` atomically: a temporary file in the same folder (which must
/// exist), synced to disk, then renamed over `path`, with the mode a new file would get. On any failure the temporary file is
/// removed and `path` is left as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), BakeError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".twopass-bake-").suffix(".tmp");
    // Temporary files are private (0600) by default; an output gets the usual mode
    // (0666 less the umask, as `File::create` would give it).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| BakeError::io(dir, e))?;
    tmp.write_all(bytes).map_err(|e| BakeError::io(path, e))?;
    tmp.as_file()
        .sync_all()
        .map_err(|e| BakeError::io(path, e))?;
    // On error the returned temporary file is dropped, which deletes it.
    tmp.persist(path)
        .map_err(|e| BakeError::io(path, e.error))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Fingerprints

/// 64-bit FNV-1a: a stable, platform-independent hash for fingerprints (not for security).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn u32(&mut self, x: u32) {
        self.bytes(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.bytes(&x.to_le_bytes());
    }
    fn vec3(&mut self, v: Vec3) {
        for c in v.to_array() {
            self.u32(c.to_bits());
        }
    }
}

/// Fingerprint of what the element mesh is built on: every triangle's position and normal
/// indices, every position and normal (bit patterns), and each triangle's object. A bake is
/// refused for a scene whose fingerprint differs.
pub fn geometry_fingerprint(scene: &Scene) -> u64 {
    let m = &scene.mesh;
    let mut h = Fnv::new();
    h.u64(m.positions.len() as u64);
    m.positions.iter().for_each(|&p| h.vec3(p));
    h.u64(m.normals.len() as u64);
    m.normals.iter().for_each(|&n| h.vec3(n));
    h.u64(m.triangles.len() as u64);
    for t in 0..m.triangles.len() {
        m.triangles[t].iter().for_each(|&i| h.u32(i));
        m.normal_indices[t].iter().for_each(|&i| h.u32(i));
        h.u32(m.triangle_object[t]);
    }
    h.0
}

/// Fingerprint of what the radiosity values depend on besides geometry: each object's emitted
/// radiance and its material's diffuse reflectance (bit patterns), in object order.
pub fn lighting_fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    h.u64(scene.objects.len() as u64);
    for o in &scene.objects {
        h.vec3(o.emission);
        let rho = scene
            .materials
            .get(o.material as usize)
            .map_or(Vec3::ZERO, |m| m.material.diffuse_albedo());
        h.vec3(rho);
    }
    h.0
}

// ---------------------------------------------------------------------------------------------
// The bake file

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
    if p.roots.len() != scene.mesh.triangles.len() {
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
    Ok(Solution::new(
        mesh,
        rgb_values("radiosity", p.radiosity, n)?,
        rgb_values("direct", p.direct, n)?,
        rgb_values("indirect", p.indirect, n)?,
        rgb_values("ambient", p.ambient, n)?,
    ))
}

/// Largest bake file read, bytes (4 GiB: far above the bake of [`crate::MAX_ELEMENTS`]).
pub const MAX_BAKE_BYTES: u64 = 4 << 30;

/// Reads the bake file at `path` for `scene` (see [`decode_bake`]); only a regular file of at
/// most [`MAX_BAKE_BYTES`] is read.
pub fn read_bake(path: &Path, scene: &Scene) -> Result<Solution, BakeError> {
    let bytes =
        twopass_scene::read_bounded(path, MAX_BAKE_BYTES).map_err(|e| BakeError::io(path, e))?;
    decode_bake(&bytes, scene).map_err(|problem| BakeError::Invalid {
        path: path.to_owned(),
        problem,
    })
}

// ---------------------------------------------------------------------------------------------
// Colour mapping for glTF

/// How radiance becomes glTF `COLOR_0`, a linear multiplier that engines expect in [0, 1]:
/// `COLOR_0 = min(1, exposure * L)` per linear RGB channel, with `L = B / pi` the radiance
/// leaving the surface in W/(m^2 sr). Negative values (rounding) become 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColorMapping {
    /// Multiplier on radiance, sr m^2 / W (1 / the radiance that maps to white).
    pub exposure: f32,
}

/// Percentile of the vertices' radiance luminance that [`ColorMapping::auto`] maps to 1.
pub const AUTO_EXPOSURE_PERCENTILE: f64 = 0.99;

impl ColorMapping {
    /// An exposure that maps the 99th percentile (over vertices) of the displayed radiance's
    /// luminance (Rec. 709 weights) to 1, so that only the brightest percent (typically the
    /// emitters) saturates. 1 when everything is black.
    pub fn auto(solution: &Solution) -> Self {
        let mut lum: Vec<f32> = solution
            .vertex_radiosity()
            .iter()
            .map(|b| luminance(*b) * std::f32::consts::FRAC_1_PI)
            .filter(|l| l.is_finite() && *l > 0.0)
            .collect();
        if lum.is_empty() {
            return Self { exposure: 1.0 };
        }
        let k = ((lum.len() - 1) as f64 * AUTO_EXPOSURE_PERCENTILE).round() as usize;
        let (_, &mut at, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
        Self { exposure: 1.0 / at }
    }

    /// `COLOR_0` of a radiance `l` (W/(m^2 sr)), and whether a channel was clipped at 1.
    pub fn color(&self, l: Rgb) -> (Rgb, bool) {
        let c = (l * self.exposure).max(Vec3::ZERO);
        (c.min(Vec3::ONE), c.max_element() > 1.0)
    }

    /// The mapping as a formula, as recorded in the manifest and the glTF asset extras.
    pub const FORMULA: &'static str = "COLOR_0 = min(1, exposure * L) per linear RGB channel, \
         L = B / pi the radiance leaving the surface in W/(m^2 sr)";
}

fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

// ---------------------------------------------------------------------------------------------
// glTF binary

/// An encoded `.glb` and what the colour mapping did.
#[derive(Debug, Clone)]
pub struct Glb {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// Vertices (as written, per object) with a channel clipped at 1.
    pub clamped_vertices: usize,
    /// Vertices written (a mesh vertex shared by two objects is written once per object).
    pub vertices: usize,
    /// Triangles (elements) written.
    pub triangles: usize,
}

/// One object's part of the glb: local vertex list (mesh vertex ids) and local indices.
struct ObjectPart {
    object: u32,
    vertices: Vec<u32>,
    indices: Vec<u32>,
}

/// Groups the displayed elements by scene object, each with its own compact vertex list in
/// ascending mesh-vertex order and its triangles in node order.
fn object_parts(mesh: &ElementMesh, scene: &Scene) -> Vec<ObjectPart> {
    let n_obj = scene.objects.len();
    let mut leaves_of: Vec<Vec<u32>> = vec![Vec::new(); n_obj];
    for leaf in mesh.leaves() {
        let t = mesh.nodes[leaf as usize].scene_triangle as usize;
        let o = scene.mesh.triangle_object.get(t).map_or(0, |&o| o as usize);
        if o < n_obj {
            leaves_of[o].push(leaf);
        }
    }
    let mut local = vec![u32::MAX; mesh.vertices.len()];
    let mut parts = Vec::new();
    for (o, leaves) in leaves_of.into_iter().enumerate() {
        if leaves.is_empty() {
            continue;
        }
        let mut vertices: Vec<u32> = leaves
            .iter()
            .flat_map(|&l| mesh.nodes[l as usize].vertices)
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        for (i, &v) in vertices.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        let indices = leaves
            .iter()
            .flat_map(|&l| mesh.nodes[l as usize].vertices.map(|v| local[v as usize]))
            .collect();
        parts.push(ObjectPart {
            object: o as u32,
            vertices,
            indices,
        });
    }
    parts
}

fn f32_bytes(out: &mut Vec<u8>, values: impl IntoIterator<Item = f32>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The glTF asset extras: how to read `COLOR_0` back as radiance.
#[derive(Serialize)]
struct GlbExtras<'a> {
    twopass: GlbExtrasBody<'a>,
}

#[derive(Serialize)]
struct GlbExtrasBody<'a> {
    color_0: &'static str,
    exposure: f32,
    radiance_unit: &'static str,
    position_unit: &'static str,
    clamped_vertices: usize,
    scene: &'a str,
}

/// Encodes the solution's displayed radiance (ambient included) as a glTF 2.0 binary: one
/// mesh and node per scene object (named after it) with `POSITION` (scene units), unit
/// `NORMAL`, `COLOR_0` from `mapping` and `u32` indices, all sharing one unlit material
/// (`KHR_materials_unlit`, white base colour) so engines show `COLOR_0` without relighting.
/// The mapping is recorded in the asset's `extras.twopass`. Meshes come in object order
/// (objects without elements are left out); each lists the mesh vertices its elements use in
/// ascending vertex order and its elements in node order.
pub fn encode_glb(
    solution: &Solution,
    scene: &Scene,
    mapping: ColorMapping,
) -> Result<Glb, BakeError> {
    use json::validation::Checked::Valid;
    use json::validation::USize64;

    let mesh = solution.mesh();
    let radiance: Vec<Rgb> = solution
        .vertex_radiosity()
        .iter()
        .map(|b| *b * std::f32::consts::FRAC_1_PI)
        .collect();
    let parts = object_parts(mesh, scene);
    let mut root = json::Root::default();
    let mut bin: Vec<u8> = Vec::new();
    let mut clamped_vertices = 0;
    let (mut n_vertices, mut n_triangles) = (0, 0);
    // The extension struct's fields depend on which gltf-json features the build enables.
    #[allow(clippy::needless_update)]
    let material = root.push(json::Material {
        name: Some("twopass baked radiance (unlit, COLOR_0)".into()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor([1.0; 4]),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(1.0),
            ..Default::default()
        },
        extensions: Some(json::extensions::material::Material {
            unlit: Some(json::extensions::material::Unlit {}),
            ..Default::default()
        }),
        ..Default::default()
    });
    let mut scene_nodes = Vec::new();
    for part in &parts {
        let n = part.vertices.len();
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut attrs: [Vec<u8>; 3] = Default::default();
        for &v in &part.vertices {
            let vert = &mesh.vertices[v as usize];
            min = min.min(vert.position);
            max = max.max(vert.position);
            f32_bytes(&mut attrs[0], vert.position.to_array());
            let normal = vert.normal.try_normalize().unwrap_or(Vec3::Z);
            f32_bytes(&mut attrs[1], normal.to_array());
            let (c, clipped) = mapping.color(radiance[v as usize]);
            clamped_vertices += usize::from(clipped);
            f32_bytes(&mut attrs[2], c.to_array());
        }
        let mut indices = Vec::with_capacity(part.indices.len() * 4);
        for &i in &part.indices {
            indices.extend_from_slice(&i.to_le_bytes());
        }
        n_vertices += n;
        n_triangles += part.indices.len() / 3;
        // Every view is a multiple of 4 bytes long, so all offsets stay 4-byte aligned.
        let mut view = |root: &mut json::Root, data: &[u8], target| {
            let offset = bin.len();
            bin.extend_from_slice(data);
            root.push(json::buffer::View {
                buffer: json::Index::new(0),
                byte_length: USize64::from(data.len()),
                byte_offset: Some(USize64::from(offset)),
                byte_stride: None,
                extensions: None,
                extras: None,
                name: None,
                target: Some(Valid(target)),
            })
        };
        let views = [
            view(&mut root, &attrs[0], json::buffer::Target::ArrayBuffer),
            view(&mut root, &attrs[1], json::buffer::Target::ArrayBuffer),
            view(&mut root, &attrs[2], json::buffer::Target::ArrayBuffer),
            view(
                &mut root,
                &indices,
                json::buffer::Target::ElementArrayBuffer,
            ),
        ];
        let accessor = |root: &mut json::Root, view, count, ty, component, bounds: Option<_>| {
            let (min, max) = match bounds {
                Some((a, b)) => (Some(a), Some(b)),
                None => (None, None),
            };
            root.push(json::Accessor {
                buffer_view: Some(view),
                byte_offset: Some(USize64(0)),
                count: USize64::from(count),
                component_type: Valid(json::accessor::GenericComponentType(component)),
                extensions: None,
                extras: None,
                type_: Valid(ty),
                min,
                max,
                name: None,
                normalized: false,
                sparse: None,
            })
        };
        use json::accessor::{ComponentType as C, Type as T};
        let bounds = (
            json::Value::from(min.to_array().to_vec()),
            json::Value::from(max.to_array().to_vec()),
        );
        let positions = accessor(&mut root, views[0], n, T::Vec3, C::F32, Some(bounds));
        let normals = accessor(&mut root, views[1], n, T::Vec3, C::F32, None);
        let colors = accessor(&mut root, views[2], n, T::Vec3, C::F32, None);
        let index_count = part.indices.len();
        let indices = accessor(&mut root, views[3], index_count, T::Scalar, C::U32, None);
        let name = scene
            .objects
            .get(part.object as usize)
            .map_or_else(|| format!("object {}", part.object), |o| o.name.clone());
        let primitive = json::mesh::Primitive {
            attributes: [
                (Valid(json::mesh::Semantic::Positions), positions),
                (Valid(json::mesh::Semantic::Normals), normals),
                (Valid(json::mesh::Semantic::Colors(0)), colors),
            ]
            .into_iter()
            .collect(),
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        };
        let mesh_index = root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.clone()),
            primitives: vec![primitive],
            weights: None,
        });
        scene_nodes.push(root.push(json::Node {
            mesh: Some(mesh_index),
            name: Some(name),
            ..Default::default()
        }));
    }
    let scene_index = root.push(json::Scene {
        extensions: None,
        extras: None,
        name: Some(scene.path.display().to_string()),
        nodes: scene_nodes,
    });
    root.scene = Some(scene_index);
    root.buffers.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        extensions: None,
        extras: None,
        name: None,
        uri: None,
    });
    root.extensions_used = vec!["KHR_materials_unlit".into()];
    let scene_name = scene.path.display().to_string();
    let extras = GlbExtras {
        twopass: GlbExtrasBody {
            color_0: ColorMapping::FORMULA,
            exposure: mapping.exposure,
            radiance_unit: "W/(m^2 sr)",
            position_unit: "scene units",
            clamped_vertices,
            scene: &scene_name,
        },
    };
    let encode_err = |message: String| BakeError::Encode {
        path: PathBuf::from("glb"),
        message,
    };
    root.asset = json::Asset {
        generator: Some(format!("twopass {}", env!("CARGO_PKG_VERSION"))),
        version: "2.0".into(),
        extras: Some(
            serde_json::value::to_raw_value(&extras).map_err(|e| encode_err(e.to_string()))?,
        ),
        ..Default::default()
    };
    let mut json_bytes = root.to_vec().map_err(|e| encode_err(e.to_string()))?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total32 = u32::try_from(total)
        .map_err(|_| encode_err(format!("{total} bytes exceed the 4 GiB limit of .glb")))?;
    let mut bytes = Vec::with_capacity(total);
    bytes.extend_from_slice(b"glTF");
    bytes.extend_from_slice(&2u32.to_le_bytes());
    bytes.extend_from_slice(&total32.to_le_bytes());
    bytes.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    bytes.extend_from_slice(b"JSON");
    bytes.extend_from_slice(&json_bytes);
    if !bin.is_empty() {
        bytes.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        bytes.extend_from_slice(b"BIN\0");
        bytes.extend_from_slice(&bin);
    }
    Ok(Glb {
        bytes,
        clamped_vertices,
        vertices: n_vertices,
        triangles: n_triangles,
    })
}

// ---------------------------------------------------------------------------------------------
// PLY

/// One PLY element as the writer sees it: a vertex or a face.
enum PlyItem {
    Vertex {
        position: Vec3,
        normal: Vec3,
        radiance: Rgb,
    },
    Face([u32; 3]),
}

impl PropertyAccess for PlyItem {
    fn new() -> Self {
        Self::Face([0; 3])
    }

    fn get_float(&self, name: &str) -> Option<f32> {
        let Self::Vertex {
            position,
            normal,
            radiance,
        } = self
        else {
            return None;
        };
        Some(match name {
            "x" => position.x,
            "y" => position.y,
            "z" => position.z,
            "nx" => normal.x,
            "ny" => normal.y,
            "nz" => normal.z,
            "red" => radiance.x,
            "green" => radiance.y,
            "blue" => radiance.z,
            _ => return None,
        })
    }

    fn get_list_uint(&self, name: &str) -> Option<&[u32]> {
        match (self, name) {
            (Self::Face(v), "vertex_indices") => Some(v),
            _ => None,
        }
    }
}

/// Encodes the element mesh as a binary little-endian PLY: element `vertex` with `float`
/// properties `x y z` (scene units), `nx ny nz` (unit normal) and `red green blue` (the raw
/// displayed radiance L = B / pi, W/(m^2 sr), linear RGB, ambient included; not clamped or
/// exposed), one per mesh vertex in mesh order; element `face` with `list uchar uint
/// vertex_indices`, one counter-clockwise triangle per element in node order. The header's
/// comments say the same.
pub fn encode_ply(solution: &Solution, scene: &Scene) -> Result<Vec<u8>, BakeError> {
    let mesh = solution.mesh();
    let mut ply = Ply::<PlyItem>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    for c in [
        format!("twopass {} radiosity bake", env!("CARGO_PKG_VERSION")),
        format!("scene {}", scene.path.display()),
        "x y z: position, scene units".into(),
        "red green blue: radiance L = B/pi leaving the surface, W/(m^2 sr), linear RGB".into(),
    ] {
        ply.header.comments.push(c);
    }
    let mut vertex = ElementDef::new("vertex".into());
    for p in ["x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"] {
        vertex.properties.add(PropertyDef::new(
            p.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    let mut face = ElementDef::new("face".into());
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::UInt),
    ));
    ply.header.elements.add(vertex);
    ply.header.elements.add(face);
    let radiosity = solution.vertex_radiosity();
    let vertices = mesh
        .vertices
        .iter()
        .zip(&radiosity)
        .map(|(v, b)| PlyItem::Vertex {
            position: v.position,
            normal: v.normal,
            radiance: *b * std::f32::consts::FRAC_1_PI,
        })
        .collect();
    let faces = mesh
        .leaves()
        .map(|l| PlyItem::Face(mesh.nodes[l as usize].vertices))
        .collect();
    ply.payload.insert("vertex".into(), vertices);
    ply.payload.insert("face".into(), faces);
    let mut bytes = Vec::new();
    ply_rs_bw::writer::Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(|e| BakeError::Encode {
            path: PathBuf::from("ply"),
            message: e.to_string(),
        })?;
    Ok(bytes)
}

// ---------------------------------------------------------------------------------------------
// Manifest

/// The solver settings a bake was made with (`null`: the solver's default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingsRecord {
    /// Requested longest patch edge, scene units (default: diagonal / 8).
    pub patch_size: Option<f32>,
    /// Requested longest element edge, scene units (default: diagonal / 24).
    pub element_size: Option<f32>,
    /// The scene's bounding-box diagonal, scene units (what the defaults derive from).
    pub scene_diagonal: f32,
    /// Adaptive subdivision, or `null` when off.
    pub adaptive: Option<AdaptiveRecord>,
    /// Shadow rays per visibility estimate: first estimate.
    pub visibility_rays_min: u32,
    /// Shadow rays per visibility estimate: most.
    pub visibility_rays_max: u32,
    /// Whether visibility was measured with shadow rays.
    pub occlusion: bool,
    /// Stop at this unshot fraction of the emitted power.
    pub unshot_fraction: f64,
    /// Stop after this many shots, if set.
    pub max_shots: Option<u64>,
    /// Stop after this wall-clock time, seconds, if set.
    pub time_budget_s: Option<f64>,
    /// Seed of the visibility sampling.
    pub seed: u64,
    /// Worker threads (the result does not depend on it).
    pub threads: usize,
}

/// Adaptive subdivision settings (see `Adaptive`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveRecord {
    /// Split when vertex luminances differ by more than this fraction of the mean.
    pub threshold: f32,
    /// Smallest element edge / 2, scene units (`null`: element size / 8).
    pub min_element_size: Option<f32>,
    /// Refinement rounds allowed.
    pub rounds: u32,
    /// Unshot fraction at which each round looks at the solution.
    pub at_unshot_fraction: f64,
}

/// Wall-clock time per phase, seconds.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TimingsRecord {
    /// Loading the scene and building its accelerator.
    pub load_s: f64,
    /// Building the patch and element mesh.
    pub meshing_s: f64,
    /// Shooting (solve time less meshing and refining).
    pub shooting_s: f64,
    /// Adaptive subdivision, with the new vertices' gathering.
    pub refining_s: f64,
    /// Computing the residual report.
    pub residuals_s: f64,
    /// Encoding and writing the output files (all but the manifest).
    pub writing_s: f64,
    /// Everything, up to writing the manifest.
    pub total_s: f64,
}

/// Mesh sizes at the end of the solve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CountsRecord {
    /// Scene triangles.
    pub scene_triangles: usize,
    /// Patches (shooters).
    pub patches: usize,
    /// Elements (displayed triangles).
    pub elements: usize,
    /// Element vertices (where radiosity is stored).
    pub vertices: usize,
    /// Adaptive rounds done.
    pub refinement_rounds: u32,
}

/// Power bookkeeping, W per RGB channel (scene units, so mm^2 scenes give W * 1e-6 per m^2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnergyRecord {
    /// Emitted.
    pub emitted: [f64; 3],
    /// Absorbed by surfaces.
    pub absorbed: [f64; 3],
    /// Shot but received by no element.
    pub escaped: [f64; 3],
    /// Received but not shot yet.
    pub unshot: [f64; 3],
    /// Change of the unshot estimate by adaptive subdivision.
    pub remeshing: [f64; 3],
    /// Largest relative imbalance after any step.
    pub worst_imbalance: f64,
}

/// The residual report (see `Residuals`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualsRecord {
    /// Vertices and patch pairs sampled.
    pub samples: usize,
    /// Largest relative energy imbalance.
    pub energy_imbalance: f64,
    /// Smallest sampled form-factor row sum.
    pub row_sum_min: f64,
    /// Mean sampled row sum.
    pub row_sum_mean: f64,
    /// Largest sampled row sum.
    pub row_sum_max: f64,
    /// Patch pairs with a non-zero form factor among those sampled.
    pub reciprocity_pairs: usize,
    /// Largest relative reciprocity difference.
    pub reciprocity_spread: f64,
    /// Area-weighted mean relative reciprocity difference.
    pub reciprocity_mean: f64,
}

/// The `.glb` colour mapping used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorRecord {
    /// The mapping, as a formula.
    pub mapping: String,
    /// Multiplier on radiance, sr m^2 / W.
    pub exposure: f32,
    /// `"auto"` (99th-percentile luminance to 1) or `"fixed"` (given by the user).
    pub exposure_mode: String,
    /// Vertices with a channel clipped at 1.
    pub clamped_vertices: usize,
}

/// One written file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileRecord {
    /// `"glb"`, `"ply"` or `"bake"`.
    pub format: String,
    /// Where it was written.
    pub path: PathBuf,
    /// Size, bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the file's bytes, so a reader can tell a file of this set from one a
    /// later, interrupted bake left beside it (absent in manifests from before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crc32: Option<u32>,
}

/// The bake manifest (JSON): what was solved, how, how long it took and how good it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`MANIFEST_VERSION`].
    pub manifest_version: u32,
    /// `twopass <version>`.
    pub generator: String,
    /// The scene file.
    pub scene: PathBuf,
    /// [`geometry_fingerprint`] of the scene, 16 hex digits.
    pub geometry_fingerprint: String,
    /// [`lighting_fingerprint`] of the scene, 16 hex digits.
    pub lighting_fingerprint: String,
    /// Solver settings.
    pub settings: SettingsRecord,
    /// Why the solve stopped: `converged`, `max_shots`, `time_budget`, `cancelled`,
    /// `exhausted`.
    pub finish: String,
    /// Time per phase.
    pub timings: TimingsRecord,
    /// Shots (patches shot, with repeats).
    pub shots: u64,
    /// Shadow rays cast.
    pub rays: u64,
    /// Mesh sizes.
    pub counts: CountsRecord,
    /// Unshot power over emitted power at the end (sums over channels).
    pub unshot_fraction: f64,
    /// Power bookkeeping.
    pub energy: EnergyRecord,
    /// The residual report.
    pub residuals: ResidualsRecord,
    /// The `.glb` colour mapping, when a `.glb` was written.
    pub color: Option<ColorRecord>,
    /// The files written (the manifest not included).
    pub files: Vec<FileRecord>,
}

fn seconds(d: Duration) -> f64 {
    d.as_secs_f64()
}

impl Manifest {
    /// A manifest of a finished solve of `scene` with `options`: `progress` is the solver's
    /// final progress, `residuals` its residual report over `samples` samples, computed in
    /// `residuals_time`. Timings of loading and writing, the colour record and the files are
    /// left for the caller to fill in.
    pub fn new(
        scene: &Scene,
        options: &Options,
        finish: Finish,
        progress: &Progress,
        residuals: &Residuals,
        samples: usize,
        residuals_time: Duration,
    ) -> Self {
        let e = &progress.energy;
        let shooting = progress
            .elapsed
            .saturating_sub(progress.meshing)
            .saturating_sub(progress.refining);
        Self {
            manifest_version: MANIFEST_VERSION,
            generator: format!("twopass {}", env!("CARGO_PKG_VERSION")),
            scene: scene.path.clone(),
            geometry_fingerprint: format!("{:016x}", geometry_fingerprint(scene)),
            lighting_fingerprint: format!("{:016x}", lighting_fingerprint(scene)),
            settings: SettingsRecord {
                patch_size: options.patch_size,
                element_size: options.element_size,
                scene_diagonal: scene.bounds.diagonal(),
                adaptive: options.adaptive.map(|a| AdaptiveRecord {
                    threshold: a.threshold,
                    min_element_size: a.min_element_size,
                    rounds: a.rounds,
                    at_unshot_fraction: a.at_unshot_fraction,
                }),
                visibility_rays_min: options.visibility.min,
                visibility_rays_max: options.visibility.max,
                occlusion: options.occlusion,
                unshot_fraction: options.stop.unshot_fraction,
                max_shots: options.stop.max_shots,
                time_budget_s: options.stop.time_budget.map(seconds),
                seed: options.seed,
                threads: rayon::current_num_threads(),
            },
            finish: match finish {
                Finish::Converged => "converged",
                Finish::MaxShots => "max_shots",
                Finish::TimeBudget => "time_budget",
                Finish::Cancelled => "cancelled",
                Finish::Exhausted => "exhausted",
            }
            .into(),
            timings: TimingsRecord {
                meshing_s: seconds(progress.meshing),
                shooting_s: seconds(shooting),
                refining_s: seconds(progress.refining),
                residuals_s: seconds(residuals_time),
                ..TimingsRecord::default()
            },
            shots: progress.shots,
            rays: progress.rays,
            counts: CountsRecord {
                scene_triangles: scene.mesh.triangles.len(),
                patches: progress.patches,
                elements: progress.elements,
                vertices: progress.vertices,
                refinement_rounds: progress.refinement_rounds,
            },
            unshot_fraction: progress.unshot_fraction,
            energy: EnergyRecord {
                emitted: e.emitted.to_array(),
                absorbed: e.absorbed.to_array(),
                escaped: e.escaped.to_array(),
                unshot: e.unshot.to_array(),
                remeshing: e.remeshing.to_array(),
                worst_imbalance: progress.worst_imbalance,
            },
            residuals: ResidualsRecord {
                samples,
                energy_imbalance: residuals.energy_imbalance,
                row_sum_min: residuals.row_sum_min,
                row_sum_mean: residuals.row_sum_mean,
                row_sum_max: residuals.row_sum_max,
                reciprocity_pairs: residuals.reciprocity_pairs,
                reciprocity_spread: residuals.reciprocity_spread,
                reciprocity_mean: residuals.reciprocity_mean,
            },
            color: None,
            files: Vec::new(),
        }
    }

    /// The manifest as pretty-printed JSON (non-finite numbers become `null`).
    pub fn to_json(&self) -> Result<Vec<u8>, BakeError> {
        let mut bytes = serde_json::to_vec_pretty(self).map_err(|e| BakeError::Encode {
            path: PathBuf::from("manifest"),
            message: e.to_string(),
        })?;
        bytes.push(b'\n');
        Ok(bytes)
    }
}
