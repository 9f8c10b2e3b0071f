//! Binary little-endian PLY: every element vertex with its raw radiance, every element.

use std::path::PathBuf;

use glam::Vec3;
use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Ply, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_scene::Scene;

use crate::error::BakeError;

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
/// properties `x y z` (scene units, kept as they are: the header says which in a `comment unit
/// mm` line and an `obj_info unit mm` line, mm standing for the scene's [`Unit`](twopass_scene::Unit)), `nx ny nz` (unit normal) and `red green blue` (the raw
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
        format!("unit {}", scene.unit.symbol()),
        format!(
            "x y z: position in scene units ({}, {} m each), not converted",
            scene.unit.symbol(),
            scene.unit.metres()
        ),
        "red green blue: radiance L = B/pi leaving the surface, W/(m^2 sr), linear RGB".into(),
    ] {
        ply.header.comments.push(c);
    }
    // `obj_info` is the PLY header's place for facts about the object; readers that list
    // comments and obj_info both see the unit.
    ply.header
        .obj_infos
        .push(format!("unit {}", scene.unit.symbol()));
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
