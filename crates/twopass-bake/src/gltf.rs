//! The glTF 2.0 binary (`.glb`): the displayed radiance as `COLOR_0` on one mesh per object.

use std::path::PathBuf;

use glam::Vec3;
use gltf_json as json;
use serde::Serialize;
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_radiosity::element::ElementMesh;
use twopass_scene::Scene;

use crate::colour::ColorMapping;
use crate::error::BakeError;

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
    scene_unit: &'static str,
    metres_per_scene_unit: f64,
    clamped_vertices: usize,
    scene: &'a str,
}

/// Encodes the solution's displayed radiance (ambient included) as a glTF 2.0 binary: one
/// mesh and node per scene object (named after it) with `POSITION` (metres, converted from the
/// scene's [`Unit`](twopass_scene::Unit)), unit
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
    // glTF positions are metres (glTF 2.0, "Coordinate System and Units"): converted here
    // rather than through a root-node scale, so every reader (engines that ignore a root
    // transform, the accessor bounds, measurements in a DCC tool) sees metres.
    let to_metres = scene.unit.metres();
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
            let position = (vert.position.as_dvec3() * to_metres).as_vec3();
            min = min.min(position);
            max = max.max(position);
            f32_bytes(&mut attrs[0], position.to_array());
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
            position_unit: "m",
            scene_unit: scene.unit.symbol(),
            metres_per_scene_unit: to_metres,
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
