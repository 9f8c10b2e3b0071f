//! glTF 2.0 input (`.gltf` with its buffers, or `.glb`), read with the `gltf` crate and turned
//! into the parts every scene is assembled from.
//!
//! **Geometry.** The default scene (else the first) is walked depth first in node order (with
//! an explicit stack), each node's world matrix the product of its ancestors' (TRS or matrix,
//! in f64). Every triangle primitive of a node's mesh becomes one object, named after the node
//! (`node N` when unnamed; `name/primitive K` when the mesh has several primitives; `#2`, `#3`
//! on repeated names), so a mesh that several nodes use (instancing) becomes one object per
//! use. Its triangles are read and stored once, at the first node that shows it; every other
//! node places that copy again by its transform ([`Repeat`](crate::Repeat)), without storing
//! it (a copy in the same place as another is dropped with a warning). Each object keeps the
//! primitive's whole vertex list in order, so its vertex `i` is the primitive's vertex `i`
//! ([`GltfOrigin`](crate::GltfOrigin); triangles the scene drops, of zero area or repeating another exactly, are
//! not in it). Indexed and non-indexed primitives are read; `NORMAL` gives smooth
//! shading normals (flat shading without it); `TEXCOORD_1`, when present, is kept as the
//! mesh's texture coordinates (the lightmap layout a bake uses if it is valid; stored v up,
//! as an OBJ's, so `(u, 1 - v)` of glTF's). The set a material's `baseColorTexture` names
//! (`texCoord`, `TEXCOORD_0` by default) is read as the mesh's albedo coordinates; every set
//! is kept in the user's asset a bake writes back. Units are metres, as glTF defines them.
//!
//! **Camera.** The first camera met in that walk, at its node's world position, looking down
//! its local -z with +y up; a perspective camera's `yfov` and `aspectRatio` (512 pixels high,
//! the width from the aspect, 512 x 512 without one). Without a camera (or with an orthographic
//! one, warned), the default framing of a bare OBJ: 40 degrees, 512 x 512, looking down -z at
//! the centre of the bounds.
//!
//! **Materials** (metallic-roughness; `baseColor` is linear RGB, its alpha is not used):
//!
//! | glTF | twopass |
//! | --- | --- |
//! | `KHR_materials_transmission` factor > 0 | `dielectric`, `ior` from `KHR_materials_ior` (1.5 without it); base colour, roughness and a factor < 1 are not modelled (warned) |
//! | `metallicFactor` < 0.5 | `lambert`, albedo `baseColorFactor` (each channel clamped to 0.999, warned) times the `baseColorTexture` (sRGB decoded to linear, its sampler's wrap modes and magnification filter; [`crate::texture`]); roughness is not used and glTF's dielectric specular (F0 = 0.04) is left out: a Lambertian reflects all of the albedo diffusely |
//! | `metallicFactor` >= 0.5, `roughness` < [`SMOOTH_ROUGHNESS`] | `conductor` (a smooth mirror-like metal) |
//! | `metallicFactor` >= 0.5, rougher | `cook_torrance` with no diffuse part, specular 1, Beckmann slope m = alpha = roughness^2 (glTF's GGX alpha, taken as Beckmann's m as Walter et al. 2007 match them) |
//! | metal Fresnel | the complex index n = 1, k = 2 sqrt(F0 / (1 - F0)) per channel, with F0 = `baseColorFactor` (clamped to 0.999): its reflectance at normal incidence is exactly F0 |
//! | `emissiveFactor` x `KHR_materials_emissive_strength` | emitted radiance L_e in W/(m^2 sr), one to one: glTF's emissive is display-referred linear radiance (1 is a surface shown at full white unexposed), taken as radiometric W/(m^2 sr) with no luminous-efficacy factor |
//! | `metallicFactor` strictly between 0 and 1 | the nearer of the two (warned) |
//! | a primitive without a material | the default grey Lambertian (albedo 0.5), warned (glTF's own default is a white rough metal, which would reflect no diffuse light) |
//! | emissive, metallic-roughness, normal and occlusion textures, a base colour texture on glass or a metal, `alphaMode` other than `OPAQUE`, `KHR_texture_transform` | not used: the factors alone (a warning names the material) |
//!
//! **Lamps** (`KHR_lights_punctual`): each node with a light becomes a [`Lamp`](crate::Lamp)
//! named after the node (else the light, else `node N`), at the node's world position, a spot
//! or directional lamp aimed down the node's local -z. glTF's photometric intensities become
//! radiometric ones divided by [`LUMINOUS_EFFICACY`](crate::LUMINOUS_EFFICACY) (683 lm/W):
//! candela to W/sr for point and spot lamps, lux to W/m^2 for directional ones, times the
//! light's `color`. Blender's exporter writes a point or spot lamp of P watts as
//! P / (4 pi) * 683 cd and a sun of S W/m^2 as S * 683 lux, so they come back as P watts
//! (4 pi I) and S W/m^2. The spot's cone angles and smooth falloff are glTF's; `range` is not
//! modelled (warned: the light falls off as 1 / r^2 without a cut-off).
//!
//! **Not modelled, warned and skipped:** skins (the node transforms' bind pose is used), morph targets (the
//! base shape is used), primitives of points or lines or triangle strips and fans (skipped),
//! sparse accessors (the primitive is skipped), any other extension the file uses (ignored).
//!
//! **Broken input is an error** naming the file and where in it (the node, mesh and primitive
//! by index and name, the buffer, the accessor): a malformed document, a buffer missing or
//! shorter than its `byteLength`, an accessor reaching past its buffer view, an index past the
//! vertex count, a NaN or infinite position, normal or texture coordinate, a singular node
//! transform. Every file is read through the bounded reader (at most
//! [`MAX_GLTF_BYTES`](crate::input::MAX_GLTF_BYTES), FIFOs and devices refused, confined to
//! the scene's folder under [`ReadPolicy::confined`](crate::ReadPolicy::confined)).
//!
//! Files: `read` (the file, its buffers and images, base64 data URIs), `material` (the table
//! above), `walk` (the nodes, primitives and camera).

mod lamp;
mod material;
mod read;
mod walk;

use std::collections::HashMap;
use std::path::Path;

use super::loader::{Loader, framing_camera};
use crate::error::{SceneError, Warning};
use crate::gltf_source::GltfSource;
use crate::input::{LineIndex, ReadPolicy};
use crate::scene::Scene;

pub use material::SMOOTH_ROUGHNESS;
pub use read::image_problem as gltf_image_problem;

/// Loads a glTF 2.0 file (`.gltf` or `.glb`) as a scene in metres.
pub(super) fn load_gltf(
    path: &Path,
    policy: &ReadPolicy,
) -> Result<(Scene, Vec<Warning>), SceneError> {
    let mut ld = Loader {
        path: path.to_owned(),
        lines: LineIndex::new(""),
        policy: policy.clone(),
        warnings: Vec::new(),
        materials: Vec::new(),
        material_ids: HashMap::new(),
        used: Vec::new(),
        textures: Vec::new(),
        texture_ids: HashMap::new(),
        lamps: Vec::new(),
        sky: None,
        obj_parts: HashMap::new(),
    };
    let file = read::read(path, policy, &mut ld.warnings)?;
    let walked = walk::walk(&mut ld, &file)?;
    let camera = match walked.camera {
        Some(camera) => camera,
        None => framing_camera(path, &walked.parts)?,
    };
    let (mut scene, warnings, kept) =
        ld.finish_parts(walked.parts, camera, crate::unit::Unit::Metre)?;
    // An object removed as a copy of earlier ones writes nothing back: its origin goes too.
    let origins = walked
        .origins
        .into_iter()
        .zip(kept)
        .filter_map(|(o, k)| k.then_some(o))
        .collect();
    scene.gltf = Some(Box::new(GltfSource {
        json: file.json,
        buffers: file.buffers,
        images: file.images,
        origins,
        camera_node: walked.camera_node,
    }));
    Ok((scene, warnings))
}

#[cfg(test)]
mod tests;
