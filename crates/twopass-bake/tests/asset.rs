//! The user's glTF written back with the lightmap (`Lightmap::asset`): the Khronos validator
//! accepts it, and read back with the `gltf` crate it keeps the input's nodes, names,
//! materials and every triangle's positions and `TEXCOORD_0`, with the atlas on `TEXCOORD_1`
//! and the lightmap referenced from the materials' extras; a valid `TEXCOORD_1` of the user's
//! own is kept byte for byte.

use std::path::Path;

use twopass_bake::lightmap::{AtlasSource, Lightmap, LightmapSettings, TexelSource, bake_lightmap};
use twopass_bake::{ColorMapping, LightmapQuantity};
use twopass_scene::Scene;
use twopass_tests::gltf::{GltfWriter, MaterialSpec, Trs};

use crate::common::solve;
use crate::validator::assert_valid;

/// A square of side `side` in the xz plane at the origin, facing +y (or -y), with
/// `TEXCOORD_0` over [0, 1]^2 (none when it faces down without `uv1`: glTF wants set 0 where
/// set 1 is) and, when given, `TEXCOORD_1` = `uv1` of its four corners.
fn square(
    w: &mut GltfWriter,
    name: &str,
    side: f32,
    up: bool,
    uv1: Option<&[[f32; 2]; 4]>,
    material: gltf_json::Index<gltf_json::Material>,
) -> gltf_json::Index<gltf_json::Mesh> {
    let p = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, side],
        [side, 0.0, side],
        [side, 0.0, 0.0],
    ];
    let n = if up {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, -1.0, 0.0]
    };
    let uv0 = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
    let indices: &[u32] = if up {
        &[0, 1, 2, 0, 2, 3]
    } else {
        &[0, 2, 1, 0, 3, 2]
    };
    w.mesh(
        name,
        &p,
        Some(&[n; 4]),
        (up || uv1.is_some()).then_some(uv0.as_slice()),
        uv1.map(|u| u.as_slice()),
        indices,
        Some(material),
    )
}

/// A floor (2 m), a lamp above it facing down, and one tile mesh shown by two nodes (one of
/// them under a scaled, turned parent); with `own_uv1`, every square carries its own
/// non-overlapping `TEXCOORD_1` (the tiles' two uses then overlap, so only without the
/// instanced tile).
pub(crate) fn room(own_uv1: bool) -> Vec<u8> {
    let (w, roots) = room_document(own_uv1);
    w.glb(roots)
}

/// The document of [`room`] and its root nodes.
pub(crate) fn room_document(own_uv1: bool) -> (GltfWriter, Vec<gltf_json::Index<gltf_json::Node>>) {
    let mut w = GltfWriter::new();
    let grey = w.material("Grey", MaterialSpec::default());
    let red = w.material(
        "Red",
        MaterialSpec {
            base: [0.7, 0.1, 0.1],
            ..MaterialSpec::default()
        },
    );
    let lamp_material = w.material(
        "Lamp",
        MaterialSpec {
            base: [0.0; 3],
            emissive: [1.0, 1.0, 1.0],
            strength: Some(20.0),
            ..MaterialSpec::default()
        },
    );
    let left = [[0.0, 0.0], [0.0, 0.5], [0.5, 0.5], [0.5, 0.0]];
    let right = [[0.5, 0.5], [0.5, 1.0], [1.0, 1.0], [1.0, 0.5]];
    let floor = square(
        &mut w,
        "FloorMesh",
        2.0,
        true,
        own_uv1.then_some(&left),
        grey,
    );
    let lamp = square(
        &mut w,
        "LampMesh",
        0.5,
        false,
        own_uv1.then_some(&right),
        lamp_material,
    );
    let floor_node = w.node(
        "Floor",
        Some(floor),
        None,
        Trs {
            t: [-1.0, 0.0, -1.0],
            ..Trs::default()
        },
        vec![],
    );
    let lamp_node = w.node(
        "Lamp",
        Some(lamp),
        None,
        Trs {
            t: [-0.25, 1.5, -0.25],
            ..Trs::default()
        },
        vec![],
    );
    let mut roots = vec![floor_node, lamp_node];
    if !own_uv1 {
        let tile = square(&mut w, "TileMesh", 0.3, true, None, red);
        let a = w.node(
            "TileA",
            Some(tile),
            None,
            Trs {
                t: [-0.8, 0.01, -0.8],
                ..Trs::default()
            },
            vec![],
        );
        let b = w.node(
            "TileB",
            Some(tile),
            None,
            Trs {
                t: [0.0, 0.0, 0.0],
                ..Trs::default()
            },
            vec![],
        );
        let h = std::f32::consts::FRAC_PI_8;
        let parent = w.node(
            "Turned",
            None,
            None,
            Trs {
                t: [0.3, 0.02, 0.2],
                r: [0.0, h.sin(), 0.0, h.cos()],
                s: [1.5, 1.0, 1.5],
            },
            vec![b],
        );
        roots.extend([a, parent]);
    }
    (w, roots)
}

pub(crate) fn baked(bytes: &[u8], dir: &Path) -> (Scene, Lightmap) {
    let path = dir.join("room.glb");
    std::fs::write(&path, bytes).unwrap();
    let (scene, _) = twopass_scene::load(&path).unwrap();
    let solution = solve(&scene, 0.1);
    let settings = LightmapSettings {
        texel_size: Some(0.02),
        ..LightmapSettings::default()
    };
    let lm = bake_lightmap(
        TexelSource::Solution(&solution),
        &scene,
        &settings,
        ColorMapping { exposure: 1.0 },
    )
    .unwrap();
    (scene, lm)
}

/// Every triangle of every primitive shown by node `name`, each corner as its position and
/// `TEXCOORD_0` bits (zeros unless `with_uv0`), the corners in their order and the triangles
/// sorted.
fn triangles(doc: &gltf::Gltf, node: &str, with_uv0: bool) -> Vec<[[u32; 5]; 3]> {
    let blob = doc.blob.as_deref().unwrap();
    let node = doc.nodes().find(|n| n.name() == Some(node)).unwrap();
    let mut out = Vec::new();
    for p in node.mesh().unwrap().primitives() {
        let r = p.reader(|_| Some(blob));
        let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
        // A primitive without TEXCOORD_0 (the lamp) is given the atlas there: compare it as
        // zeros.
        let uv: Vec<[f32; 2]> = match r.read_tex_coords(0) {
            Some(uv) if with_uv0 => uv.into_f32().collect(),
            _ => vec![[0.0; 2]; pos.len()],
        };
        let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
        for t in idx.chunks_exact(3) {
            out.push([0, 1, 2].map(|k| {
                let v = t[k] as usize;
                let (p, u) = (pos[v], uv[v]);
                [p[0], p[1], p[2], u[0], u[1]].map(f32::to_bits)
            }));
        }
    }
    out.sort_unstable();
    out
}

#[test]
fn the_asset_comes_back_whole_with_the_lightmap_on_texcoord_1() {
    let dir = tempfile::tempdir().unwrap();
    let input = room(false);
    let (scene, lm) = baked(&input, dir.path());
    assert!(
        matches!(lm.atlas, AtlasSource::Generated(_)),
        "{:?}",
        lm.atlas
    );
    assert_eq!(lm.quantity, LightmapQuantity::Irradiance);
    let asset = lm.asset.as_ref().expect("a glTF scene gets its asset back");
    if let Some(report) = assert_valid("room.lightmapped.glb", asset) {
        assert_eq!(report["info"]["maxUVs"], 2, "{report}");
    }
    let before = gltf::Gltf::from_slice(&input).unwrap();
    let after = gltf::Gltf::from_slice(asset).unwrap();
    let names = |d: &gltf::Gltf| -> Vec<Option<String>> {
        d.nodes().map(|n| n.name().map(str::to_owned)).collect()
    };
    // The nodes are the input's, then the scene's camera (the input has none).
    let mut with_camera = names(&before);
    with_camera.push(Some(twopass_bake::lightmap::CAMERA_NAME.to_owned()));
    assert_eq!(with_camera, names(&after));
    let materials = |d: &gltf::Gltf| -> Vec<(Option<String>, [f32; 4], [f32; 3])> {
        d.materials()
            .map(|m| {
                (
                    m.name().map(str::to_owned),
                    m.pbr_metallic_roughness().base_color_factor(),
                    m.emissive_factor(),
                )
            })
            .collect()
    };
    assert_eq!(materials(&before), materials(&after));
    for node in ["Floor", "Lamp", "TileA", "TileB"] {
        // The same triangles, corner for corner, with their TEXCOORD_0.
        let uv0 = node != "Lamp";
        assert_eq!(
            triangles(&before, node, uv0),
            triangles(&after, node, uv0),
            "{node}"
        );
        let n = after.nodes().find(|n| n.name() == Some(node)).unwrap();
        let mesh = n.mesh().unwrap();
        let original = before.nodes().find(|n| n.name() == Some(node)).unwrap();
        assert_eq!(mesh.name(), original.mesh().unwrap().name(), "{node}");
        for p in mesh.primitives() {
            let blob = after.blob.as_deref().unwrap();
            let uv1: Vec<[f32; 2]> = p
                .reader(|_| Some(blob))
                .read_tex_coords(1)
                .unwrap()
                .into_f32()
                .collect();
            assert!(
                uv1.iter().flatten().all(|c| (0.0..=1.0).contains(c)),
                "{node}"
            );
        }
    }
    // The two tiles share a mesh in the input and have one each in the asset (their own
    // places in the atlas).
    let mesh_of = |d: &gltf::Gltf, n: &str| {
        d.nodes()
            .find(|x| x.name() == Some(n))
            .unwrap()
            .mesh()
            .unwrap()
            .index()
    };
    assert_eq!(mesh_of(&before, "TileA"), mesh_of(&before, "TileB"));
    assert_ne!(mesh_of(&after, "TileA"), mesh_of(&after, "TileB"));
    // Every baked material refers to the lightmap texture on set 1, an embedded PNG.
    let json: serde_json::Value =
        serde_json::from_slice(&after.document.clone().into_json().to_vec().unwrap()).unwrap();
    let record = &json["asset"]["extras"]["twopass"];
    assert_eq!(record["quantity"], "irradiance");
    let texture = record["texture"].as_u64().unwrap();
    for m in json["materials"].as_array().unwrap() {
        let l = &m["extras"]["lightMap"];
        assert_eq!(l["index"].as_u64(), Some(texture), "{m}");
        assert_eq!(l["texCoord"], 1);
        let pi = std::f64::consts::PI;
        assert!((l["intensity"].as_f64().unwrap() - pi).abs() < 1e-6, "{l}");
    }
    let image = after.textures().nth(texture as usize).unwrap().source();
    match image.source() {
        gltf::image::Source::View { view, mime_type } => {
            assert_eq!(mime_type, "image/png");
            let blob = after.blob.as_deref().unwrap();
            assert_eq!(
                &blob[view.offset()..view.offset() + view.length()],
                lm.rgbm.as_ref().unwrap().0.as_slice()
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(scene.objects.len(), 4);
}

#[test]
fn a_valid_texcoord_1_of_the_users_is_the_atlas_and_the_geometry_is_kept_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let input = room(true);
    let (_, lm) = baked(&input, dir.path());
    assert_eq!(lm.atlas, AtlasSource::Scene);
    let asset = lm.asset.as_ref().unwrap();
    assert_valid("room-uv1.lightmapped.glb", asset);
    let before = gltf::Gltf::from_slice(&input).unwrap();
    let after = gltf::Gltf::from_slice(asset).unwrap();
    let (b0, b1) = (
        before.blob.as_deref().unwrap(),
        after.blob.as_deref().unwrap(),
    );
    // The input's buffer is the asset's first bytes, and every accessor reads the same.
    assert_eq!(&b1[..b0.len()], b0);
    assert_eq!(before.accessors().count(), after.accessors().count());
    let uv1 = |p: &gltf::Primitive<'_>, blob: &[u8]| -> Vec<[f32; 2]> {
        p.reader(|_| Some(blob))
            .read_tex_coords(1)
            .unwrap()
            .into_f32()
            .collect()
    };
    for (a, b) in before.meshes().zip(after.meshes()) {
        for (p, q) in a.primitives().zip(b.primitives()) {
            assert_eq!(uv1(&p, b0), uv1(&q, b1));
        }
    }
}

#[test]
fn a_gltf_with_external_buffer_and_image_comes_back_as_one_glb() {
    use gltf_json as json;
    let dir = tempfile::tempdir().unwrap();
    let (mut w, roots) = room_document(false);
    // A 2 x 2 PNG beside the document, as the floor material's base colour texture.
    let mut png = Vec::new();
    {
        let mut e = png::Encoder::new(&mut png, 2, 2);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        let mut writer = e.write_header().unwrap();
        writer
            .write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
            .unwrap();
    }
    std::fs::write(dir.path().join("checker.png"), &png).unwrap();
    let image = w.root.push(json::Image {
        buffer_view: None,
        mime_type: None,
        name: Some("checker".into()),
        uri: Some("checker.png".into()),
        extensions: None,
        extras: None,
    });
    let texture = w.root.push(json::Texture {
        name: None,
        sampler: None,
        source: image,
        extensions: None,
        extras: None,
    });
    w.root.materials[0]
        .pbr_metallic_roughness
        .base_color_texture = Some(json::texture::Info {
        index: texture,
        tex_coord: 0,
        extensions: None,
        extras: None,
    });
    let path = dir.path().join("room.gltf");
    w.write_gltf(roots, &path, "room.bin");
    let (scene, warnings) = twopass_scene::load(&path).unwrap();
    // The texture is the floor's albedo, read from the PNG beside the document.
    assert_eq!(scene.textures.len(), 1);
    assert!(
        warnings
            .iter()
            .all(|w| !w.to_string().contains("baseColorTexture")),
        "{warnings:?}"
    );
    let solution = solve(&scene, 0.1);
    let settings = LightmapSettings {
        texel_size: Some(0.02),
        ..LightmapSettings::default()
    };
    let lm = bake_lightmap(
        TexelSource::Solution(&solution),
        &scene,
        &settings,
        ColorMapping { exposure: 1.0 },
    )
    .unwrap();
    let asset = lm.asset.unwrap();
    assert_valid("room-gltf.lightmapped.glb", &asset);
    // One buffer, the binary chunk; the user's image embedded byte for byte.
    let after = gltf::Gltf::from_slice(&asset).unwrap();
    assert_eq!(after.buffers().count(), 1);
    let blob = after.blob.as_deref().unwrap();
    let checker = after
        .images()
        .find(|i| i.name() == Some("checker"))
        .unwrap();
    match checker.source() {
        gltf::image::Source::View { view, mime_type } => {
            assert_eq!(mime_type, "image/png");
            assert_eq!(
                &blob[view.offset()..view.offset() + view.length()],
                png.as_slice()
            );
        }
        other => panic!("{other:?}"),
    }
    let floor = after.nodes().find(|n| n.name() == Some("Floor")).unwrap();
    let p = floor.mesh().unwrap().primitives().next().unwrap();
    let info = p
        .material()
        .pbr_metallic_roughness()
        .base_color_texture()
        .unwrap();
    assert_eq!(info.texture().source().name(), Some("checker"));
}
