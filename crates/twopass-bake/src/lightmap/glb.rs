//! The lightmap `.glb`: the scene's own triangles with the atlas on `TEXCOORD_1`, the PNG as
//! emissive texture, and the extras that say how to read it back as radiance and where the
//! scene's camera is.

use glam::Vec2;
use gltf_json as json;
use serde::Serialize;
use twopass_scene::Scene;

use super::camera::{CAMERA_NAME, CameraRecord, GltfCamera};
use super::layout::Layout;
use super::reference::Encoded;
use super::settings::Resolved;
use crate::error::BakeError;
use crate::gltf::{Attribute, GlbBuilder};
use crate::weld::SharedVertices;

/// The asset extras of a lightmap `.glb`: how to read its texture back as radiance.
#[derive(Serialize)]
struct LightmapExtras<'a> {
    twopass: LightmapExtrasBody<'a>,
}

#[derive(Serialize)]
struct LightmapExtrasBody<'a> {
    lightmap: &'static str,
    quantity: &'static str,
    texcoord: u32,
    atlas: &'a str,
    exposure: f32,
    radiance_unit: &'static str,
    texel_size: f32,
    texel_size_unit: &'static str,
    padding_texels: u32,
    position_unit: &'static str,
    scene_unit: &'static str,
    metres_per_scene_unit: f64,
    scene: &'a str,
    camera: CameraRecord,
    /// The name of the glTF camera node that places the same camera.
    camera_node: &'static str,
    /// The EXR's [`lightmap_fingerprint`](crate::fingerprint::lightmap_fingerprint), 16 hex
    /// digits: the `.glb` is read only with that EXR.
    exr_fingerprint: String,
    /// The texture engines take and how to decode it (module `reference`).
    #[serde(flatten)]
    engine_texture: serde_json::Value,
}

/// How the lightmap PNG encodes radiance, as recorded in the `.glb`.
pub const PNG_FORMULA: &str = "sRGB-encoded 8-bit of min(1, exposure * L), L the radiance \
     leaving the surface in W/(m^2 sr); the HDR values are in the .exr beside the .glb";

/// The lightmap `.glb` of `scene` on `layout` with `png` embedded and the fingerprint of the
/// EXR beside it (see [`bake_lightmap`]).
///
/// [`bake_lightmap`]: super::bake_lightmap
pub(super) fn encode_lightmap_glb(
    scene: &Scene,
    layout: &Layout,
    s: &Resolved,
    encoded: &Encoded<'_>,
) -> Result<Vec<u8>, BakeError> {
    let m = &scene.mesh;
    let to_metres = scene.unit.metres();
    let mut b = GlbBuilder::new();
    let texture = b.png_texture("twopass lightmap", encoded.png);
    let engine_texture = match encoded.rgbm {
        Some((png, _)) => b.png_texture("twopass lightmap (RGBM)", png),
        None => texture,
    };
    let reference = json_raw(
        &serde_json::json!({ "lightMap": encoded.material_entry(engine_texture.value(), s) }),
    )?;
    let material = b.root.push(json::Material {
        extras: Some(reference),
        name: Some("twopass lightmap (emissive, TEXCOORD_1)".into()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor([0.0, 0.0, 0.0, 1.0]),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(1.0),
            ..Default::default()
        },
        emissive_texture: Some(json::texture::Info {
            index: texture,
            tex_coord: 1,
            extensions: None,
            extras: None,
        }),
        emissive_factor: json::material::EmissiveFactor([1.0; 3]),
        ..Default::default()
    });
    let size = Vec2::new(layout.width as f32, layout.height as f32);
    for object in &scene.objects {
        let mut shared = SharedVertices::default();
        let (mut positions, mut normals, mut uvs, mut indices) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for t in object.triangles.clone() {
            let tri = m.triangle(t);
            let nrm = m.normal_indices(t);
            for k in 0..3 {
                let normal = m.normal(nrm[k]);
                let group = layout.groups[t as usize][k];
                let (v, new) = shared.get(group, tri[k], normal, positions.len() as u32);
                if new {
                    let p = m.position(tri[k]);
                    positions.push((p.as_dvec3() * to_metres).as_vec3());
                    normals.push(normal);
                    uvs.push(layout.corners[t as usize][k] / size);
                }
                indices.push(v);
            }
        }
        if indices.is_empty() {
            continue;
        }
        use json::mesh::Semantic as S;
        b.mesh(
            &object.name,
            &[
                Attribute::Vec3(S::Positions, &positions),
                Attribute::Vec3(S::Normals, &normals),
                // glTF requires TEXCOORD_n to be continuous from 0; set 0 is the same atlas.
                Attribute::Vec2(S::TexCoords(0), &uvs),
                Attribute::Vec2(S::TexCoords(1), &uvs),
            ],
            &indices,
            material,
        );
    }
    add_camera(&mut b, scene)?;
    let scene_name = scene.path.display().to_string();
    let atlas = layout.source.describe();
    let extras = LightmapExtras {
        twopass: LightmapExtrasBody {
            lightmap: s.quantity.png_formula(),
            quantity: s.quantity.name(),
            texcoord: 1,
            atlas: &atlas,
            exposure: encoded.mapping.exposure,
            radiance_unit: "W/(m^2 sr)",
            texel_size: s.texel_size,
            texel_size_unit: scene.unit.symbol(),
            padding_texels: s.padding,
            position_unit: "m",
            scene_unit: scene.unit.symbol(),
            metres_per_scene_unit: to_metres,
            scene: &scene_name,
            camera: CameraRecord::of(scene),
            camera_node: CAMERA_NAME,
            exr_fingerprint: format!("{:016x}", encoded.exr_fingerprint),
            engine_texture: encoded.record(engine_texture.value(), s),
        },
    };
    b.finish(&scene_name, &extras)
}

/// Adds the scene's camera as a glTF perspective camera on a node of the scene
/// ([`GltfCamera`]).
fn add_camera(b: &mut GlbBuilder, scene: &Scene) -> Result<(), BakeError> {
    let bad = |e: serde_json::Error| BakeError::Encode {
        path: "lightmap glb".into(),
        message: format!("the camera: {e}"),
    };
    let camera = GltfCamera::of(scene);
    let index = b.root.cameras.len();
    b.root
        .cameras
        .push(serde_json::from_value(camera.camera_json()).map_err(bad)?);
    let node = b
        .root
        .push::<json::Node>(serde_json::from_value(camera.node_json(index)).map_err(bad)?);
    b.nodes.push(node);
    Ok(())
}

/// `value` as the raw JSON of a glTF `extras`.
fn json_raw(value: &serde_json::Value) -> Result<Box<serde_json::value::RawValue>, BakeError> {
    serde_json::value::to_raw_value(value).map_err(|e| BakeError::Encode {
        path: "lightmap glb".into(),
        message: e.to_string(),
    })
}
