//! The bake: the settings resolved for the scene, the atlas laid out, every region filled in
//! parallel, and the lightmap encoded as EXR, PNG and `.glb`.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use twopass_composite::tonemap::{quantize, srgb_encode};
use twopass_composite::{Image, Rgb8Image};
use twopass_scene::Scene;

use super::asset::encode_asset_glb;
use super::fill::{RegionTexels, TexelSource, fill_region};
use super::glb::encode_lightmap_glb;
use super::layout::{Layout, generated_layout, scene_layout};
use super::reference::Encoded;
use super::rgbm::{RGBM_FORMULA, encode_rgbm};
use super::settings::{
    Lightmap, LightmapEncoding, LightmapQuantity, LightmapSettings, Resolved, TEXELS_PER_DIAGONAL,
};
use crate::colour::ColorMapping;
use crate::error::BakeError;
use crate::fingerprint::LIGHTMAP_FINGERPRINT;

/// Bakes the light of `source` (a solution's diffuse radiance interpolated per texel, or a
/// final gather per texel: [`TexelSource`]) into a lightmap over the scene's own triangles,
/// and encodes it: the HDR EXR, the LDR PNG (with
/// `mapping`), with [`LightmapEncoding::Rgbm`] the RGBM PNG, and a `.glb` of the scene's triangles (not the element mesh) whose `TEXCOORD_1`
/// addresses the lightmap.
///
/// The atlas is the scene's own texture coordinates (an OBJ's `vt`) when every triangle has
/// them, they lie in [0, 1] and no two triangles overlap (then the atlas is square, sized so
/// that a texel covers `texel_size` x `texel_size` scene units on average); otherwise
/// generated charts ([`AtlasSource`](super::settings::AtlasSource) says which, and why).
///
/// The `.glb` has one mesh and node per object (named after it), `POSITION` in metres,
/// `NORMAL` (the scene's shading normals), `TEXCOORD_1` (and `TEXCOORD_0`, the same atlas:
/// glTF wants sets numbered from 0), and one material: black base colour, metallic 0,
/// roughness 1, and the PNG as `emissiveTexture` with `texCoord` 1 (emissive factor 1); its
/// `asset.extras.twopass` say how the PNG encodes radiance (`exposure`) and where the scene's
/// camera is ([`CameraRecord`](super::CameraRecord)), also a glTF camera node. The
/// material's `extras.lightMap` names the texture engines take (the RGBM PNG, embedded too,
/// or the emissive sRGB PNG; module `reference`). Any
/// glTF viewer then shows the baked light as the surface's emission without relighting it;
/// engines with a lightmap slot take the same texture on UV set 1 (README, "Bakes for
/// engines"). A vertex is written once per position, shading normal (normals within
/// [`COPLANAR_COS`](crate::lightmap::COPLANAR_COS) count as one) and chart or texture coordinate, so UV seams and creases
/// split vertices and nothing else does.
pub fn bake_lightmap(
    source: TexelSource<'_>,
    scene: &Scene,
    settings: &LightmapSettings,
    mapping: ColorMapping,
) -> Result<Lightmap, BakeError> {
    let s = resolve(scene, settings)?;
    let layout = lay_out(scene, &s)?;
    let (width, height) = (layout.width, layout.height);
    let filled: Vec<RegionTexels> = layout
        .regions
        .par_iter()
        .map(|r| fill_region(r, &layout, scene, source, &s))
        .collect();
    let mut image = Image::new(width, height);
    let (mut covered_texels, mut rays, mut shadow_rays) = (0, 0, 0);
    for (r, texels) in layout.regions.iter().zip(&filled) {
        let (value, mask) = (&texels.value, &texels.filled);
        covered_texels += texels.covered;
        rays += texels.rays;
        shadow_rays += texels.shadow_rays;
        let [w, h] = r.size;
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if mask[i] {
                    let j = ((r.at[1] + y) * width + r.at[0] + x) as usize;
                    image.pixels_mut()[j] = value[i];
                }
            }
        }
    }
    let encode_err = |e: twopass_composite::CompositeError| BakeError::Encode {
        path: PathBuf::from("lightmap"),
        message: e.to_string(),
    };
    let fingerprint = crate::fingerprint::lightmap_fingerprint(&image);
    let tag = [(LIGHTMAP_FINGERPRINT, format!("{fingerprint:016x}"))];
    let exr =
        twopass_composite::write::encode_exr_image_with(Path::new("lightmap.exr"), &image, &tag)
            .map_err(encode_err)?;
    let ldr = Rgb8Image::from_fn(width, height, |x, y| {
        let (c, _) = mapping.color(image.pixels()[(y * width + x) as usize]);
        c.to_array().map(|v| quantize(srgb_encode(v)))
    });
    let description = format!(
        "twopass lightmap: {}; exposure {:e}",
        s.quantity.png_formula(),
        mapping.exposure
    );
    let png =
        twopass_composite::write::encode_png(Path::new("lightmap.png"), &ldr, Some(&description))
            .map_err(encode_err)?;
    let rgbm = match s.encoding {
        LightmapEncoding::Rgbm => {
            let rgbm = encode_rgbm(&image);
            let description = format!(
                "twopass lightmap, RGBM: {RGBM_FORMULA}, multiplier {:e}; {}",
                rgbm.multiplier,
                s.quantity.name()
            );
            let png = twopass_composite::write::encode_png_rgba(
                Path::new("lightmap.rgbm.png"),
                (width, height),
                &rgbm.rgba,
                Some(&description),
            )
            .map_err(encode_err)?;
            Some((png, rgbm.multiplier))
        }
        LightmapEncoding::Srgb => None,
    };
    let encoded = Encoded {
        png: &png,
        rgbm: rgbm.as_ref().map(|(png, m)| (png.as_slice(), *m)),
        mapping,
        exr_fingerprint: fingerprint,
    };
    let glb = encode_lightmap_glb(scene, &layout, &s, &encoded)?;
    let asset = match &scene.gltf {
        Some(src) => Some(encode_asset_glb(src, scene, &layout, &s, &encoded)?),
        None => None,
    };
    Ok(Lightmap {
        width,
        height,
        texel_size: s.texel_size,
        radiance: image,
        quantity: s.quantity,
        charts: layout.charts,
        curved_objects: layout.curved_objects,
        covered_texels,
        rays,
        shadow_rays,
        atlas: layout.source,
        glb,
        asset,
        exr,
        png,
        encoding: s.encoding,
        rgbm,
    })
}

/// The atlas: the scene's own texture coordinates where they serve, else generated charts.
fn lay_out(scene: &Scene, s: &Resolved) -> Result<Layout, BakeError> {
    match scene_layout(scene, s) {
        Ok(layout) => Ok(layout),
        Err(why) => generated_layout(scene, s, why),
    }
}

/// The lightmap's atlas size (width, height, in texels) that [`bake_lightmap`] would make for
/// `scene` with `settings`, or why it cannot make one (the charts need more than
/// [`MAX_LIGHTMAP_SIDE`](super::MAX_LIGHTMAP_SIDE) texels a side): the layout depends on the
/// geometry alone, so a front end can refuse a texel size before it solves.
pub fn lightmap_atlas_size(
    scene: &Scene,
    settings: &LightmapSettings,
) -> Result<(u32, u32), BakeError> {
    let layout = lay_out(scene, &resolve(scene, settings)?)?;
    Ok((layout.width, layout.height))
}

/// `settings` with the library's defaults filled in for `scene`, checked.
fn resolve(scene: &Scene, settings: &LightmapSettings) -> Result<Resolved, BakeError> {
    let s = Resolved {
        texel_size: settings
            .texel_size
            .unwrap_or(scene.bounds.diagonal() / TEXELS_PER_DIAGONAL),
        padding: settings.padding.max(1),
        quantity: settings
            .quantity
            .unwrap_or_else(|| LightmapQuantity::for_scene(scene)),
        encoding: settings.encoding,
    };
    if !(s.texel_size.is_finite() && s.texel_size > 0.0) {
        return Err(BakeError::Encode {
            path: PathBuf::from("lightmap"),
            message: format!("texel size {} must be finite and > 0", s.texel_size),
        });
    }
    Ok(s)
}
