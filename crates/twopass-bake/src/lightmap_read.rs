//! Reading a lightmap bake back as diffuse light for the tracer: the `.lightmap.glb` of
//! [`bake_lightmap`](crate::bake_lightmap) gives each scene triangle's corners on `TEXCOORD_1`,
//! the HDR lightmap beside it (`<stem>.lightmap.exr`, plain `R`, `G`, `B`, radiance in
//! W/(m^2 sr)) gives the texels, and [`LightmapRadiance`] answers
//! [`DiffuseRadiance::radiance`] with the lightmap bilinearly sampled at the hit's
//! `TEXCOORD_1`, the way a GPU samples a lightmap (texel centres at half-integers, clamped at
//! the atlas's edge).
//!
//! The HDR EXR is read, not the PNG embedded in the `.glb`: the PNG is 8-bit sRGB of
//! `min(1, exposure * L)`, which clips the light source and quantizes the dark corners, so it
//! cannot reproduce the radiance a renderer needs. The EXR's header is read first: its size must
//! be the embedded PNG's and its fingerprint ([`lightmap_fingerprint`]) the one the `.glb`
//! records, so an EXR from another bake is refused before a pixel is decoded.

use std::path::{Path, PathBuf};

use glam::Vec2;
use twopass_brdf::Rgb;
use twopass_composite::Image;
use twopass_scene::{DiffuseRadiance, Scene};

use crate::error::{BakeError, BakeProblem};
use crate::fingerprint::{LIGHTMAP_FINGERPRINT, lightmap_fingerprint};

/// Diffuse radiance read from a lightmap bake: the lightmap sampled at each scene triangle's
/// `TEXCOORD_1`.
#[derive(Debug, Clone)]
pub struct LightmapRadiance {
    /// Per scene triangle, its corners in the atlas, texels (x right, y down, continuous).
    corners: Vec<[Vec2; 3]>,
    /// The HDR lightmap, W/(m^2 sr) per RGB channel.
    image: Image,
    /// The EXR the texels came from.
    exr: PathBuf,
    /// For an irradiance lightmap (texels E / pi), each scene triangle's diffuse albedo and
    /// emitted radiance, so that the radiance is albedo x texel + emission; `None` for a
    /// radiance lightmap.
    reflect: Option<Vec<(Rgb, Rgb)>>,
    /// For an irradiance lightmap of a textured scene, the base colour textures that multiply
    /// the albedo per point (as an engine multiplies the lightmap by its own textures), and
    /// per scene triangle its texture, sampler and texture coordinates; empty otherwise.
    textures: Vec<twopass_scene::texture::Texture>,
    tints: Vec<Option<(twopass_scene::texture::AlbedoTexture, [Vec2; 3])>>,
}

impl LightmapRadiance {
    /// The HDR lightmap, W/(m^2 sr) per RGB channel.
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// The EXR the texels were read from (`<stem>.lightmap.exr` beside the `.glb`).
    pub fn exr_path(&self) -> &Path {
        &self.exr
    }

    /// Bilinear sample at continuous texel coordinates `p` (texel centres at `i + 0.5`),
    /// clamped to the atlas's edge.
    fn sample(&self, p: Vec2) -> Rgb {
        let (w, h) = (self.image.width(), self.image.height());
        let q = p - Vec2::splat(0.5);
        let x0 = q.x.floor();
        let y0 = q.y.floor();
        let (fx, fy) = (q.x - x0, q.y - y0);
        let clamp = |v: f32, n: u32| (v.max(0.0) as u32).min(n - 1);
        let (xa, xb) = (clamp(x0, w), clamp(x0 + 1.0, w));
        let (ya, yb) = (clamp(y0, h), clamp(y0 + 1.0, h));
        let g = |x, y| self.image.get(x, y);
        let top = g(xa, ya) * (1.0 - fx) + g(xb, ya) * fx;
        let bottom = g(xa, yb) * (1.0 - fx) + g(xb, yb) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

impl DiffuseRadiance for LightmapRadiance {
    /// The lightmap bilinearly sampled at the point's `TEXCOORD_1`, W/(m^2 sr) (an irradiance
    /// lightmap's E / pi times the albedo, its base colour texture's value at the point
    /// included, plus the emission).
    fn radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb {
        let Some(c) = self.corners.get(triangle as usize) else {
            return Rgb::ZERO;
        };
        let p = c[0] * barycentric[0] + c[1] * barycentric[1] + c[2] * barycentric[2];
        if !p.is_finite() {
            return Rgb::ZERO;
        }
        let texel = self.sample(p);
        match self.reflect.as_ref().and_then(|r| r.get(triangle as usize)) {
            Some(&(albedo, emitted)) => {
                let tint = match self.tints.get(triangle as usize) {
                    Some(Some((a, uv))) => self.textures[a.texture as usize].sample(
                        a,
                        uv[0] * barycentric[0] + uv[1] * barycentric[1] + uv[2] * barycentric[2],
                    ),
                    _ => Rgb::ONE,
                };
                albedo * tint * texel + emitted
            }
            None => texel,
        }
    }

    /// Zero: a lightmap holds the total radiance only, not its indirect part, so renderers that
    /// add direct light per pixel (hybrid-direct) must not use one; the CLI refuses that.
    fn indirect_radiance(&self, _triangle: u32, _barycentric: [f32; 3]) -> Rgb {
        Rgb::ZERO
    }
}

/// Refuses the accessors of `prim` that the gltf crate's readers assume well formed without
/// its validation checking them, and panic on otherwise: indices that are not unsigned
/// integers, texture coordinates that are not floats or normalized integers, a stride shorter
/// than an element, sparse storage (the bake never writes it) or none at all. A missing
/// accessor is left to the reader, which says so.
fn check_accessors(prim: &::gltf::Primitive<'_>) -> Result<(), String> {
    use ::gltf::Semantic;
    use ::gltf::accessor::{DataType, Dimensions};
    let wanted: [(&str, Option<::gltf::Accessor<'_>>, Dimensions, &[DataType]); 3] = [
        (
            "POSITION",
            prim.get(&Semantic::Positions),
            Dimensions::Vec3,
            &[DataType::F32],
        ),
        (
            "TEXCOORD_1",
            prim.get(&Semantic::TexCoords(1)),
            Dimensions::Vec2,
            &[DataType::F32, DataType::U8, DataType::U16],
        ),
        (
            "indices",
            prim.indices(),
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
        ),
    ];
    for (name, accessor, dimensions, types) in wanted {
        let Some(a) = accessor else { continue };
        let short_stride = a
            .view()
            .and_then(|v| v.stride())
            .is_some_and(|s| s < a.size());
        if a.dimensions() != dimensions
            || !types.contains(&a.data_type())
            || a.sparse().is_some()
            || a.view().is_none()
            || short_stride
        {
            return Err(format!(
                "its {name} accessor {} is {:?} of {:?}{}, not what a lightmap .glb holds: bake \
                 again",
                a.index(),
                a.dimensions(),
                a.data_type(),
                if a.sparse().is_some() { ", sparse" } else { "" }
            ));
        }
    }
    Ok(())
}

/// The HDR lightmap that belongs to a lightmap `.glb`: `x.lightmap.glb` -> `x.lightmap.exr`.
pub fn lightmap_exr_path(glb: &Path) -> PathBuf {
    glb.with_extension("exr")
}

/// Reads a lightmap bake for `scene`: the `.glb` at `glb` (written by
/// [`bake_lightmap`](crate::bake_lightmap) for this scene) and the HDR EXR beside it
/// ([`lightmap_exr_path`]).
///
/// The `.glb` must hold one mesh per scene object with triangles, in the scene's order and
/// named after it, with the object's triangles in order and every corner (metres) within
/// 1e-4 of the scene's bounding-box diagonal of the scene's own corner (converted from its
/// unit); otherwise it was baked for another scene and is refused. Emission and reflectance
/// are not recorded in the `.glb`, so a lightmap of the same geometry lit differently is not
/// detected (the `.bake` file's fingerprints do that). Errors name the file and the problem; nothing
/// panics on a damaged file.
pub fn read_lightmap_glb(glb: &Path, scene: &Scene) -> Result<LightmapRadiance, BakeError> {
    let invalid = |path: &Path, message: String| BakeError::Invalid {
        path: path.to_owned(),
        problem: BakeProblem::Lightmap(message),
    };
    let bytes = twopass_scene::read_bounded(glb, crate::format::MAX_BAKE_BYTES)
        .map_err(|e| BakeError::io(glb, e))?;
    let gltf = ::gltf::Gltf::from_slice(&bytes)
        .map_err(|e| invalid(glb, format!("not a glTF binary: {e}")))?;
    let blob = gltf.blob.as_deref();
    let doc = &gltf.document;
    let m = &scene.mesh;
    let to_metres = scene.unit.metres();
    let size = {
        let b = &scene.bounds;
        (b.max - b.min).length() as f64 * to_metres
    };
    let tolerance = (1e-4 * size).max(1e-6) as f32;
    // The atlas's size, from the embedded lightmap PNG's header.
    // The image's JSON, not `Image::source`, which panics on a buffer view without a
    // mimeType (`twopass_scene::gltf_image_problem`).
    let png = match doc.as_json().images.first() {
        Some(image) => {
            if let Some(problem) = twopass_scene::gltf_image_problem(image) {
                return Err(invalid(glb, format!("its lightmap image {problem}")));
            }
            image
                .buffer_view
                .and_then(|v| doc.views().nth(v.value()))
                .and_then(|view| {
                    let start = view.offset();
                    blob.and_then(|b| b.get(start..start.checked_add(view.length())?))
                })
        }
        None => None,
    }
    .ok_or_else(|| invalid(glb, "no embedded lightmap image".to_owned()))?;
    let (width, height) = png_size(png)
        .ok_or_else(|| invalid(glb, "the embedded lightmap image is not a PNG".to_owned()))?;
    let mut meshes = doc.meshes();
    let mut corners = vec![[Vec2::ZERO; 3]; m.triangle_count()];
    let atlas = Vec2::new(width as f32, height as f32);
    for object in scene.objects.iter().filter(|o| !o.triangles.is_empty()) {
        let mesh = meshes.next().ok_or_else(|| {
            invalid(
                glb,
                format!(
                    "no mesh for object `{}`: baked for another scene; bake again",
                    object.name
                ),
            )
        })?;
        if mesh.name() != Some(object.name.as_str()) {
            return Err(invalid(
                glb,
                format!(
                    "mesh `{}` where the scene has object `{}`: baked for another scene; bake again",
                    mesh.name().unwrap_or("(unnamed)"),
                    object.name
                ),
            ));
        }
        let prim = mesh
            .primitives()
            .next()
            .ok_or_else(|| invalid(glb, format!("mesh `{}` has no primitive", object.name)))?;
        check_accessors(&prim).map_err(|p| invalid(glb, format!("mesh `{}`: {p}", object.name)))?;
        let reader = prim.reader(|buffer| match buffer.source() {
            ::gltf::buffer::Source::Bin => blob,
            ::gltf::buffer::Source::Uri(_) => None,
        });
        let what = |attr: &str| invalid(glb, format!("mesh `{}` has no {attr}", object.name));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| what("POSITION"))?
            .collect();
        let uvs: Vec<[f32; 2]> = reader
            .read_tex_coords(1)
            .ok_or_else(|| what("TEXCOORD_1 (not a lightmap .glb)"))?
            .into_f32()
            .collect();
        let indices: Vec<u32> = reader
            .read_indices()
            .ok_or_else(|| what("indices"))?
            .into_u32()
            .collect();
        let expected = object.triangles.len() * 3;
        if indices.len() != expected || uvs.len() != positions.len() {
            return Err(invalid(
                glb,
                format!(
                    "mesh `{}` has {} indices, {} positions and {} TEXCOORD_1, the scene's object \
                     {} triangles: baked for another scene; bake again",
                    object.name,
                    indices.len(),
                    positions.len(),
                    uvs.len(),
                    object.triangles.len()
                ),
            ));
        }
        for (k, t) in object.triangles.clone().enumerate() {
            let tri = m.triangle(t);
            for c in 0..3 {
                let v = indices[3 * k + c] as usize;
                let (Some(p), Some(uv)) = (positions.get(v), uvs.get(v)) else {
                    return Err(invalid(
                        glb,
                        format!("mesh `{}`: index {v} out of range", object.name),
                    ));
                };
                let want = (m.position(tri[c]).as_dvec3() * to_metres).as_vec3();
                let off = (glam::Vec3::from_array(*p) - want).abs().max_element();
                if off.is_nan() || off > tolerance {
                    return Err(invalid(
                        glb,
                        format!(
                            "mesh `{}` triangle {k}: a corner is {off:e} m from the scene's: \
                             baked for another scene (or a changed one); bake again",
                            object.name
                        ),
                    ));
                }
                let uv = Vec2::from_array(*uv);
                if !uv.is_finite() {
                    return Err(invalid(
                        glb,
                        format!("mesh `{}`: a non-finite TEXCOORD_1", object.name),
                    ));
                }
                corners[t as usize][c] = uv * atlas;
            }
        }
    }
    let exr = lightmap_exr_path(glb);
    let of_glb = |e: twopass_composite::CompositeError| {
        invalid(&exr, format!("the HDR lightmap of {}: {e}", glb.display()))
    };
    // The header first: its size against the `.glb`'s atlas and its fingerprint against the
    // `.glb`'s, before a pixel is decoded (a ZIP EXR of a few megabytes can declare a
    // 20,000 x 20,000 image that takes gigabytes to decode).
    let header = twopass_composite::write::read_exr_header(&exr).map_err(of_glb)?;
    if header.sizes != [(u64::from(width), u64::from(height))] {
        let sizes: Vec<String> = header
            .sizes
            .iter()
            .map(|(w, h)| format!("{w} x {h}"))
            .collect();
        return Err(invalid(
            &exr,
            format!(
                "{} texels, the lightmap in {} has {width} x {height}: from another bake; \
                 bake again",
                sizes.join(" and "),
                glb.display()
            ),
        ));
    }
    let recorded = glb_record(&gltf, "exr_fingerprint");
    let found = header.text.get(LIGHTMAP_FINGERPRINT).cloned();
    if recorded != found {
        return Err(invalid(
            &exr,
            format!(
                "lightmap fingerprint {}, but {} records {}: the EXR of another bake; bake again",
                found.as_deref().unwrap_or("(none)"),
                glb.display(),
                recorded.as_deref().unwrap_or("(none)")
            ),
        ));
    }
    let image = twopass_composite::write::read_exr(&exr).map_err(of_glb)?;
    if let Some(recorded) = &recorded
        && format!("{:016x}", lightmap_fingerprint(&image)) != *recorded
    {
        return Err(invalid(
            &exr,
            format!(
                "the texels do not match the fingerprint {recorded} it and {} record: \
                 changed after the bake; bake again",
                glb.display()
            ),
        ));
    }
    if (image.width(), image.height()) != (width, height) {
        return Err(invalid(
            &exr,
            format!(
                "{} x {} texels, the lightmap in {} has {width} x {height}: from another bake; \
                 bake again",
                image.width(),
                image.height(),
                glb.display()
            ),
        ));
    }
    image
        .check_finite("lightmap")
        .map_err(|e| invalid(&exr, e.to_string()))?;
    let reflect = (glb_record(&gltf, "quantity").as_deref() == Some("irradiance")).then(|| {
        (0..m.triangle_count() as u32)
            .map(|t| {
                let o = &scene.objects[m.object_of(t) as usize];
                (scene.material_of(t).diffuse_albedo(), o.emission)
            })
            .collect()
    });
    let (textures, tints) = if reflect.is_some() && scene.has_textures() {
        let tints = (0..m.triangle_count() as u32)
            .map(|t| scene.albedo_texture_of(t).map(|(_, a, uv)| (*a, uv)))
            .collect();
        (scene.textures.clone(), tints)
    } else {
        (Vec::new(), Vec::new())
    };
    Ok(LightmapRadiance {
        corners,
        image,
        exr,
        reflect,
        textures,
        tints,
    })
}

/// The text a lightmap `.glb` records under `asset.extras.twopass.<key>`, if any: `exr_fingerprint`
/// (its EXR's fingerprint; bakes before it was recorded have none) or `quantity` (`radiance` or
/// `irradiance`; bakes before it was recorded hold radiance).
fn glb_record(gltf: &::gltf::Gltf, key: &str) -> Option<String> {
    let raw = gltf.document.as_json().asset.extras.as_ref()?;
    let value: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    value["twopass"][key].as_str().map(str::to_owned)
}

/// Width and height from a PNG's header (`IHDR`, the first chunk), or `None`.
fn png_size(png: &[u8]) -> Option<(u32, u32)> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    if png.get(..8)? != SIGNATURE || png.get(12..16)? != b"IHDR" {
        return None;
    }
    let be = |r: std::ops::Range<usize>| Some(u32::from_be_bytes(png.get(r)?.try_into().ok()?));
    let (w, h) = (be(16..20)?, be(20..24)?);
    (w > 0 && h > 0).then_some((w, h))
}
