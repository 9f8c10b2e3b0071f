use std::path::Path;

use glam::Vec3;
use twopass_tests::gltf::{GltfWriter, MaterialSpec, Trs};

use crate::{SceneError, Warning, load};

/// One triangle's corners in its mesh's space.
const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A rotation of 90 degrees about +y as a quaternion (x, y, z, w).
fn quarter_turn_y() -> [f32; 4] {
    let h = std::f32::consts::FRAC_PI_4;
    [0.0, h.sin(), 0.0, h.cos()]
}

/// A hierarchy: `Parent` (scale 2, 3, 4; 90 degrees about y; translation 1, 2, 3) holding
/// `A` (translation 0, 0, 5) showing the triangle mesh with an emissive material; `B` at the
/// root (translation 10, 0, 0) showing the same mesh (instanced) with a grey one; a camera
/// node at (0, 1, 10).
fn hierarchy() -> Vec<u8> {
    let mut w = GltfWriter::new();
    let lamp = w.material(
        "Lamp",
        MaterialSpec {
            base: [0.8, 0.8, 0.8],
            emissive: [1.0, 0.5, 0.25],
            strength: Some(4.0),
            ..MaterialSpec::default()
        },
    );
    let mesh = w.mesh("Tri", &TRIANGLE, None, None, None, &[0, 1, 2], Some(lamp));
    let a = w.node(
        "A",
        Some(mesh),
        None,
        Trs {
            t: [0.0, 0.0, 5.0],
            ..Trs::default()
        },
        vec![],
    );
    let parent = w.node(
        "Parent",
        None,
        None,
        Trs {
            t: [1.0, 2.0, 3.0],
            r: quarter_turn_y(),
            s: [2.0, 3.0, 4.0],
        },
        vec![a],
    );
    let b = w.node(
        "B",
        Some(mesh),
        None,
        Trs {
            t: [10.0, 0.0, 0.0],
            ..Trs::default()
        },
        vec![],
    );
    let camera = w.camera(0.8, Some(1.5));
    let eye = w.node(
        "Eye",
        None,
        Some(camera),
        Trs {
            t: [0.0, 1.0, 10.0],
            ..Trs::default()
        },
        vec![],
    );
    w.glb(vec![parent, b, eye])
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn hierarchy_instances_camera_and_emission_load_in_world_space() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "h.glb", &hierarchy());
    let (scene, warnings) = load(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["A", "B"]);
    // The mesh both nodes show is stored once: B places A's triangle again.
    assert_eq!(scene.mesh.stored_triangle_count(), 1);
    assert_eq!(scene.mesh.triangle_count(), 2);
    assert_eq!(scene.mesh.repeats().len(), 1);
    assert_eq!(scene.mesh.repeats()[0].object, 1);
    // A: p -> T + R_y(90) (S (p + (0, 0, 5))), with R_y(90) (x, y, z) = (z, y, -x), worked by
    // hand: (0,0,0) -> S (0,0,20) -> R (20,0,0) -> (21,2,3); (1,0,0) -> (2,0,20) -> (20,0,-2)
    // -> (21,2,1); (0,1,0) -> (0,3,20) -> (20,3,0) -> (21,5,3).
    let expected_a = [
        Vec3::new(21.0, 2.0, 3.0),
        Vec3::new(21.0, 2.0, 1.0),
        Vec3::new(21.0, 5.0, 3.0),
    ];
    let expected_b = [
        Vec3::new(10.0, 0.0, 0.0),
        Vec3::new(11.0, 0.0, 0.0),
        Vec3::new(10.0, 1.0, 0.0),
    ];
    for (o, expected) in scene.objects.iter().zip([expected_a, expected_b]) {
        let t = o.triangles.start;
        assert_eq!(o.triangles.len(), 1);
        let got = scene.mesh.corners(t);
        for (g, e) in got.iter().zip(expected) {
            assert!(
                (*g - e).length() < 1e-5,
                "{}: {got:?} vs {expected:?}",
                o.name
            );
        }
    }
    // The emission: emissiveFactor times the strength, W/(m^2 sr).
    assert_eq!(scene.objects[0].emission.to_array(), [4.0, 2.0, 1.0]);
    assert_eq!(scene.objects[1].emission.to_array(), [4.0, 2.0, 1.0]);
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.materials[0].name, "Lamp");
    assert_eq!(
        scene.materials[0].material.diffuse_albedo().to_array(),
        [0.8; 3]
    );
    // The camera: at its node, looking down -z, 1.5 aspect at 512 pixels high.
    let c = &scene.camera;
    assert!((c.position - Vec3::new(0.0, 1.0, 10.0)).length() < 1e-6);
    assert!((c.forward - Vec3::NEG_Z).length() < 1e-6);
    assert!((c.fov_y - 0.8).abs() < 1e-6);
    assert_eq!((c.width, c.height), (768, 512));
    // The origins: node, mesh, primitive of each object.
    let src = scene.gltf.as_ref().unwrap();
    let origins: Vec<(usize, usize)> = src.origins.iter().map(|o| (o.node, o.mesh)).collect();
    assert_eq!(origins, [(0, 0), (2, 0)]);
    // The camera's node is recorded, so a bake writing the asset back adds no second one.
    let doc = gltf::json::Root::from_slice(&src.json).unwrap();
    let node = src.camera_node.expect("the camera's node");
    assert_eq!(doc.nodes[node].name.as_deref(), Some("Eye"));
}

#[test]
fn a_gltf_with_its_buffer_in_a_file_loads_and_a_missing_buffer_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::new();
    let grey = w.material("Grey", MaterialSpec::default());
    let mesh = w.mesh("Tri", &TRIANGLE, None, None, None, &[0, 1, 2], Some(grey));
    let n = w.node("Only", Some(mesh), None, Trs::default(), vec![]);
    let path = dir.path().join("s.gltf");
    w.write_gltf(vec![n], &path, "s.bin");
    let (scene, warnings) = load(&path).unwrap();
    assert_eq!(scene.objects.len(), 1);
    // No camera: the default framing (no camera node recorded); nothing emits.
    assert_eq!(scene.gltf.as_ref().unwrap().camera_node, None);
    assert!(
        warnings
            .iter()
            .any(|w| matches!(w, Warning::NoEmitters { .. }))
    );
    std::fs::remove_file(dir.path().join("s.bin")).unwrap();
    let err = load(&path).unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with(&format!("{}: buffer 0: ", path.display()))
            && text.contains("s.bin: cannot read"),
        "{text}"
    );
}

/// A glb of one triangle whose index buffer holds `indices` and whose positions are `p`.
fn one_triangle(p: &[[f32; 3]], indices: &[u32]) -> Vec<u8> {
    let mut w = GltfWriter::new();
    let grey = w.material("Grey", MaterialSpec::default());
    let mesh = w.mesh("Tri", p, None, None, None, indices, Some(grey));
    let n = w.node("Chair", Some(mesh), None, Trs::default(), vec![]);
    w.glb(vec![n])
}

#[test]
fn broken_geometry_is_an_error_naming_node_mesh_and_primitive() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "bad.glb", &one_triangle(&TRIANGLE, &[0, 1, 7]));
    let err = load(&path).unwrap_err();
    assert!(matches!(err, SceneError::Gltf { .. }), "{err:?}");
    assert_eq!(
        err.to_string(),
        format!(
            "{}: node 0 `Chair`, mesh 0 `Tri`, primitive 0: index 2 is 7, out of range for the 3 vertices of POSITION",
            path.display()
        )
    );
    let nan = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let path = write(dir.path(), "nan.glb", &one_triangle(&nan, &[0, 1, 2]));
    assert_eq!(
        load(&path).unwrap_err().to_string(),
        format!(
            "{}: node 0 `Chair`, mesh 0 `Tri`, primitive 0: POSITION 1 is not finite ([NaN, 0, 0])",
            path.display()
        )
    );
}

#[test]
fn a_buffer_shorter_than_its_byte_length_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = one_triangle(&TRIANGLE, &[0, 1, 2]);
    // Cut the binary chunk's last 8 bytes (and say so in its header and the file's), so the
    // buffer is shorter than its byteLength.
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let bin_len = u32::from_le_bytes(bytes[bin_at..bin_at + 4].try_into().unwrap()) - 8;
    bytes.truncate(bytes.len() - 8);
    bytes[bin_at..bin_at + 4].copy_from_slice(&bin_len.to_le_bytes());
    let total = bytes.len() as u32;
    bytes[8..12].copy_from_slice(&total.to_le_bytes());
    let path = write(dir.path(), "short.glb", &bytes);
    let text = load(&path).unwrap_err().to_string();
    assert_eq!(
        text,
        format!(
            "{}: buffer 0: holds {bin_len} bytes, fewer than its byteLength of {}",
            path.display(),
            bin_len + 8
        )
    );
}

#[test]
fn not_a_gltf_is_an_error_and_unmodelled_parts_are_warned() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "x.gltf", b"{ not json");
    let text = load(&path).unwrap_err().to_string();
    assert!(
        text.starts_with(&format!(
            "{}: the document: not a valid glTF 2.0 file",
            path.display()
        )),
        "{text}"
    );
    // A half-metal and a material without textures: the metallic warning names the material.
    let mut w = GltfWriter::new();
    let m = w.material(
        "Brushed",
        MaterialSpec {
            metallic: 0.7,
            roughness: 0.5,
            ..MaterialSpec::default()
        },
    );
    let mesh = w.mesh("Tri", &TRIANGLE, None, None, None, &[0, 1, 2], Some(m));
    let n = w.node("N", Some(mesh), None, Trs::default(), vec![]);
    let path = write(dir.path(), "metal.glb", &w.glb(vec![n]));
    let (scene, warnings) = load(&path).unwrap();
    let text: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        text.contains(&format!(
            "{}: material 0 `Brushed`: metallicFactor 0.7 taken as 1 (a conductor)",
            path.display()
        )),
        "{text:?}"
    );
    // Rough metal: Cook-Torrance with Beckmann m = roughness^2, no diffuse part.
    let mat = &scene.materials[0].material;
    assert_eq!(mat.diffuse_albedo().to_array(), [0.0; 3]);
    match mat.lobe() {
        Some(twopass_brdf::Lobe::CookTorrance { roughness, .. }) => {
            assert!((roughness - 0.25).abs() < 1e-6, "{roughness}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn base64_decodes_rfc_4648_vectors() {
    use super::read::base64;
    // RFC 4648, section 10.
    for (text, plain) in [
        ("", ""),
        ("Zg==", "f"),
        ("Zm8=", "fo"),
        ("Zm9v", "foo"),
        ("Zm9vYg==", "foob"),
        ("Zm9vYmE=", "fooba"),
        ("Zm9vYmFy", "foobar"),
    ] {
        assert_eq!(base64(text).unwrap(), plain.as_bytes(), "{text}");
    }
    assert!(base64("Zm9v!").is_err());
}

#[test]
fn no_corrupted_byte_makes_the_loader_panic() {
    // Every byte of a small glb replaced by 0x00, 0xff and itself + 1 in turn (lengths,
    // offsets, counts, indices, floats and JSON text): each load returns, a scene or an error.
    let dir = tempfile::tempdir().unwrap();
    let bytes = hierarchy();
    let path = dir.path().join("c.glb");
    let (mut loaded, mut refused) = (0, 0);
    for i in 0..bytes.len() {
        for value in [0x00, 0xff, bytes[i].wrapping_add(1)] {
            let mut b = bytes.clone();
            b[i] = value;
            std::fs::write(&path, &b).unwrap();
            match load(&path) {
                Ok(_) => loaded += 1,
                Err(_) => refused += 1,
            }
        }
    }
    assert!(
        loaded > 0 && refused > 0,
        "{loaded} loaded, {refused} refused"
    );
}

#[test]
fn a_confined_load_refuses_a_buffer_outside_the_scene_folder() {
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("scene");
    std::fs::create_dir(&inner).unwrap();
    let mut w = GltfWriter::new();
    let grey = w.material("Grey", MaterialSpec::default());
    let mesh = w.mesh("Tri", &TRIANGLE, None, None, None, &[0, 1, 2], Some(grey));
    let n = w.node("Only", Some(mesh), None, Trs::default(), vec![]);
    let path = inner.join("s.gltf");
    // The buffer is written beside the scene's folder and named by `../`.
    w.write_gltf(vec![n], &path, "../outside.bin");
    assert!(load(&path).is_ok());
    let policy = crate::ReadPolicy::confined(&path).unwrap();
    let text = crate::load_with(&path, &policy).unwrap_err().to_string();
    assert!(
        text.starts_with(&format!("{}: buffer 0: ", path.display()))
            && text.contains("lies outside the scene's folder"),
        "{text}"
    );
}

#[test]
fn transmission_with_ior_is_a_dielectric_and_a_smooth_metal_a_conductor() {
    use gltf::json;
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::new();
    let glass = w.material(
        "Water",
        MaterialSpec {
            base: [1.0; 3],
            roughness: 0.0,
            ..MaterialSpec::default()
        },
    );
    let gold = w.material(
        "Gold",
        MaterialSpec {
            base: [1.0, 0.78, 0.34],
            metallic: 1.0,
            roughness: 0.0,
            ..MaterialSpec::default()
        },
    );
    #[allow(clippy::needless_update)]
    let extensions = json::extensions::material::Material {
        transmission: Some(json::extensions::material::Transmission {
            transmission_factor: json::extensions::material::TransmissionFactor(1.0),
            transmission_texture: None,
            extras: None,
        }),
        ior: Some(json::extensions::material::Ior {
            ior: json::extensions::material::IndexOfRefraction(1.33),
            extras: None,
        }),
        ..Default::default()
    };
    w.root.materials[glass.value()].extensions = Some(extensions);
    w.root.extensions_used.extend([
        "KHR_materials_transmission".to_owned(),
        "KHR_materials_ior".to_owned(),
    ]);
    let a = w.mesh("A", &TRIANGLE, None, None, None, &[0, 1, 2], Some(glass));
    let b = w.mesh("B", &TRIANGLE, None, None, None, &[0, 1, 2], Some(gold));
    let na = w.node("Glass", Some(a), None, Trs::default(), vec![]);
    let nb = w.node(
        "Metal",
        Some(b),
        None,
        Trs {
            t: [2.0, 0.0, 0.0],
            ..Trs::default()
        },
        vec![],
    );
    let path = write(dir.path(), "m.glb", &w.glb(vec![na, nb]));
    let (scene, warnings) = load(&path).unwrap();
    // A clear, smooth, fully transmitting material: nothing lost, no warning of it; the gold's
    // red channel of 1 is clamped, as said.
    let text: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
    let p = path.display();
    assert_eq!(
        text,
        [
            format!(
                "{p}: material 1 `Gold`: baseColorFactor [1.0, 0.78, 0.34] clamped to [0.999, 0.78, 0.34] (a reflectance must be below 1)"
            ),
            format!("{p}: nothing in the scene emits light: every render will be black"),
        ]
    );
    match scene.materials[0].material.lobe() {
        Some(twopass_brdf::Lobe::Dielectric { ior }) => assert_eq!(*ior, 1.33),
        other => panic!("{other:?}"),
    }
    // The gold: a smooth conductor whose normal-incidence reflectance is the base colour
    // (clamped to 0.999 where it is 1).
    match scene.materials[1].material.lobe() {
        Some(twopass_brdf::Lobe::Conductor { ior }) => {
            for (c, f0) in [0.999f32, 0.78, 0.34].into_iter().enumerate() {
                let r =
                    twopass_brdf::fresnel::complex(1.0, ior.n.to_array()[c], ior.k.to_array()[c]);
                assert!((r - f0).abs() < 1e-4, "channel {c}: {r} vs {f0}");
            }
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn khr_lights_punctual_lamps_load_placed_aimed_and_in_watts() {
    use crate::{Lamp, LampKind};
    let dir = tempfile::tempdir().unwrap();
    let mut w = GltfWriter::new();
    let grey = w.material("Grey", MaterialSpec::default());
    let mesh = w.mesh("Tri", &TRIANGLE, None, None, None, &[0, 1, 2], Some(grey));
    let floor = w.node("Floor", Some(mesh), None, Trs::default(), vec![]);
    // A point lamp of 100 W as Blender writes it: 100 / (4 pi) * 683 cd, under a parent that
    // moves it by (1, 2, 3).
    let watts = 100.0f32;
    let bulb = w.light_node(
        "Bulb",
        "point",
        watts / (4.0 * std::f32::consts::PI) * 683.0,
        [1.0, 1.0, 1.0],
        None,
        Trs {
            t: [0.0, 0.0, 5.0],
            ..Trs::default()
        },
    );
    let holder = w.node(
        "Holder",
        None,
        None,
        Trs {
            t: [1.0, 2.0, 3.0],
            ..Trs::default()
        },
        vec![bulb],
    );
    // A spot turned 90 degrees about +y: its -z becomes -x.
    let spot = w.light_node(
        "Spot",
        "spot",
        683.0 * 2.0,
        [1.0, 1.0, 1.0],
        Some((0.25, 0.5)),
        Trs {
            r: quarter_turn_y(),
            ..Trs::default()
        },
    );
    // A sun of 3 W/m^2 (3 * 683 lux), tinted.
    let sun = w.light_node(
        "Sun",
        "directional",
        683.0 * 3.0,
        [1.0, 0.5, 0.25],
        None,
        Trs::default(),
    );
    let path = write(dir.path(), "l.glb", &w.glb(vec![floor, holder, spot, sun]));
    let (scene, warnings) = load(&path).unwrap();
    assert!(
        !warnings
            .iter()
            .any(|w| matches!(w, Warning::NoEmitters { .. })),
        "{warnings:?}"
    );
    let by_name = |n: &str| -> &Lamp { scene.lamps.iter().find(|l| l.name == n).unwrap() };
    let bulb = by_name("Bulb");
    assert_eq!(bulb.kind, LampKind::Point);
    assert!((bulb.position - Vec3::new(1.0, 2.0, 8.0)).length() < 1e-6);
    let power = bulb.power(scene.bounds.diagonal());
    assert!((power.x - watts).abs() < 1e-4 * watts, "{power}");
    let spot = by_name("Spot");
    let LampKind::Spot {
        direction,
        cos_inner,
        cos_outer,
    } = spot.kind
    else {
        panic!("{spot:?}")
    };
    assert!((direction - Vec3::NEG_X).length() < 1e-6, "{direction}");
    assert_eq!((cos_inner, cos_outer), (0.25f32.cos(), 0.5f32.cos()));
    assert!((spot.intensity.x - 2.0).abs() < 1e-6);
    let sun = by_name("Sun");
    assert_eq!(
        sun.kind,
        LampKind::Directional {
            direction: Vec3::NEG_Z
        }
    );
    let e = sun.intensity.to_array();
    for (got, want) in e.iter().zip([3.0, 1.5, 0.75]) {
        assert!((got - want).abs() < 1e-6, "{e:?}");
    }
}

/// `bytes` (a `.glb`) with `insert` put at the start of its JSON object, the chunk padded
/// with spaces and both lengths updated.
fn with_json(bytes: &[u8], insert: &str) -> Vec<u8> {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = std::str::from_utf8(&bytes[20..20 + json_len]).unwrap();
    let mut json = json.replacen('{', &format!("{{{insert}"), 1);
    while json.len() % 4 != 0 {
        json.push(' ');
    }
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json.as_bytes());
    out.extend_from_slice(&bytes[20 + json_len..]);
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

/// Issue 43's long fuzz run: an image with a buffer view but no mimeType (which glTF requires
/// with one), or with neither a uri nor a buffer view, made the gltf crate's `Image::source`
/// panic; each is refused naming the image.
#[test]
fn an_image_the_gltf_crate_cannot_read_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let glb = one_triangle(&TRIANGLE, &[0, 1, 2]);
    for (image, problem) in [
        (
            r#"{"bufferView":0}"#,
            "has a bufferView but no mimeType (glTF requires one with it)",
        ),
        (r#"{"name":"x"}"#, "has neither a uri nor a bufferView"),
    ] {
        let bytes = with_json(&glb, &format!(r#""images":[{image}],"#));
        let path = write(dir.path(), "image.glb", &bytes);
        let err = load(&path).unwrap_err().to_string();
        assert_eq!(err, format!("{}: image 0: {problem}", path.display()));
    }
    // The same document with a mimeType loads.
    let bytes = with_json(
        &glb,
        r#""images":[{"bufferView":0,"mimeType":"image/png"}],"#,
    );
    load(write(dir.path(), "fine.glb", &bytes)).unwrap();
}
