//! The HDR lightmap inside the `.glb` files: the RGBM PNG that the materials'
//! `extras.lightMap` names, decoded here with the `png` crate and the formula the `.glb`
//! records (value = multiplier x A x RGB, the 8-bit values over 255 read linearly), equals the
//! EXR's texels within the 8-bit RGBM bound (max(r, g, b) + multiplier / 255) / 510 per
//! channel, texels above the sRGB PNG's clip included; `--lightmap-encoding srgb` names the
//! sRGB PNG instead.

use serde_json::Value;
use twopass_bake::lightmap::{LightmapEncoding, LightmapSettings, TexelSource, bake_lightmap};
use twopass_bake::{ColorMapping, LightmapQuantity};
use twopass_composite::Image;

use crate::asset::{baked, room};
use crate::common::cornell;
use crate::validator::assert_valid;

/// The JSON chunk and the binary chunk of a `.glb`.
fn chunks(glb: &[u8]) -> (Value, &[u8]) {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    (json, &glb[20 + len + 8..])
}

/// The bytes of the image texture `index` of the document shows.
fn texture_png<'a>(doc: &Value, bin: &'a [u8], index: u64) -> &'a [u8] {
    let image = doc["textures"][index as usize]["source"].as_u64().unwrap() as usize;
    let view = &doc["bufferViews"][doc["images"][image]["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    &bin[start..start + view["byteLength"].as_u64().unwrap() as usize]
}

/// Decodes `png` with the `png` crate: (width, height, channels, bytes).
fn decode(png: &[u8]) -> (u32, u32, usize, Vec<u8>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(png))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    // RGBM is linear data: no sRGB or gamma chunk asks a reader to convert it.
    assert!(reader.info().srgb.is_none() && reader.info().gama_chunk.is_none());
    buf.truncate(info.buffer_size());
    (info.width, info.height, info.color_type.samples(), buf)
}

/// Checks the RGBM texture that `entry` (a material's `extras.lightMap`) names against the
/// lightmap's texels `exr`; returns how many texels lie above the sRGB PNG's clip.
fn check_rgbm(doc: &Value, bin: &[u8], entry: &Value, exr: &Image, exposure: f32) -> usize {
    assert_eq!(entry["encoding"], "rgbm", "{entry}");
    assert_eq!(entry["texCoord"], 1, "{entry}");
    let m = entry["multiplier"].as_f64().unwrap() as f32;
    let (w, h, channels, bytes) = decode(texture_png(doc, bin, entry["index"].as_u64().unwrap()));
    assert_eq!((w, h, channels), (exr.width(), exr.height(), 4));
    // The multiplier is the largest channel of any texel: nothing clips.
    let largest = exr
        .pixels()
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    assert_eq!(m, largest);
    let mut above_clip = 0;
    for (i, want) in exr.pixels().iter().enumerate() {
        let px = &bytes[4 * i..4 * i + 4];
        let a = f32::from(px[3]) / 255.0;
        let bound = (want.max_element() + m / 255.0) / 510.0;
        for c in 0..3 {
            let got = m * a * (f32::from(px[c]) / 255.0);
            // The bound plus the rounding of f32 arithmetic on values near m.
            assert!(
                (got - want[c]).abs() <= bound + 1e-6 * m,
                "texel {i} channel {c}: {got} vs {want} (bound {bound})"
            );
        }
        if want.max_element() * exposure > 1.0 {
            above_clip += 1;
        }
    }
    above_clip
}

#[test]
fn the_rgbm_texture_in_the_lightmap_glb_holds_the_exr_values_unclipped() {
    let (scene, solution) = cornell(100.0);
    let mapping = ColorMapping::auto(&solution);
    let settings = LightmapSettings {
        texel_size: Some(10.0),
        quantity: Some(LightmapQuantity::Radiance),
        ..LightmapSettings::default()
    };
    assert_eq!(settings.encoding, LightmapEncoding::Rgbm, "the default");
    let lm = bake_lightmap(TexelSource::Solution(&solution), &scene, &settings, mapping).unwrap();
    assert_valid("cornell-box.lightmap.glb", &lm.glb);
    let (rgbm_png, multiplier) = lm.rgbm.clone().expect("an RGBM PNG");
    let (doc, bin) = chunks(&lm.glb);
    let material = &doc["materials"][0];
    let entry = &material["extras"]["lightMap"];
    // The emissive texture stays the sRGB PNG (what any glTF viewer shows); the lightMap entry
    // names the RGBM one, the same bytes as the PNG written beside.
    let emissive = material["emissiveTexture"]["index"].as_u64().unwrap();
    assert_eq!(texture_png(&doc, bin, emissive), lm.png.as_slice());
    assert_eq!(
        texture_png(&doc, bin, entry["index"].as_u64().unwrap()),
        rgbm_png
    );
    assert_eq!(entry["multiplier"].as_f64().unwrap() as f32, multiplier);
    assert_eq!(
        entry["intensity"].as_f64().unwrap(),
        1.0,
        "radiance: {entry}"
    );
    let record = &doc["asset"]["extras"]["twopass"];
    assert_eq!(record["encoding"], "rgbm");
    assert_eq!(
        record["rgbm_multiplier"].as_f64().unwrap() as f32,
        multiplier
    );
    assert_eq!(record["texture"], entry["index"]);
    let above = check_rgbm(&doc, bin, entry, &lm.radiance, mapping.exposure);
    // The light's texels (and the brightest walls) are above the sRGB PNG's clip.
    assert!(
        above > 0,
        "no texel above the clip at exposure {}",
        mapping.exposure
    );
}

#[test]
fn the_asset_names_the_rgbm_texture_and_srgb_is_the_alternative() {
    let dir = tempfile::tempdir().unwrap();
    let (_, lm) = baked(&room(false), dir.path());
    let asset = lm.asset.as_ref().unwrap();
    let (doc, bin) = chunks(asset);
    let mut checked = 0;
    for m in doc["materials"].as_array().unwrap() {
        let entry = &m["extras"]["lightMap"];
        let pi = std::f64::consts::PI;
        assert!(
            (entry["intensity"].as_f64().unwrap() - pi).abs() < 1e-6,
            "{entry}"
        );
        assert_eq!(entry["quantity"], "irradiance");
        check_rgbm(&doc, bin, entry, &lm.radiance, 1.0);
        checked += 1;
    }
    assert_eq!(checked, 3);

    // With the sRGB encoding the entry names the sRGB PNG, with its exposure; no RGBM.
    let (scene, solution) = cornell(100.0);
    let settings = LightmapSettings {
        texel_size: Some(10.0),
        encoding: LightmapEncoding::Srgb,
        ..LightmapSettings::default()
    };
    let mapping = ColorMapping { exposure: 2.0 };
    let lm = bake_lightmap(TexelSource::Solution(&solution), &scene, &settings, mapping).unwrap();
    assert!(lm.rgbm.is_none());
    let (doc, bin) = chunks(&lm.glb);
    let entry = &doc["materials"][0]["extras"]["lightMap"];
    assert_eq!(entry["encoding"], "srgb");
    assert_eq!(entry["exposure"], 2.0);
    assert_eq!(
        entry["intensity"], 0.5,
        "radiance over the exposure: {entry}"
    );
    assert_eq!(
        texture_png(&doc, bin, entry["index"].as_u64().unwrap()),
        lm.png
    );
    assert_eq!(
        doc["asset"]["extras"]["twopass"]["rgbm_multiplier"],
        Value::Null
    );
}
