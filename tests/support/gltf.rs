//! A small glTF 2.0 writer for tests (gltf-json's typed structs, one binary buffer): meshes,
//! materials, nodes with transforms, cameras, written as `.glb` or as `.gltf` with its buffer
//! in a separate `.bin`. Independent of the twopass code that reads and writes glTF.

use std::path::Path;

use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;

/// A glTF document under construction with its binary buffer.
#[derive(Default)]
pub struct GltfWriter {
    /// The document (push objects into it directly for what the builder methods do not write).
    pub root: json::Root,
    /// The binary buffer's bytes.
    pub bin: Vec<u8>,
}

/// One material of [`GltfWriter::material`]: metallic-roughness factors and emission.
#[derive(Debug, Clone, Copy)]
pub struct MaterialSpec {
    /// Linear base colour (alpha 1).
    pub base: [f32; 3],
    /// `metallicFactor`.
    pub metallic: f32,
    /// `roughnessFactor`.
    pub roughness: f32,
    /// `emissiveFactor`.
    pub emissive: [f32; 3],
    /// `KHR_materials_emissive_strength`, when given.
    pub strength: Option<f32>,
}

impl Default for MaterialSpec {
    fn default() -> Self {
        Self {
            base: [0.5; 3],
            metallic: 0.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            strength: None,
        }
    }
}

/// A node's local transform (glTF's TRS: translation, rotation quaternion x y z w, scale).
#[derive(Debug, Clone, Copy)]
pub struct Trs {
    /// Translation.
    pub t: [f32; 3],
    /// Rotation as a unit quaternion (x, y, z, w).
    pub r: [f32; 4],
    /// Scale.
    pub s: [f32; 3],
}

impl Default for Trs {
    fn default() -> Self {
        Self {
            t: [0.0; 3],
            r: [0.0, 0.0, 0.0, 1.0],
            s: [1.0; 3],
        }
    }
}

impl GltfWriter {
    /// An empty document.
    pub fn new() -> Self {
        Self::default()
    }

    fn view(
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

    /// An accessor of `count` elements of `ty` over `data`.
    pub fn accessor(
        &mut self,
        data: &[u8],
        count: usize,
        ty: json::accessor::Type,
        component: json::accessor::ComponentType,
        bounds: Option<([f32; 3], [f32; 3])>,
    ) -> json::Index<json::Accessor> {
        use json::buffer::Target;
        let target = if ty == json::accessor::Type::Scalar {
            Target::ElementArrayBuffer
        } else {
            Target::ArrayBuffer
        };
        let view = self.view(data, Some(target));
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: Some(USize64(0)),
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(ty),
            min: bounds.map(|b| json::Value::from(b.0.to_vec())),
            max: bounds.map(|b| json::Value::from(b.1.to_vec())),
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A mesh of one indexed triangle primitive: positions, optional normals and texture
    /// coordinate sets 0 and 1, and the material.
    #[allow(clippy::too_many_arguments)]
    pub fn mesh(
        &mut self,
        name: &str,
        positions: &[[f32; 3]],
        normals: Option<&[[f32; 3]]>,
        uv0: Option<&[[f32; 2]]>,
        uv1: Option<&[[f32; 2]]>,
        indices: &[u32],
        material: Option<json::Index<json::Material>>,
    ) -> json::Index<json::Mesh> {
        use json::accessor::{ComponentType as C, Type as T};
        use json::mesh::Semantic as S;
        let floats =
            |v: &mut dyn Iterator<Item = f32>| v.flat_map(f32::to_le_bytes).collect::<Vec<u8>>();
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for p in positions {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        let mut attributes = std::collections::BTreeMap::new();
        let data = floats(&mut positions.iter().flatten().copied());
        let a = self.accessor(&data, positions.len(), T::Vec3, C::F32, Some((min, max)));
        attributes.insert(Valid(S::Positions), a);
        if let Some(n) = normals {
            let data = floats(&mut n.iter().flatten().copied());
            let a = self.accessor(&data, n.len(), T::Vec3, C::F32, None);
            attributes.insert(Valid(S::Normals), a);
        }
        for (set, uv) in [(0, uv0), (1, uv1)] {
            if let Some(uv) = uv {
                let data = floats(&mut uv.iter().flatten().copied());
                let a = self.accessor(&data, uv.len(), T::Vec2, C::F32, None);
                attributes.insert(Valid(S::TexCoords(set)), a);
            }
        }
        let data: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let idx = self.accessor(&data, indices.len(), T::Scalar, C::U32, None);
        self.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.to_owned()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(idx),
                material,
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        })
    }

    /// A metallic-roughness material.
    pub fn material(&mut self, name: &str, m: MaterialSpec) -> json::Index<json::Material> {
        if m.strength.is_some()
            && !self
                .root
                .extensions_used
                .iter()
                .any(|e| e == "KHR_materials_emissive_strength")
        {
            self.root
                .extensions_used
                .push("KHR_materials_emissive_strength".into());
        }
        #[allow(clippy::needless_update)]
        let extensions = m.strength.map(|s| json::extensions::material::Material {
            emissive_strength: Some(json::extensions::material::EmissiveStrength {
                emissive_strength: json::extensions::material::EmissiveStrengthFactor(s),
            }),
            ..Default::default()
        });
        self.root.push(json::Material {
            name: Some(name.to_owned()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([
                    m.base[0], m.base[1], m.base[2], 1.0,
                ]),
                metallic_factor: json::material::StrengthFactor(m.metallic),
                roughness_factor: json::material::StrengthFactor(m.roughness),
                ..Default::default()
            },
            emissive_factor: json::material::EmissiveFactor(m.emissive),
            extensions,
            ..Default::default()
        })
    }

    /// Gives `material` a base colour texture: the image bytes `png` embedded in the binary
    /// buffer (a buffer view, `image/png`), read from texture coordinate set `tex_coord`
    /// through a sampler with nearest magnification and clamp-to-edge wrapping when
    /// `nearest_clamped`, or without a sampler (glTF's defaults: repeat, linear).
    pub fn base_colour_texture(
        &mut self,
        material: json::Index<json::Material>,
        png: &[u8],
        tex_coord: u32,
        nearest_clamped: bool,
    ) {
        let view = self.view(png, None);
        let source = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some("albedo".into()),
            uri: None,
            extensions: None,
            extras: None,
        });
        let sampler = nearest_clamped.then(|| {
            self.root.push(json::texture::Sampler {
                mag_filter: Some(Valid(json::texture::MagFilter::Nearest)),
                wrap_s: Valid(json::texture::WrappingMode::ClampToEdge),
                wrap_t: Valid(json::texture::WrappingMode::ClampToEdge),
                ..Default::default()
            })
        });
        let texture = self.root.push(json::Texture {
            name: None,
            sampler,
            source,
            extensions: None,
            extras: None,
        });
        self.root.materials[material.value()]
            .pbr_metallic_roughness
            .base_color_texture = Some(json::texture::Info {
            index: texture,
            tex_coord,
            extensions: None,
            extras: None,
        });
    }

    /// A node with a name, an optional mesh and camera, a TRS transform and children.
    pub fn node(
        &mut self,
        name: &str,
        mesh: Option<json::Index<json::Mesh>>,
        camera: Option<json::Index<json::Camera>>,
        trs: Trs,
        children: Vec<json::Index<json::Node>>,
    ) -> json::Index<json::Node> {
        self.root.push(json::Node {
            name: Some(name.to_owned()),
            mesh,
            camera,
            translation: Some(trs.t),
            rotation: Some(json::scene::UnitQuaternion(trs.r)),
            scale: Some(trs.s),
            children: (!children.is_empty()).then_some(children),
            ..Default::default()
        })
    }

    /// A node holding `KHR_lights_punctual` light `light` of `kind` (`"point"`, `"spot"`,
    /// `"directional"`), glTF's photometric `intensity` (cd, or lux for a directional light)
    /// and `color`, `spot` the (inner, outer) cone angles in radians, placed by `trs`.
    pub fn light_node(
        &mut self,
        name: &str,
        kind: &str,
        intensity: f32,
        color: [f32; 3],
        spot: Option<(f32, f32)>,
        trs: Trs,
    ) -> json::Index<json::Node> {
        use json::extensions::scene::khr_lights_punctual as klp;
        let type_ = match kind {
            "point" => klp::Type::Point,
            "spot" => klp::Type::Spot,
            _ => klp::Type::Directional,
        };
        let ext = self.root.extensions.get_or_insert_with(Default::default);
        let lights = &mut ext
            .khr_lights_punctual
            .get_or_insert_with(|| json::extensions::root::KhrLightsPunctual { lights: vec![] })
            .lights;
        lights.push(klp::Light {
            color,
            extensions: None,
            extras: None,
            intensity,
            name: Some(format!("{name} light")),
            range: None,
            spot: spot.map(|(inner, outer)| klp::Spot {
                inner_cone_angle: inner,
                outer_cone_angle: outer,
            }),
            type_: Valid(type_),
        });
        let light = json::Index::new(lights.len() as u32 - 1);
        if !self
            .root
            .extensions_used
            .iter()
            .any(|e| e == "KHR_lights_punctual")
        {
            self.root.extensions_used.push("KHR_lights_punctual".into());
        }
        self.root.push(json::Node {
            name: Some(name.to_owned()),
            translation: Some(trs.t),
            rotation: Some(json::scene::UnitQuaternion(trs.r)),
            scale: Some(trs.s),
            extensions: Some(json::extensions::scene::Node {
                khr_lights_punctual: Some(klp::KhrLightsPunctual { light }),
            }),
            ..Default::default()
        })
    }

    /// A perspective camera: vertical field of view (radians), aspect ratio (width / height).
    pub fn camera(&mut self, yfov: f32, aspect: Option<f32>) -> json::Index<json::Camera> {
        self.root.push(json::Camera {
            name: Some("camera".into()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: aspect,
                yfov,
                zfar: None,
                znear: 0.01,
                extensions: None,
                extras: None,
            }),
            type_: Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: None,
        })
    }

    /// The document with one scene of `roots` (the default scene) and its buffer declared.
    fn close(&mut self, roots: Vec<json::Index<json::Node>>, uri: Option<String>) {
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some("scene".into()),
            nodes: roots,
        });
        self.root.scene = Some(scene);
        self.root.buffers = vec![json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            extensions: None,
            extras: None,
            name: None,
            uri,
        }];
        self.root.asset = json::Asset {
            generator: Some("twopass tests".into()),
            version: "2.0".into(),
            ..Default::default()
        };
    }

    /// The `.glb` bytes of the document with one scene of `roots`.
    pub fn glb(mut self, roots: Vec<json::Index<json::Node>>) -> Vec<u8> {
        self.close(roots, None);
        let mut json_bytes = self.root.to_vec().unwrap();
        while !json_bytes.len().is_multiple_of(4) {
            json_bytes.push(b' ');
        }
        let total = 12 + 8 + json_bytes.len() + 8 + self.bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json_bytes);
        out.extend_from_slice(&(self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        out
    }

    /// Writes the document as `path` (`.gltf`) with its buffer beside it as `bin_name`.
    pub fn write_gltf(mut self, roots: Vec<json::Index<json::Node>>, path: &Path, bin_name: &str) {
        self.close(roots, Some(bin_name.to_owned()));
        let dir = path.parent().unwrap();
        std::fs::write(dir.join(bin_name), &self.bin).unwrap();
        std::fs::write(path, self.root.to_vec().unwrap()).unwrap();
    }
}
