//! The walk over a glTF scene: node world transforms (explicit stack), each triangle
//! primitive read through checked accessors into a part, the first camera, and a warning for
//! whatever is not modelled.

use std::collections::HashMap;

use glam::{DMat4, DVec3, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use twopass_brdf::Rgb;

use super::read::{GltfFile, quoted};
use crate::camera::Camera;
use crate::error::{SceneError, Warning};
use crate::gltf_source::GltfOrigin;
use crate::load::loader::{Geometry, Loader, Part, PlacedPart};
use crate::shape::ShapeMesh;
use crate::transform::Transform;

/// Pixels of a glTF camera's image height (its width follows `aspectRatio`).
const CAMERA_HEIGHT: u32 = 512;

/// Extensions the loader reads (the rest are warned about and ignored).
const READ_EXTENSIONS: [&str; 4] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
];

/// What the walk found: the parts with their origins (one to one) and the first camera.
pub(super) struct Walked {
    pub(super) parts: Vec<PlacedPart>,
    pub(super) origins: Vec<GltfOrigin>,
    pub(super) camera: Option<Camera>,
    /// The node of [`Walked::camera`].
    pub(super) camera_node: Option<usize>,
}

impl Loader {
    fn gltf_warn(&mut self, at: &str, problem: String) {
        self.warnings.push(Warning::Gltf {
            path: self.path.clone(),
            at: at.to_owned(),
            problem,
        });
    }

    fn gltf_err(&self, at: &str, problem: String) -> SceneError {
        SceneError::Gltf {
            path: self.path.clone(),
            at: at.to_owned(),
            problem,
        }
    }
}

/// Walks the default scene (else the first) of `file`.
pub(super) fn walk(ld: &mut Loader, file: &GltfFile) -> Result<Walked, SceneError> {
    let doc = &file.document;
    for ext in doc.extensions_used() {
        if !READ_EXTENSIONS.contains(&ext) {
            ld.gltf_warn(
                "the document",
                format!("extension {ext} is not read; what it adds is ignored"),
            );
        }
    }
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| ld.gltf_err("the document", "has no scene".into()))?;
    let mut materials: HashMap<Option<usize>, (u32, Rgb, Option<u32>)> = HashMap::new();
    let mut names: HashMap<String, usize> = HashMap::new();
    let mut walked = Walked {
        parts: Vec::new(),
        origins: Vec::new(),
        camera: None,
        camera_node: None,
    };
    // The part that first placed each (mesh, primitive), `None` for one not read (warned).
    let mut placed: HashMap<(usize, usize), Option<usize>> = HashMap::new();
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node<'_>, DMat4)> = scene
        .nodes()
        .map(|n| (n, DMat4::IDENTITY))
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    while let Some((node, parent)) = stack.pop() {
        let at = format!("node {}{}", node.index(), quoted(node.name()));
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(ld.gltf_err(
                &at,
                "is reached twice in the scene's hierarchy (a node has at most one parent)".into(),
            ));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
        if let Some(light) = node.light() {
            let lamp = super::lamp::lamp_of(ld, &light, &node, world, &at)?;
            ld.lamps.push(lamp);
        }
        if node.skin().is_some() {
            ld.gltf_warn(
                &at,
                "skin is not modelled: the mesh is placed by the node transforms (its bind pose)"
                    .into(),
            );
        }
        if let Some(camera) = node.camera()
            && walked.camera.is_none()
        {
            walked.camera = camera_of(ld, &camera, world, &at)?;
            walked.camera_node = walked.camera.map(|_| node.index());
        }
        let Some(mesh) = node.mesh() else {
            continue;
        };
        let transform =
            Transform::from_matrix(world).map_err(|p| ld.gltf_err(&at, format!("world {p}")))?;
        let several = mesh.primitives().len() > 1;
        for primitive in mesh.primitives() {
            let at = format!(
                "{at}, mesh {}{}, primitive {}",
                mesh.index(),
                quoted(mesh.name()),
                primitive.index()
            );
            let key = primitive.material().index();
            let (material, emission, set) = match materials.get(&key) {
                Some(&m) => m,
                None => {
                    let m = if key.is_some() {
                        let (material, emission, name, texture) =
                            ld.gltf_material(&primitive.material(), file)?;
                        let name = if ld.material_ids.contains_key(&name) {
                            format!("{name}#{}", key.unwrap_or(0))
                        } else {
                            name
                        };
                        let id = ld.add_material(name, material);
                        ld.materials[id as usize].albedo_texture = texture;
                        let set = texture.and_then(|_| {
                            let pbr = primitive.material().pbr_metallic_roughness();
                            pbr.base_color_texture().map(|i| i.tex_coord())
                        });
                        (id, emission, set)
                    } else {
                        ld.gltf_warn(
                            &at,
                            "has no material: the default grey Lambertian (glTF's own default, a white rough metal, would reflect no diffuse light)".into(),
                        );
                        (ld.default_material(), Rgb::ZERO, None)
                    };
                    materials.insert(key, m);
                    m
                }
            };
            // A primitive another node already showed is placed again, not read again: its
            // mesh is stored once ([`crate::Repeat`]).
            let geometry = match placed.get(&(mesh.index(), primitive.index())) {
                Some(Some(of)) => Geometry::Copy { of: *of },
                Some(None) => continue,
                None => {
                    let shape = read_primitive(ld, file, &primitive, &at, set)?;
                    placed.insert(
                        (mesh.index(), primitive.index()),
                        shape.as_ref().map(|_| walked.parts.len()),
                    );
                    let Some(shape) = shape else {
                        continue;
                    };
                    Geometry::Mesh(shape)
                }
            };
            ld.use_material(material);
            let base = node
                .name()
                .map_or_else(|| format!("node {}", node.index()), str::to_owned);
            let base = if several {
                format!("{base}/primitive {}", primitive.index())
            } else {
                base
            };
            let count = names.entry(base.clone()).or_default();
            *count += 1;
            let name = if *count == 1 {
                base
            } else {
                format!("{base}#{count}")
            };
            walked.parts.push(PlacedPart {
                part: Part {
                    name,
                    line: None,
                    geometry,
                    material,
                    emission,
                },
                transform,
            });
            walked.origins.push(GltfOrigin {
                node: node.index(),
                mesh: mesh.index(),
                primitive: primitive.index(),
                flips: transform.flips,
            });
        }
    }
    Ok(walked)
}

/// The scene camera of a glTF camera at `world`: `None` (after a warning) for an orthographic
/// one.
fn camera_of(
    ld: &mut Loader,
    camera: &gltf::Camera<'_>,
    world: DMat4,
    at: &str,
) -> Result<Option<Camera>, SceneError> {
    let at = format!("{at}, camera {}{}", camera.index(), quoted(camera.name()));
    let gltf::camera::Projection::Perspective(p) = camera.projection() else {
        ld.gltf_warn(
            &at,
            "an orthographic camera is not modelled: the scene is framed by the default camera"
                .into(),
        );
        return Ok(None);
    };
    let position = world.transform_point3(DVec3::ZERO).as_vec3();
    let forward = world.transform_vector3(DVec3::NEG_Z).as_vec3();
    let up = world.transform_vector3(DVec3::Y).as_vec3();
    let width = match p.aspect_ratio() {
        Some(a) if a.is_finite() && a > 0.0 => {
            (CAMERA_HEIGHT as f32 * a).round().clamp(1.0, 65536.0) as u32
        }
        _ => CAMERA_HEIGHT,
    };
    Camera::look_at(
        position,
        position + forward.normalize_or_zero(),
        up,
        p.yfov(),
        width,
        CAMERA_HEIGHT,
    )
    .map(Some)
    .map_err(|problem| ld.gltf_err(&at, format!("cannot form an image: {problem}")))
}

/// The primitive as a mesh in its node's space, or `None` (after a warning) when it cannot be
/// modelled; broken data is an error.
fn read_primitive(
    ld: &mut Loader,
    file: &GltfFile,
    primitive: &gltf::Primitive<'_>,
    at: &str,
    albedo_set: Option<u32>,
) -> Result<Option<ShapeMesh>, SceneError> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        ld.gltf_warn(
            at,
            format!(
                "{:?} primitives are not modelled (only triangle lists): skipped",
                primitive.mode()
            ),
        );
        return Ok(None);
    }
    if primitive.morph_targets().len() > 0 {
        ld.gltf_warn(
            at,
            "morph targets are not modelled: the base shape is used".into(),
        );
    }
    let position = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| ld.gltf_err(at, "has no POSITION attribute".into()))?;
    // Every accessor the primitive has (attributes and morph targets), since a bake writes
    // them all back.
    let mut accessors: Vec<(String, gltf::Accessor<'_>)> = primitive
        .attributes()
        .map(|(semantic, a)| (semantic.to_string(), a))
        .collect();
    accessors.extend(primitive.indices().map(|a| ("indices".to_owned(), a)));
    for target in primitive.morph_targets() {
        for a in [target.positions(), target.normals(), target.tangents()]
            .into_iter()
            .flatten()
        {
            accessors.push(("morph target".to_owned(), a));
        }
    }
    if let Some((what, a)) = accessors.iter().find(|(_, a)| a.sparse().is_some()) {
        ld.gltf_warn(
            at,
            format!(
                "{what} accessor {} is sparse, which is not read: the primitive is skipped",
                a.index()
            ),
        );
        return Ok(None);
    }
    let err = |problem: String| ld.gltf_err(at, problem);
    let positions: Vec<Vec3> = read_floats(file, &position, "POSITION", Dimensions::Vec3, false)
        .map_err(err)?
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(err(format!("POSITION {i} is not finite ({p})")));
    }
    let n = positions.len();
    let indices: Vec<u32> = match primitive.indices() {
        Some(a) => read_indices(file, &a).map_err(err)?,
        None => (0..n as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(err(format!(
            "has {} indices, not a multiple of 3 (a triangle list)",
            indices.len()
        )));
    }
    if let Some((i, v)) = indices.iter().enumerate().find(|(_, v)| **v as usize >= n) {
        return Err(err(format!(
            "index {i} is {v}, out of range for the {n} vertices of POSITION"
        )));
    }
    let triangles: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    if triangles.is_empty() {
        ld.gltf_warn(at, "has no triangles: skipped".into());
        return Ok(None);
    }
    let mut shape = ShapeMesh {
        positions,
        triangles,
        ..ShapeMesh::default()
    };
    if let Some(a) = primitive.get(&gltf::Semantic::Normals) {
        let values = read_floats(file, &a, "NORMAL", Dimensions::Vec3, false).map_err(err)?;
        same_count(a.count(), n, "NORMAL").map_err(err)?;
        let mut normals = Vec::with_capacity(n);
        for (i, c) in values.chunks_exact(3).enumerate() {
            let v = Vec3::new(c[0], c[1], c[2]);
            match v.try_normalize() {
                Some(u) => normals.push(u),
                None => {
                    return Err(err(format!(
                        "NORMAL {i} is {v}, not a direction (zero or not finite)"
                    )));
                }
            }
        }
        shape.normals = normals;
        shape.normal_indices = shape.triangles.clone();
    }
    if let Some(a) = primitive.get(&gltf::Semantic::TexCoords(1)) {
        let values = read_floats(file, &a, "TEXCOORD_1", Dimensions::Vec2, true).map_err(err)?;
        same_count(a.count(), n, "TEXCOORD_1").map_err(err)?;
        let mut uv = Vec::with_capacity(n);
        for (i, c) in values.chunks_exact(2).enumerate() {
            if !(c[0].is_finite() && c[1].is_finite()) {
                return Err(err(format!("TEXCOORD_1 {i} is not finite ({c:?})")));
            }
            // Stored v up, as an OBJ's `vt`: glTF's v points down.
            uv.push(Vec2::new(c[0], 1.0 - c[1]));
        }
        shape.texcoords = uv;
        shape.texcoord_indices = shape.triangles.clone();
    }
    if let Some(set) = albedo_set
        && let Some(a) = primitive.get(&gltf::Semantic::TexCoords(set))
    {
        let what = format!("TEXCOORD_{set}");
        let values = read_floats(file, &a, &what, Dimensions::Vec2, true).map_err(err)?;
        same_count(a.count(), n, &what).map_err(err)?;
        let uv: Vec<Vec2> = values
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect();
        if let Some((i, c)) = uv.iter().enumerate().find(|(_, c)| !c.is_finite()) {
            return Err(err(format!("{what} {i} is not finite ({c})")));
        }
        shape.albedo_uvs = shape
            .triangles
            .iter()
            .map(|t| t.map(|v| uv[v as usize]))
            .collect();
    }
    Ok(Some(shape))
}

fn same_count(count: usize, n: usize, what: &str) -> Result<(), String> {
    if count == n {
        Ok(())
    } else {
        Err(format!("{what} has {count} elements, but POSITION has {n}"))
    }
}

/// The bytes of element `i` of a non-sparse accessor, after [`checked_layout`].
struct Layout<'a> {
    data: &'a [u8],
    start: usize,
    stride: usize,
}

impl Layout<'_> {
    fn element(&self, i: usize) -> usize {
        self.start + i * self.stride
    }
}

/// Where a non-sparse accessor's elements lie in its buffer, checked to lie inside its buffer
/// view and the view inside the buffer: an error in words otherwise.
fn checked_layout<'a>(file: &'a GltfFile, a: &gltf::Accessor<'_>) -> Result<Layout<'a>, String> {
    let name = format!("accessor {}", a.index());
    let view = a
        .view()
        .ok_or_else(|| format!("{name} has no buffer view (all zeros are not read)"))?;
    let buffer = &file.buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer.len()) {
        return Err(format!(
            "buffer view {} (bytes {} to {}) reaches past the {} bytes of buffer {}",
            view.index(),
            view.offset(),
            view.offset().saturating_add(view.length()),
            buffer.len(),
            view.buffer().index()
        ));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if a.count() == 0 {
        return Err(format!("{name} has no elements"));
    }
    if stride < size {
        return Err(format!(
            "{name}: byteStride {stride} is smaller than its {size}-byte elements"
        ));
    }
    let end = stride
        .checked_mul(a.count() - 1)
        .and_then(|s| s.checked_add(a.offset()))
        .and_then(|s| s.checked_add(size));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "{name}: {} elements of {size} bytes every {stride} from byte {} reach past the {} bytes of buffer view {}",
            a.count(),
            a.offset(),
            view.length(),
            view.index()
        ));
    }
    Ok(Layout {
        data: &buffer[view.offset()..view.offset() + view.length()],
        start: a.offset(),
        stride,
    })
}

/// The components of a float (or, with `normalized_ok`, normalized unsigned byte or short)
/// accessor of `dims`, as f32, element after element.
fn read_floats(
    file: &GltfFile,
    a: &gltf::Accessor<'_>,
    what: &str,
    dims: Dimensions,
    normalized_ok: bool,
) -> Result<Vec<f32>, String> {
    let ty = a.data_type();
    let ty_ok = ty == DataType::F32
        || (normalized_ok && a.normalized() && matches!(ty, DataType::U8 | DataType::U16));
    if a.dimensions() != dims || !ty_ok {
        return Err(format!(
            "{what} accessor {} is {:?} of {:?}{}, not {dims:?} of float",
            a.index(),
            a.dimensions(),
            ty,
            if a.normalized() { " (normalized)" } else { "" }
        ));
    }
    let l = checked_layout(file, a)?;
    let k = dims.multiplicity();
    let mut out = Vec::with_capacity(a.count() * k);
    for i in 0..a.count() {
        let e = l.element(i);
        for c in 0..k {
            out.push(match ty {
                DataType::U8 => f32::from(l.data[e + c]) / 255.0,
                DataType::U16 => {
                    let at = e + 2 * c;
                    f32::from(u16::from_le_bytes([l.data[at], l.data[at + 1]])) / 65535.0
                }
                _ => {
                    let at = e + 4 * c;
                    f32::from_le_bytes([l.data[at], l.data[at + 1], l.data[at + 2], l.data[at + 3]])
                }
            });
        }
    }
    Ok(out)
}

/// The indices of an index accessor (scalar unsigned byte, short or int).
fn read_indices(file: &GltfFile, a: &gltf::Accessor<'_>) -> Result<Vec<u32>, String> {
    let ty = a.data_type();
    if a.dimensions() != Dimensions::Scalar
        || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
    {
        return Err(format!(
            "indices accessor {} is {:?} of {ty:?}, not scalar unsigned integers",
            a.index(),
            a.dimensions()
        ));
    }
    let l = checked_layout(file, a)?;
    Ok((0..a.count())
        .map(|i| {
            let e = l.element(i);
            let d = l.data;
            match ty {
                DataType::U8 => u32::from(d[e]),
                DataType::U16 => u32::from(u16::from_le_bytes([d[e], d[e + 1]])),
                _ => u32::from_le_bytes([d[e], d[e + 1], d[e + 2], d[e + 3]]),
            }
        })
        .collect())
}
