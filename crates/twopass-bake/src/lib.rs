//! twopass-bake: a radiosity [`Solution`] written in formats that real-time engines and tools read,
//! and in a bake file that loads back into the same `Solution` so a later render needs no
//! solve.
//!
//! | output | what it holds | colour |
//! | --- | --- | --- |
//! | glTF 2.0 binary (`.glb`, [`encode_glb`]) | one mesh and node per scene object: `POSITION` (metres), `NORMAL`, `COLOR_0`, the HDR radiance `_RADIANCE` with its parts `_DIRECT` and `_INDIRECT` (custom float `VEC3` attributes, [`HDR_ATTRIBUTES`]), `u32` indices; one unlit material (`KHR_materials_unlit`) so an engine displays `COLOR_0` as it is | `COLOR_0 = min(1, exposure * L)` per linear RGB channel, float, for display (see [`ColorMapping`]); `_RADIANCE` etc. raw `L`, W/(m^2 sr) |
//! | PLY, binary little endian ([`encode_ply`]) | every element vertex (`x y z nx ny nz` and `radiance_r/g/b`, `direct_r/g/b`, `indirect_r/g/b` as `float`; `red green blue` as `uchar`) and every element (`vertex_indices`, `uint`) | `radiance_*` etc. raw radiance `L`, W/(m^2 sr); `red green blue` an 8-bit sRGB display colour ([`display_colour`]) |
//! | bake file ([`encode_bake`], [`decode_bake`], [`read_bake`]) | the element mesh and the per-vertex radiosity parts, bit for bit, with fingerprints of the scene it belongs to | radiosity `B`, W/m^2 |
//! | lightmap ([`bake_lightmap`]) | the scene's own triangles (not the element mesh) as `.glb` with a generated UV atlas on `TEXCOORD_1` and the lightmap PNG as `emissiveTexture` (`texCoord` 1); the lightmap as EXR and PNG, and (default) an RGBM PNG the `.glb`'s `extras.lightMap` names | EXR: raw `L`, W/(m^2 sr); PNG: sRGB of `min(1, exposure * L)`; RGBM: `L = multiplier * A * RGB` |
//! | per-vertex `.glb` on the scene's own mesh ([`encode_vertex_glb`]) | the scene's own triangles and vertices with the solution sampled there: `POSITION` (metres), `NORMAL`, `COLOR_0`, `_RADIANCE`, `_DIRECT`, `_INDIRECT` | as the element-mesh `.glb` |
//! | manifest (JSON, [`Manifest`]) | settings, timings per phase, rays, counts, unshot fraction, energy, residuals, files | |
//!
//! Units: the `.glb` is in metres (glTF's unit: positions converted from the scene's
//! [`Unit`](twopass_scene::Unit)); the PLY, the bake file and the manifest keep scene units
//! (the Cornell box is in millimetres; the PLY header says `comment unit mm`), radiance `L = B / pi` in W/(m^2 sr), radiosity `B` in W/m^2 per channel.
//! Every file is written atomically ([`write_atomic`], the workspace's one atomic write from
//! twopass-composite): a temporary file in the target's folder, synced, then renamed over the
//! target, so a failed write never leaves a partial file.
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
//!
//! This crate is the I/O edge of the radiosity solver (ARCHITECTURE.md, "Architecture
//! invariants"): twopass-radiosity computes and never touches a file or a file format; this
//! crate encodes, decodes, reads and writes. Modules, one job each: [`error`], [`fingerprint`],
//! [`format`](mod@format) (the bake file), [`colour`] (radiance to `COLOR_0`), [`gltf`],
//! [`lightmap`], [`lightmap_read`] (a lightmap bake read back as diffuse light), [`vertex`] (the per-vertex bake on the scene's own mesh), [`ply`],
//! [`manifest`]; the private `weld` gives the per-vertex bake and the lightmap their output
//! vertices (one per scene position and shading normal).
//!
//! ```no_run
//! use twopass_radiosity::{Options, Solver};
//! let (scene, _) = twopass_scene::load("scenes/cornell-box.toml")?;
//! let mut solver = Solver::new(&scene, Options::default())?;
//! solver.run(|_| std::ops::ControlFlow::Continue(()));
//! let solution = solver.solution();
//! let bytes = twopass_bake::encode_bake(&solution, &scene)?;
//! twopass_bake::write_atomic(std::path::Path::new("cornell-box.bake"), &bytes)?;
//! let again = twopass_bake::read_bake(std::path::Path::new("cornell-box.bake"), &scene)?;
//! # let _ = again;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! [`ElementMesh::from_parts`]: twopass_radiosity::element::ElementMesh::from_parts
//! [`Solution`]: twopass_radiosity::Solution

pub mod colour;
pub mod error;
pub mod fingerprint;
pub mod format;
pub mod gathered;
pub mod gltf;
pub mod lightmap;
pub mod lightmap_read;
pub mod manifest;
pub mod ply;
pub mod vertex;
mod weld;

pub use colour::{AUTO_EXPOSURE_PERCENTILE, ColorMapping, RadianceParts};
pub use error::{BakeError, BakeProblem};
pub use fingerprint::{
    Fingerprint, LIGHTMAP_FINGERPRINT, geometry_fingerprint, lighting_fingerprint,
    lightmap_fingerprint, scene_fingerprint,
};
pub use format::{BAKE_FORMAT_VERSION, MAX_BAKE_BYTES, decode_bake, encode_bake, read_bake};
pub use gathered::{ELEMENT_KEYS, gathered_solution};
pub use gltf::{Glb, HDR_ATTRIBUTES, SOURCE_INDEX, encode_glb};
pub use lightmap::{
    AtlasSource, CameraRecord, Lightmap, LightmapEncoding, LightmapQuantity, LightmapSettings,
    TexelSource, bake_lightmap, lightmap_atlas_size,
};
pub use lightmap_read::{LightmapRadiance, lightmap_exr_path, read_lightmap_glb};
pub use manifest::{
    AdaptiveRecord, ColorRecord, CountsRecord, EnergyRecord, FileRecord, GatherRecord,
    LightmapRecord, MANIFEST_VERSION, Manifest, PointGatherRecord, ResidualsRecord, SettingsRecord,
    TimingsRecord,
};
pub use ply::{display_colour, encode_ply};
pub use twopass_radiosity::{InvalidMesh, MeshPart};
pub use vertex::{VERTEX_KEYS, encode_vertex_glb};

/// Writes `bytes` to `path` atomically (the workspace's one atomic write,
/// [`twopass_composite::write::write_atomic`]), as a [`BakeError`] on failure.
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> Result<(), BakeError> {
    Ok(twopass_composite::write::write_atomic(path, bytes)?)
}
