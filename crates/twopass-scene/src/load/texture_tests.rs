//! Textures through the loaders: an OBJ's `map_Kd` and a glTF's `baseColorTexture` read into
//! the scene (PNGs written here with the `image` crate), and the sRGB decoding against
//! published values.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;
use twopass_brdf::Rgb;
use twopass_tests::gltf::{GltfWriter, MaterialSpec, Trs};

use crate::{Scene, load};

/// A 2 x 2 RGB image, top row first: red, green; blue, grey 128.
const TEXELS: [u8; 12] = [255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128];

/// sRGB 128 in linear light: ((128 / 255 + 0.055) / 1.055)^2.4, as tabulated.
const GREY_128: f32 = 0.215_860_5;

fn png(width: u32, height: u32, texels: &[u8]) -> Vec<u8> {
    let img = image::RgbImage::from_raw(width, height, texels.to_vec()).expect("sizes agree");
    let mut out = Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb8(img)
        .write_to(&mut out, image::ImageOutputFormat::Png)
        .expect("encodes");
    out.into_inner()
}

/// The diffuse albedo at the point `p` of the plane z = 0 (found on whichever triangle holds
/// it).
fn albedo_at(scene: &Scene, p: Vec3) -> Rgb {
    for t in 0..scene.mesh.triangles.len() as u32 {
        let b = scene.mesh.barycentric(t, p.as_dvec3());
        if b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)) {
            return scene.diffuse_albedo_at(t, b.map(|x| x as f32));
        }
    }
    panic!("no triangle holds {p}");
}

fn close(a: Rgb, b: Rgb) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// The sRGB decoding against published values (IEC 61966-2-1: 0 -> 0, 10 -> 0.0030353,
/// 64 -> 0.0512695, 128 -> 0.2158605, 255 -> 1), through a PNG decoded by the loader's own
/// path.
#[test]
fn srgb_values_decode_to_the_published_linear_values() {
    let bytes = png(
        5,
        1,
        &[
            0, 0, 0, 10, 10, 10, 64, 64, 64, 128, 128, 128, 255, 255, 255,
        ],
    );
    let t = crate::texture::decode(&bytes, "t".into()).expect("decodes");
    let got: Vec<f32> = t.levels[0].texels.iter().map(|c| c.x).collect();
    let expected = [0.0, 0.003_035_3, 0.051_269_5, GREY_128, 1.0];
    for (g, e) in got.iter().zip(expected) {
        assert!((g - e).abs() < 2e-6, "{got:?} vs {expected:?}");
    }
}

/// An OBJ quad over [0, 1]^2 with `vt` equal to its x and y and an MTL whose `map_Kd` names a
/// 2 x 2 PNG: each quarter shows its texel times Kd (the texel centres, where bilinear
/// filtering gives the texel itself); the image's top row is at v = 1.
#[test]
fn an_obj_reads_its_map_kd() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tex.png"), png(2, 2, &TEXELS)).unwrap();
    std::fs::write(
        dir.path().join("quad.mtl"),
        "newmtl checker\nKd 0.5 0.5 0.5\nmap_Kd -clamp on tex.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("quad.obj"),
        "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl checker\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    let (scene, warnings) = load(dir.path().join("quad.obj")).unwrap();
    assert!(
        warnings.iter().all(|w| !w.to_string().contains("map_Kd")),
        "{warnings:?}"
    );
    assert_eq!(scene.textures.len(), 1);
    assert!(scene.materials[0].albedo_texture.is_some());
    let grey = GREY_128 * 0.5;
    for (p, e) in [
        (Vec3::new(0.25, 0.75, 0.0), Rgb::new(0.5, 0.0, 0.0)),
        (Vec3::new(0.75, 0.75, 0.0), Rgb::new(0.0, 0.5, 0.0)),
        (Vec3::new(0.25, 0.25, 0.0), Rgb::new(0.0, 0.0, 0.5)),
        (Vec3::new(0.75, 0.25, 0.0), Rgb::splat(grey)),
    ] {
        let got = albedo_at(&scene, p);
        assert!(close(got, e), "at {p}: {got} vs {e}");
    }
}

/// A glTF triangle whose material's base colour texture (embedded in the `.glb`, read from
/// `TEXCOORD_1` through a nearest, clamped sampler) multiplies `baseColorFactor`; the
/// coordinates follow glTF's convention (v down: v = 0.25 is the top row).
#[test]
fn a_gltf_reads_its_base_colour_texture() {
    let mut w = GltfWriter::new();
    let m = w.material(
        "Checker",
        MaterialSpec {
            base: [0.8, 0.6, 0.4],
            ..MaterialSpec::default()
        },
    );
    w.base_colour_texture(m, &png(2, 2, &TEXELS), 1, true);
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    // Set 0 is a decoy: the texture reads set 1, which maps the triangle's corners to the
    // image's top-left, top-right and bottom-left.
    let uv0 = [[0.9, 0.9]; 3];
    let uv1 = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let mesh = w.mesh(
        "Tri",
        &positions,
        None,
        Some(&uv0),
        Some(&uv1),
        &[0, 1, 2],
        Some(m),
    );
    let node = w.node("T", Some(mesh), None, Trs::default(), vec![]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.glb");
    std::fs::write(&path, w.glb(vec![node])).unwrap();
    let (scene, warnings) = load(&path).unwrap();
    assert!(
        warnings.iter().all(|w| !w.to_string().contains("Texture")),
        "{warnings:?}"
    );
    assert_eq!(scene.textures.len(), 1);
    // (0.1, 0.1) at uv (0.1, 0.1): the top-left texel, red; (0.6, 0.1): top right, green;
    // (0.1, 0.6): bottom left, blue. Nearest filtering: no blend near the texel edges.
    for (p, e) in [
        (Vec3::new(0.1, 0.1, 0.0), Rgb::new(0.8, 0.0, 0.0)),
        (Vec3::new(0.6, 0.1, 0.0), Rgb::new(0.0, 0.6, 0.0)),
        (Vec3::new(0.1, 0.6, 0.0), Rgb::new(0.0, 0.0, 0.4)),
        (Vec3::new(0.45, 0.45, 0.0), Rgb::new(0.8, 0.0, 0.0)),
    ] {
        let got = albedo_at(&scene, p);
        assert!(close(got, e), "at {p}: {got} vs {e}");
    }
    assert!(
        Path::new(&scene.textures[0].name)
            .to_str()
            .unwrap()
            .contains("image 0")
    );
}
