//! Binary little-endian PLY: every element vertex with its HDR radiance (total, direct,
//! indirect) and an 8-bit display colour, every element.

use std::path::PathBuf;

use glam::Vec3;
use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Ply, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use twopass_brdf::Rgb;
use twopass_composite::tonemap::{quantize, srgb_encode};
use twopass_radiosity::Solution;
use twopass_scene::Scene;

use crate::colour::ColorMapping;
use crate::error::BakeError;

/// The float vertex properties, in header order.
const FLOAT_PROPERTIES: [&str; 15] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "radiance_r",
    "radiance_g",
    "radiance_b",
    "direct_r",
    "direct_g",
    "direct_b",
    "indirect_r",
    "indirect_g",
    "indirect_b",
];

/// One PLY element as the writer sees it: a vertex or a face.
enum PlyItem {
    Vertex {
        position: Vec3,
        normal: Vec3,
        radiance: Rgb,
        direct: Rgb,
        indirect: Rgb,
        display: [u8; 3],
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
            direct,
            indirect,
            ..
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
            "radiance_r" => radiance.x,
            "radiance_g" => radiance.y,
            "radiance_b" => radiance.z,
            "direct_r" => direct.x,
            "direct_g" => direct.y,
            "direct_b" => direct.z,
            "indirect_r" => indirect.x,
            "indirect_g" => indirect.y,
            "indirect_b" => indirect.z,
            _ => return None,
        })
    }

    fn get_uchar(&self, name: &str) -> Option<u8> {
        let Self::Vertex { display, .. } = self else {
            return None;
        };
        match name {
            "red" => Some(display[0]),
            "green" => Some(display[1]),
            "blue" => Some(display[2]),
            _ => None,
        }
    }

    fn get_list_uint(&self, name: &str) -> Option<&[u32]> {
        match (self, name) {
            (Self::Face(v), "vertex_indices") => Some(v),
            _ => None,
        }
    }
}

/// The 8-bit display colour of a radiance `l`: `mapping`'s clipped linear colour, sRGB encoded
/// and quantized (`round(255 srgb(min(1, exposure * L)))`), as PLY viewers expect `uchar`
/// colours.
pub fn display_colour(mapping: ColorMapping, l: Rgb) -> [u8; 3] {
    let (c, _) = mapping.color(l);
    c.to_array().map(|x| quantize(srgb_encode(x)))
}

/// Encodes the element mesh as a binary little-endian PLY.
///
/// Element `vertex`, one per mesh vertex in mesh order:
/// - `float x y z`: position in scene units, kept as they are; the header says which in a
///   `comment unit mm` line and an `obj_info unit mm` line (mm standing for the scene's
///   [`Unit`](twopass_scene::Unit));
/// - `float nx ny nz`: unit normal;
/// - `float radiance_r radiance_g radiance_b`: the displayed radiance `L = B / pi` leaving the
///   surface, W/(m^2 sr), linear RGB, HDR (not exposed, not clipped), ambient included;
/// - `float direct_r direct_g direct_b`: its part reflected once from the emitters;
/// - `float indirect_r indirect_g indirect_b`: its part reflected two or more times, with the
///   ambient estimate of a partial solve (radiance - direct - indirect is the emission);
/// - `uchar red green blue`: a display colour only, [`display_colour`] with `mapping`.
///
/// The HDR values are under names no viewer takes for 8-bit colour; `red green blue` are the
/// names viewers do read, so they show the display colour. Element `face`: `list uchar uint
/// vertex_indices`, one counter-clockwise triangle per element in node order. The header's
/// comments say the same.
pub fn encode_ply(
    solution: &Solution,
    scene: &Scene,
    mapping: ColorMapping,
) -> Result<Vec<u8>, BakeError> {
    let mesh = solution.mesh();
    let mut ply = Ply::<PlyItem>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    for c in [
        format!("twopass {} radiosity bake", env!("CARGO_PKG_VERSION")),
        format!("scene {}", scene.path.display()),
        format!("unit {}", scene.unit.symbol()),
        format!(
            "x y z: position in scene units ({}, {} m each), not converted",
            scene.unit.symbol(),
            scene.unit.metres()
        ),
        "radiance_r radiance_g radiance_b: HDR radiance L = B/pi leaving the surface, \
         W/(m^2 sr), linear RGB, not clipped"
            .into(),
        "direct_*: light reflected once from the emitters; indirect_*: two or more bounces \
         (with the ambient term); radiance - direct - indirect = emission; same unit"
            .into(),
        format!(
            "red green blue: display colour only, round(255 srgb(min(1, {:e} * L)))",
            mapping.exposure
        ),
    ] {
        ply.header.comments.push(c);
    }
    // `obj_info` is the PLY header's place for facts about the object; readers that list
    // comments and obj_info both see the unit.
    ply.header
        .obj_infos
        .push(format!("unit {}", scene.unit.symbol()));
    let mut vertex = ElementDef::new("vertex".into());
    for p in FLOAT_PROPERTIES {
        vertex.properties.add(PropertyDef::new(
            p.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    for p in ["red", "green", "blue"] {
        vertex.properties.add(PropertyDef::new(
            p.into(),
            PropertyType::Scalar(ScalarType::UChar),
        ));
    }
    let mut face = ElementDef::new("face".into());
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::UInt),
    ));
    ply.header.elements.add(vertex);
    ply.header.elements.add(face);
    let parts = crate::colour::RadianceParts::of(solution);
    let vertices = mesh
        .vertices
        .iter()
        .enumerate()
        .map(|(i, v)| PlyItem::Vertex {
            position: v.position,
            normal: v.normal,
            radiance: parts.radiance[i],
            direct: parts.direct[i],
            indirect: parts.indirect[i],
            display: display_colour(mapping, parts.radiance[i]),
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
