//! The glTF 2.0 binary (`.glb`): the element mesh with its radiance per vertex, one mesh per
//! object, in metres; and the small builder the other `.glb` outputs (lightmap, per-vertex bake
//! on the user's mesh) share.

use std::path::PathBuf;

use glam::Vec3;
use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use serde::Serialize;
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_radiosity::element::ElementMesh;
use twopass_scene::Scene;

use crate::colour::{ColorMapping, RadianceParts};
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

/// The custom vertex attributes every baked `.glb` carries beside `COLOR_0` (glTF 2.0 allows
/// application-specific attributes whose names start with an underscore): float `VEC3`,
/// linear RGB radiance in W/(m^2 sr), HDR (not exposed, not clipped).
pub const HDR_ATTRIBUTES: [&str; 3] = ["_RADIANCE", "_DIRECT", "_INDIRECT"];

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
        let o = scene.mesh.object_of(t as u32) as usize;
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

/// A glTF document under construction with its binary chunk: buffer views, accessors,
/// meshes and nodes in one buffer, 4-byte aligned throughout.
pub(crate) struct GlbBuilder {
    pub(crate) root: json::Root,
    bin: Vec<u8>,
    /// The root nodes of the document's one scene.
    pub(crate) nodes: Vec<json::Index<json::Node>>,
}

/// One vertex stream of a primitive.
pub(crate) enum Attribute<'a> {
    /// `VEC3` floats (positions get min/max bounds).
    Vec3(json::mesh::Semantic, &'a [Vec3]),
    /// `VEC2` floats (texture coordinates).
    Vec2(json::mesh::Semantic, &'a [glam::Vec2]),
    /// Unsigned integers (an application-specific attribute: indices), exact: `SCALAR`
    /// floats when every value is below 2^24, else `VEC2` unsigned shorts (low and high 16
    /// bits). glTF allows no `UNSIGNED_INT` vertex attribute.
    Index(json::mesh::Semantic, &'a [u32]),
}

impl GlbBuilder {
    pub(crate) fn new() -> Self {
        Self {
            root: json::Root::default(),
            bin: Vec::new(),
            nodes: Vec::new(),
        }
    }

    /// Appends `data` (padded to 4 bytes) as a buffer view.
    pub(crate) fn view(
        &mut self,
        data: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let offset = self.bin.len();
        self.bin.extend_from_slice(data);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(data.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: None,
            name: None,
            target: target.map(Valid),
        })
    }

    fn accessor(
        &mut self,
        data: &[u8],
        count: usize,
        ty: json::accessor::Type,
        component: json::accessor::ComponentType,
        target: json::buffer::Target,
        bounds: Option<(json::Value, json::Value)>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(data, Some(target));
        let (min, max) = match bounds {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
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
    }

    /// Embeds a PNG in the binary chunk as an image with a texture (bilinear, clamped to the
    /// edge: a lightmap's charts must not wrap).
    pub(crate) fn png_texture(&mut self, name: &str, png: &[u8]) -> json::Index<json::Texture> {
        let view = self.view(png, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(name.to_owned()),
            uri: None,
            extensions: None,
            extras: None,
        });
        use json::texture::{MagFilter, MinFilter, WrappingMode};
        let sampler = self.root.push(json::texture::Sampler {
            mag_filter: Some(Valid(MagFilter::Linear)),
            min_filter: Some(Valid(MinFilter::Linear)),
            wrap_s: Valid(WrappingMode::ClampToEdge),
            wrap_t: Valid(WrappingMode::ClampToEdge),
            name: None,
            extensions: None,
            extras: None,
        });
        self.root.push(json::Texture {
            name: Some(name.to_owned()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        })
    }

    /// Adds a mesh of one indexed triangle primitive and a node showing it.
    pub(crate) fn mesh(
        &mut self,
        name: &str,
        attributes: &[Attribute<'_>],
        indices: &[u32],
        material: json::Index<json::Material>,
    ) {
        use json::accessor::{ComponentType as C, Type as T};
        use json::buffer::Target::ArrayBuffer;
        let mut map = std::collections::BTreeMap::new();
        for a in attributes {
            let mut data = Vec::new();
            let (semantic, accessor) = match a {
                Attribute::Vec3(semantic, values) => {
                    f32_bytes(&mut data, values.iter().flat_map(|v| v.to_array()));
                    let bounds = (*semantic == json::mesh::Semantic::Positions).then(|| {
                        let min = values.iter().fold(Vec3::INFINITY, |m, v| m.min(*v));
                        let max = values.iter().fold(Vec3::NEG_INFINITY, |m, v| m.max(*v));
                        (
                            json::Value::from(min.to_array().to_vec()),
                            json::Value::from(max.to_array().to_vec()),
                        )
                    });
                    let acc =
                        self.accessor(&data, values.len(), T::Vec3, C::F32, ArrayBuffer, bounds);
                    (semantic.clone(), acc)
                }
                Attribute::Vec2(semantic, values) => {
                    f32_bytes(&mut data, values.iter().flat_map(|v| v.to_array()));
                    let acc =
                        self.accessor(&data, values.len(), T::Vec2, C::F32, ArrayBuffer, None);
                    (semantic.clone(), acc)
                }
                Attribute::Index(semantic, values) => {
                    let n = values.len();
                    let acc = if values.iter().all(|&v| v < 1 << 24) {
                        f32_bytes(&mut data, values.iter().map(|&v| v as f32));
                        self.accessor(&data, n, T::Scalar, C::F32, ArrayBuffer, None)
                    } else {
                        for &v in *values {
                            data.extend((v as u16).to_le_bytes());
                            data.extend(((v >> 16) as u16).to_le_bytes());
                        }
                        self.accessor(&data, n, T::Vec2, C::U16, ArrayBuffer, None)
                    };
                    (semantic.clone(), acc)
                }
            };
            map.insert(Valid(semantic), accessor);
        }
        let mut data = Vec::with_capacity(indices.len() * 4);
        for i in indices {
            data.extend_from_slice(&i.to_le_bytes());
        }
        let indices = self.accessor(
            &data,
            indices.len(),
            T::Scalar,
            C::U32,
            json::buffer::Target::ElementArrayBuffer,
            None,
        );
        let primitive = json::mesh::Primitive {
            attributes: map,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        };
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.to_owned()),
            primitives: vec![primitive],
            weights: None,
        });
        let node = self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(name.to_owned()),
            ..Default::default()
        });
        self.nodes.push(node);
    }

    /// The document as `.glb` bytes: one scene of every node, `asset.extras` = `extras`.
    /// A mesh of vertex radiance: positions (m), normals and the display colour `COLOR_0`,
    /// then the HDR radiance, direct and indirect parts under [`HDR_ATTRIBUTES`], and, when
    /// given, each vertex's index in the user's vertex list as [`SOURCE_INDEX`].
    pub(crate) fn vertex_radiance_mesh(
        &mut self,
        name: &str,
        [positions, normals, colours]: [&[Vec3]; 3],
        [radiance, direct, indirect]: [&[Vec3]; 3],
        (indices, sources): (&[u32], Option<&[u32]>),
        material: json::Index<json::Material>,
    ) {
        use json::mesh::Semantic as S;
        let mut attributes = vec![
            Attribute::Vec3(S::Positions, positions),
            Attribute::Vec3(S::Normals, normals),
            Attribute::Vec3(S::Colors(0), colours),
            Attribute::Vec3(custom(HDR_ATTRIBUTES[0]), radiance),
            Attribute::Vec3(custom(HDR_ATTRIBUTES[1]), direct),
            Attribute::Vec3(custom(HDR_ATTRIBUTES[2]), indirect),
        ];
        if let Some(sources) = sources {
            attributes.push(Attribute::Index(custom(SOURCE_INDEX), sources));
        }
        self.mesh(name, &attributes, indices, material);
    }

    /// Closes a file of vertex-radiance meshes: the `extras` that say how to read them (the
    /// colour mapping, units, clipped vertices) and the counts.
    pub(crate) fn finish_vertex_radiance(
        self,
        scene: &Scene,
        mapping: &ColorMapping,
        clamped_vertices: usize,
        (vertices, triangles): (usize, usize),
    ) -> Result<Glb, BakeError> {
        let scene_name = scene.path.display().to_string();
        let extras = GlbExtras {
            twopass: GlbExtrasBody {
                color_0: ColorMapping::FORMULA,
                exposure: mapping.exposure,
                radiance_attributes: RADIANCE_ATTRIBUTES,
                radiance_unit: "W/(m^2 sr)",
                position_unit: "m",
                scene_unit: scene.unit.symbol(),
                metres_per_scene_unit: scene.unit.metres(),
                clamped_vertices,
                scene: &scene_name,
            },
        };
        let bytes = self.finish(&scene_name, &extras)?;
        Ok(Glb {
            bytes,
            clamped_vertices,
            vertices,
            triangles,
        })
    }

    pub(crate) fn finish(
        mut self,
        scene_name: &str,
        extras: &impl Serialize,
    ) -> Result<Vec<u8>, BakeError> {
        let encode_err = |message: String| BakeError::Encode {
            path: PathBuf::from("glb"),
            message,
        };
        let nodes = std::mem::take(&mut self.nodes);
        let scene_index = self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some(scene_name.to_owned()),
            nodes,
        });
        self.root.scene = Some(scene_index);
        let bin = self.bin;
        if !bin.is_empty() {
            self.root.buffers.push(json::Buffer {
                byte_length: USize64::from(bin.len()),
                extensions: None,
                extras: None,
                name: None,
                uri: None,
            });
        }
        self.root.asset = json::Asset {
            generator: Some(format!("twopass {}", env!("CARGO_PKG_VERSION"))),
            version: "2.0".into(),
            extras: Some(
                serde_json::value::to_raw_value(extras).map_err(|e| encode_err(e.to_string()))?,
            ),
            ..Default::default()
        };
        let json_bytes = self.root.to_vec().map_err(|e| encode_err(e.to_string()))?;
        glb_bytes(json_bytes, bin)
    }
}

/// A `.glb` of `json` and `bin`: the 12-byte header, the JSON chunk padded with spaces and,
/// unless `bin` is empty, the binary chunk padded with zeros (4-byte aligned, as glTF wants).
pub(crate) fn glb_bytes(mut json_bytes: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>, BakeError> {
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total32 = u32::try_from(total).map_err(|_| BakeError::Encode {
        path: PathBuf::from("glb"),
        message: format!("{total} bytes exceed the 4 GiB limit of .glb"),
    })?;
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
    Ok(bytes)
}

/// The unlit material of the per-vertex bakes: white base colour times `COLOR_0`, shown as it
/// is (`KHR_materials_unlit`).
pub(crate) fn unlit_vertex_colour_material(b: &mut GlbBuilder) -> json::Index<json::Material> {
    // The extension struct's fields depend on which gltf-json features the build enables.
    #[allow(clippy::needless_update)]
    let material = b.root.push(json::Material {
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
    if !b
        .root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_materials_unlit")
    {
        b.root.extensions_used.push("KHR_materials_unlit".into());
    }
    material
}

/// The vertex attribute of the per-vertex bake on the user's mesh that names each vertex's
/// index in the user's own vertex list: an OBJ's `v` statements (0-based, file order), a glTF
/// primitive's accessor element, a built-in shape's vertex. Stored exactly: `SCALAR` floats
/// holding integers when every index is below 2^24 (16,777,216), else `VEC2` unsigned shorts
/// `(low, high)` with index = low + 65536 high (glTF allows no 32-bit integer attribute).
pub const SOURCE_INDEX: &str = "_TWOPASS_SOURCE_INDEX";

/// A radiance attribute semantic (`_RADIANCE`, ...).
pub(crate) fn custom(name: &str) -> json::mesh::Semantic {
    json::mesh::Semantic::Extras(name.trim_start_matches('_').to_owned())
}

/// The glTF asset extras of a per-vertex bake: how to read its colours back as radiance.
#[derive(Serialize)]
pub(crate) struct GlbExtras<'a> {
    pub(crate) twopass: GlbExtrasBody<'a>,
}

#[derive(Serialize)]
pub(crate) struct GlbExtrasBody<'a> {
    pub(crate) color_0: &'static str,
    pub(crate) exposure: f32,
    pub(crate) radiance_attributes: &'static str,
    pub(crate) radiance_unit: &'static str,
    pub(crate) position_unit: &'static str,
    pub(crate) scene_unit: &'static str,
    pub(crate) metres_per_scene_unit: f64,
    pub(crate) clamped_vertices: usize,
    pub(crate) scene: &'a str,
}

/// What `_RADIANCE`, `_DIRECT` and `_INDIRECT` hold, as recorded in the asset extras.
pub(crate) const RADIANCE_ATTRIBUTES: &str = "_RADIANCE: HDR radiance L = B / pi leaving the \
     surface (float VEC3, linear RGB, not clipped); _DIRECT: its part reflected once from the \
     emitters; _INDIRECT: two or more bounces (ambient term included); _RADIANCE - _DIRECT - \
     _INDIRECT = emission";

/// Encodes the solution's displayed radiance (ambient included) as a glTF 2.0 binary: one
/// mesh and node per scene object (named after it) with `POSITION` (metres, converted from the
/// scene's [`Unit`](twopass_scene::Unit)), unit `NORMAL`, `COLOR_0` from `mapping` (linear,
/// float, exposure-scaled and clipped at 1 for display), the HDR radiance and its parts as
/// the custom attributes [`HDR_ATTRIBUTES`] (W/(m^2 sr), see [`RadianceParts`]), and `u32`
/// indices, all sharing one unlit material (`KHR_materials_unlit`, white base colour) so
/// engines show `COLOR_0` without relighting. The mapping and units are recorded in the
/// asset's `extras.twopass`. Meshes come in object order (objects without elements are left
/// out); each lists the mesh vertices its elements use in ascending vertex order and its
/// elements in node order.
pub fn encode_glb(
    solution: &Solution,
    scene: &Scene,
    mapping: ColorMapping,
) -> Result<Glb, BakeError> {
    let mesh = solution.mesh();
    let parts = RadianceParts::of(solution);
    let objects = object_parts(mesh, scene);
    // glTF positions are metres (glTF 2.0, "Coordinate System and Units"): converted here
    // rather than through a root-node scale, so every reader (engines that ignore a root
    // transform, the accessor bounds, measurements in a DCC tool) sees metres.
    let to_metres = scene.unit.metres();
    let mut b = GlbBuilder::new();
    let material = unlit_vertex_colour_material(&mut b);
    let mut clamped_vertices = 0;
    let (mut n_vertices, mut n_triangles) = (0, 0);
    for part in &objects {
        let pick = |values: &[Rgb]| -> Vec<Vec3> {
            part.vertices.iter().map(|&v| values[v as usize]).collect()
        };
        let positions: Vec<Vec3> = part
            .vertices
            .iter()
            .map(|&v| (mesh.vertices[v as usize].position.as_dvec3() * to_metres).as_vec3())
            .collect();
        let normals: Vec<Vec3> = part
            .vertices
            .iter()
            .map(|&v| {
                mesh.vertices[v as usize]
                    .normal
                    .try_normalize()
                    .unwrap_or(Vec3::Z)
            })
            .collect();
        let radiance = pick(&parts.radiance);
        let colours = mapping.colors(&radiance, &mut clamped_vertices);
        let (direct, indirect) = (pick(&parts.direct), pick(&parts.indirect));
        let name = scene
            .objects
            .get(part.object as usize)
            .map_or_else(|| format!("object {}", part.object), |o| o.name.clone());
        b.vertex_radiance_mesh(
            &name,
            [&positions, &normals, &colours],
            [&radiance, &direct, &indirect],
            (&part.indices, None),
            material,
        );
        n_vertices += part.vertices.len();
        n_triangles += part.indices.len() / 3;
    }
    b.finish_vertex_radiance(scene, &mapping, clamped_vertices, (n_vertices, n_triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of accessor `index` of `b` (tightly packed) and its component type and type.
    fn accessor_bytes(b: &GlbBuilder, index: usize) -> (Vec<u8>, String) {
        let a = &b.root.accessors[index];
        let view = &b.root.buffer_views[a.buffer_view.unwrap().value()];
        let start = view.byte_offset.map_or(0, |o| o.0 as usize);
        let bytes = b.bin[start..start + view.byte_length.0 as usize].to_vec();
        let kind = serde_json::to_string(&(&a.component_type, &a.type_)).unwrap();
        (bytes, kind)
    }

    #[test]
    fn source_indices_are_floats_below_2_pow_24_and_ushort_pairs_beyond() {
        let mut b = GlbBuilder::new();
        let material = unlit_vertex_colour_material(&mut b);
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let small = [0, 7, (1 << 24) - 1];
        let large = [3, 1 << 24, 0xDEAD_BEEF];
        for sources in [&small, &large] {
            b.mesh(
                "m",
                &[
                    Attribute::Vec3(json::mesh::Semantic::Positions, &p),
                    Attribute::Index(custom(SOURCE_INDEX), sources),
                ],
                &[0, 1, 2],
                material,
            );
        }
        // Accessors: positions, indices, ... per mesh; the source index is the second.
        let (bytes, kind) = accessor_bytes(&b, 1);
        assert_eq!(kind, "[5126,\"SCALAR\"]");
        let floats: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as u32)
            .collect();
        assert_eq!(floats, small);
        let (bytes, kind) = accessor_bytes(&b, 4);
        assert_eq!(kind, "[5123,\"VEC2\"]");
        let pairs: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| {
                let lo = u16::from_le_bytes([c[0], c[1]]);
                let hi = u16::from_le_bytes([c[2], c[3]]);
                u32::from(lo) + 65536 * u32::from(hi)
            })
            .collect();
        assert_eq!(pairs, large);
    }
}
