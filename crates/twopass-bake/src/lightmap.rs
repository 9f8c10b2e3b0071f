//! Lightmaps: the radiosity solution as a texture over a second UV set (`TEXCOORD_1`) of the
//! scene's own triangles, the way engines and DCC tools take baked light.
//!
//! **Charts.** The UV atlas is generated here: the triangles of each object are grouped into
//! charts of edge-connected, coplanar triangles (geometric normals within
//! [`COPLANAR_COS`]), and each chart is projected orthogonally onto its plane, so a chart is an
//! isometry of the surface (no stretch: one texel is `texel_size` x `texel_size` scene units
//! everywhere). Curved surfaces (spheres, smooth OBJ meshes) get one chart per triangle. This
//! is the planar-segmentation half of what xatlas does; the curved-surface half (LSCM
//! parameterization of non-planar charts) is not done. The binding `xatlas-rs` (0.1.3, bindgen
//! 0.49, last released years ago, undocumented) was not taken: it would bring a C++ build and
//! an unmaintained wrapper for a gain only on curved meshes. The charts are packed with
//! [`etagere`] (the shelf packer WebRender uses for its texture atlases; maintained, pure Rust).
//! An OBJ's own `vt` coordinates are used instead when every triangle of the scene has them,
//! they lie in [0, 1] and no two triangles overlap in them ([`AtlasSource`]); OBJ has no second
//! UV set, so that one set is the lightmap's.
//!
//! **Texels.** Every texel whose centre lies on a triangle of its chart takes the solution's
//! radiance there ([`DiffuseRadiance::radiance`]: the element mesh's per-vertex radiosity
//! interpolated at that point of the scene triangle, divided by pi), and each triangle's
//! centroid texel is always filled, so no triangle is left without a value. Each chart has a
//! border of `padding` texels on every side; the empty texels of a chart are then dilated
//! `padding` times (each takes the mean of its filled neighbours in the same chart), so bilinear
//! filtering and mip levels at a chart's edge read the chart's own light, never a neighbour's
//! or black.
//!
//! **Encodings.** The HDR lightmap is linear radiance `L` in W/(m^2 sr) per RGB channel (EXR,
//! 32-bit float, plain `R`, `G`, `B`). The LDR lightmap a glTF loader uses is a plain
//! exposure-scaled sRGB PNG: `round(255 srgb(min(1, exposure * L)))`, the [`ColorMapping`] of
//! the per-vertex bakes, so the PNG's linear value times `1 / exposure` gives `L` up to the
//! clip.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use gltf_json as json;
use rayon::prelude::*;
use serde::Serialize;
use twopass_brdf::Rgb;
use twopass_composite::tonemap::{quantize, srgb_encode};
use twopass_composite::{Image, Rgb8Image};
use twopass_scene::{DiffuseRadiance, Scene};

use crate::colour::ColorMapping;
use crate::error::BakeError;
use crate::gltf::{Attribute, GlbBuilder};

/// Two triangles sharing an edge are in one chart when the cosine between their geometric
/// normals is at least this (about 0.8 degrees).
pub const COPLANAR_COS: f32 = 0.9999;

/// Largest lightmap side, texels: 8192 x 8192 RGB f32 is 805 MB in memory.
pub const MAX_LIGHTMAP_SIDE: u32 = 8192;

/// How to lay out and fill a lightmap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightmapSettings {
    /// Edge of one texel on the surface, scene units (finite, > 0).
    pub texel_size: f32,
    /// Border around every chart, texels, filled by dilation (at least 1; 2 keeps bilinear
    /// filtering and the first mip level inside the chart).
    pub padding: u32,
}

impl Default for LightmapSettings {
    fn default() -> Self {
        Self {
            texel_size: 1.0,
            padding: 2,
        }
    }
}

/// A baked lightmap and the user-mesh glTF that shows it.
#[derive(Debug, Clone)]
pub struct Lightmap {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Linear radiance per texel, W/(m^2 sr) per RGB channel, row-major, top row first (UV
    /// (0, 0) is the top-left corner, as glTF has it).
    pub radiance: Image,
    /// Charts in the atlas (1 when the scene's own texture coordinates are used).
    pub charts: usize,
    /// Texels whose centre lies on a triangle (the rest are padding, dilated or empty).
    pub covered_texels: usize,
    /// Where the texture coordinates come from.
    pub atlas: AtlasSource,
    /// The scene's triangles with `TEXCOORD_1` into the atlas, as a `.glb` embedding the PNG.
    pub glb: Vec<u8>,
    /// The HDR lightmap as EXR bytes.
    pub exr: Vec<u8>,
    /// The LDR lightmap as PNG bytes (exposure-scaled sRGB).
    pub png: Vec<u8>,
}

/// One chart: coplanar connected triangles of one object, projected onto their plane.
struct Chart {
    triangles: Vec<u32>,
    origin: Vec3,
    axes: [Vec3; 2],
    /// Smallest plane coordinate of the chart's corners, texels.
    min: Vec2,
    /// Size with the padding, texels.
    size: [u32; 2],
    /// Top-left corner in the atlas, texels.
    at: [u32; 2],
}

impl Chart {
    /// Atlas coordinates (texels, continuous) of a point on the chart's plane.
    fn atlas(&self, p: Vec3, texel: f32, pad: u32) -> Vec2 {
        let d = p - self.origin;
        let q = Vec2::new(d.dot(self.axes[0]), d.dot(self.axes[1])) / texel;
        q - self.min + Vec2::splat(pad as f32) + Vec2::new(self.at[0] as f32, self.at[1] as f32)
    }
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

/// Groups each object's triangles into charts of edge-connected coplanar triangles.
fn charts(scene: &Scene, texel: f32, pad: u32) -> Vec<Chart> {
    let m = &scene.mesh;
    let n = m.triangles.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, tri) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            match edges.entry((a.min(b), a.max(b))) {
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(t as u32);
                }
                std::collections::hash_map::Entry::Occupied(e) => {
                    let u = *e.get();
                    let same_object = m.triangle_object[u as usize] == m.triangle_object[t];
                    let coplanar =
                        m.geometric_normals[u as usize].dot(m.geometric_normals[t]) >= COPLANAR_COS;
                    if same_object && coplanar {
                        let (ru, rt) = (find(&mut parent, u), find(&mut parent, t as u32));
                        parent[ru.max(rt) as usize] = ru.min(rt);
                    }
                }
            }
        }
    }
    let mut index_of: HashMap<u32, usize> = HashMap::new();
    let mut out: Vec<Chart> = Vec::new();
    for t in 0..n as u32 {
        let root = find(&mut parent, t);
        let i = *index_of.entry(root).or_insert_with(|| {
            let normal = m.geometric_normals[root as usize];
            let (u, v) = normal.any_orthonormal_pair();
            out.push(Chart {
                triangles: Vec::new(),
                origin: m.corners(root)[0],
                axes: [u, v],
                min: Vec2::ZERO,
                size: [0, 0],
                at: [0, 0],
            });
            out.len() - 1
        });
        out[i].triangles.push(t);
    }
    for c in &mut out {
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for &t in &c.triangles {
            for p in m.corners(t) {
                let d = p - c.origin;
                let q = Vec2::new(d.dot(c.axes[0]), d.dot(c.axes[1])) / texel;
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
        c.min = lo;
        let extent = (hi - lo).ceil();
        c.size = [extent.x as u32 + 1 + 2 * pad, extent.y as u32 + 1 + 2 * pad];
    }
    out
}

/// Packs the charts into the smallest square (growing by 10 %) that holds them; returns the
/// atlas width and the used height.
fn pack(charts: &mut [Chart], texel: f32) -> Result<(u32, u32), BakeError> {
    let area: f64 = charts
        .iter()
        .map(|c| f64::from(c.size[0]) * f64::from(c.size[1]))
        .sum();
    let widest = charts
        .iter()
        .map(|c| c.size[0].max(c.size[1]))
        .max()
        .unwrap_or(1);
    let mut side = ((area * 1.1).sqrt().ceil() as u32).max(widest).max(4);
    // Tallest first: shelves fill with charts of like height.
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(charts[i].size[1]), i));
    loop {
        if side > MAX_LIGHTMAP_SIDE {
            return Err(BakeError::Encode {
                path: PathBuf::from("lightmap"),
                message: format!(
                    "the charts need more than {MAX_LIGHTMAP_SIDE} x {MAX_LIGHTMAP_SIDE} texels \
                     at a texel size of {texel} scene units; choose a larger texel size"
                ),
            });
        }
        let s = side as i32;
        let mut atlas = etagere::AtlasAllocator::new(etagere::size2(s, s));
        let mut placed = true;
        for &i in &order {
            let [w, h] = charts[i].size;
            match atlas.allocate(etagere::size2(w as i32, h as i32)) {
                Some(a) => charts[i].at = [a.rectangle.min.x as u32, a.rectangle.min.y as u32],
                None => {
                    placed = false;
                    break;
                }
            }
        }
        if placed {
            let height = charts
                .iter()
                .map(|c| c.at[1] + c.size[1])
                .max()
                .unwrap_or(1);
            // Multiples of 4 texels: block-compressed formats and older GPUs want them.
            return Ok((side.next_multiple_of(4), height.next_multiple_of(4)));
        }
        side = (side + side / 10).max(side + 1);
    }
}

/// Where a lightmap's texture coordinates come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AtlasSource {
    /// The scene's own texture coordinates (an OBJ's `vt`): every triangle has them, they lie
    /// in [0, 1] and no two triangles overlap.
    Scene,
    /// Generated charts, because the scene's coordinates could not serve (the reason).
    Generated(String),
}

impl AtlasSource {
    /// In words, as the manifest records it.
    pub fn describe(&self) -> String {
        match self {
            Self::Scene => "the scene's texture coordinates (OBJ vt)".to_owned(),
            Self::Generated(why) => format!("generated charts ({why})"),
        }
    }
}

/// A lightmap's layout: the atlas size, each triangle's corners in the atlas (texels, y
/// down), the rectangles filled and dilated separately, and per corner the group that keeps
/// vertices apart in the `.glb` (a chart, or a texture-coordinate index).
struct Layout {
    width: u32,
    height: u32,
    corners: Vec<[Vec2; 3]>,
    regions: Vec<Region>,
    groups: Vec<[u32; 3]>,
    source: AtlasSource,
}

/// A rectangle of the atlas with the triangles inside it.
struct Region {
    at: [u32; 2],
    size: [u32; 2],
    triangles: Vec<u32>,
}

/// The generated layout: charts packed into an atlas.
fn generated_layout(scene: &Scene, s: &LightmapSettings, why: String) -> Result<Layout, BakeError> {
    let mut charts = charts(scene, s.texel_size, s.padding);
    let (width, height) = pack(&mut charts, s.texel_size)?;
    let m = &scene.mesh;
    let mut corners = vec![[Vec2::ZERO; 3]; m.triangles.len()];
    let mut groups = vec![[0; 3]; m.triangles.len()];
    for (i, c) in charts.iter().enumerate() {
        for &t in &c.triangles {
            corners[t as usize] = m.corners(t).map(|p| c.atlas(p, s.texel_size, s.padding));
            groups[t as usize] = [i as u32; 3];
        }
    }
    let regions = charts
        .into_iter()
        .map(|c| Region {
            at: c.at,
            size: c.size,
            triangles: c.triangles,
        })
        .collect();
    Ok(Layout {
        width,
        height,
        corners,
        regions,
        groups,
        source: AtlasSource::Generated(why),
    })
}

/// The layout of the scene's own texture coordinates, or why they cannot serve. The atlas is
/// square, with as many texels as the surface area holds at `texel_size` spread over the
/// coordinates' own area; OBJ's v points up, the atlas's y down.
fn scene_layout(scene: &Scene, s: &LightmapSettings) -> Result<Layout, String> {
    let m = &scene.mesh;
    let mut uv = Vec::with_capacity(m.triangles.len());
    for (t, idx) in m.texcoord_indices.iter().enumerate() {
        let Some(idx) = idx else {
            return Err(format!(
                "object `{}` has no texture coordinates",
                scene.objects[m.triangle_object[t] as usize].name
            ));
        };
        let q = idx.map(|k| m.texcoords[k as usize]);
        if q.iter()
            .any(|p| !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y))
        {
            return Err(format!(
                "object `{}` has texture coordinates outside [0, 1]",
                scene.objects[m.triangle_object[t] as usize].name
            ));
        }
        uv.push(q);
    }
    if uv.is_empty() {
        return Err("the scene has no triangles".to_owned());
    }
    let uv_area: f64 = uv
        .iter()
        .map(|q| f64::from((q[1] - q[0]).perp_dot(q[2] - q[0]).abs()) / 2.0)
        .sum();
    if uv_area <= 0.0 {
        return Err("the texture coordinates cover no area".to_owned());
    }
    let texels = scene.total_area() / f64::from(s.texel_size).powi(2) / uv_area;
    let side = (texels.sqrt().ceil() as u32).max(4).next_multiple_of(4);
    if side > MAX_LIGHTMAP_SIDE {
        return Err(format!(
            "they would need {side} x {side} texels at this texel size"
        ));
    }
    let size = Vec2::splat(side as f32);
    let corners: Vec<[Vec2; 3]> = uv
        .iter()
        .map(|q| q.map(|p| Vec2::new(p.x, 1.0 - p.y) * size))
        .collect();
    // Overlap: no texel centre strictly inside two triangles (a shared edge is no overlap).
    let mut owner = vec![u32::MAX; (side * side) as usize];
    for (t, c) in corners.iter().enumerate() {
        let [a, b, d] = *c;
        let det = (b - a).perp_dot(d - a);
        if det.abs() <= f32::MIN_POSITIVE {
            return Err(format!(
                "object `{}` has a triangle of zero area in texture space",
                scene.objects[m.triangle_object[t] as usize].name
            ));
        }
        let lo = a.min(b).min(d).floor().max(Vec2::ZERO);
        let hi = a.max(b).max(d).ceil().min(size);
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let w1 = (p - a).perp_dot(d - a) / det;
                let w2 = (b - a).perp_dot(p - a) / det;
                if w1 > 1e-4 && w2 > 1e-4 && 1.0 - w1 - w2 > 1e-4 {
                    let i = (y * side + x) as usize;
                    if owner[i] != u32::MAX {
                        let name = |t: usize| &scene.objects[m.triangle_object[t] as usize].name;
                        return Err(format!(
                            "texture coordinates overlap (objects `{}` and `{}`)",
                            name(owner[i] as usize),
                            name(t)
                        ));
                    }
                    owner[i] = t as u32;
                }
            }
        }
    }
    let groups = m
        .texcoord_indices
        .iter()
        .map(|i| i.unwrap_or([0; 3]))
        .collect();
    Ok(Layout {
        width: side,
        height: side,
        corners,
        regions: vec![Region {
            at: [0, 0],
            size: [side, side],
            triangles: (0..m.triangles.len() as u32).collect(),
        }],
        groups,
        source: AtlasSource::Scene,
    })
}

/// One region's texels (its rectangle, row-major), which of them hold a value, and how many
/// texel centres lie on a triangle.
fn fill_region(
    region: &Region,
    layout: &Layout,
    radiance: &dyn DiffuseRadiance,
    padding: u32,
) -> (Vec<Rgb>, Vec<bool>, usize) {
    let [w, h] = region.size;
    let mut value = vec![Rgb::ZERO; (w * h) as usize];
    let mut filled = vec![false; (w * h) as usize];
    let origin = Vec2::new(region.at[0] as f32, region.at[1] as f32);
    let mut covered = 0;
    for &t in &region.triangles {
        let [a, b, c] = layout.corners[t as usize].map(|p| p - origin);
        let det = (b - a).perp_dot(c - a);
        if det.abs() <= f32::MIN_POSITIVE {
            continue;
        }
        let weights = |p: Vec2| {
            let w1 = (p - a).perp_dot(c - a) / det;
            let w2 = (b - a).perp_dot(p - a) / det;
            [1.0 - w1 - w2, w1, w2]
        };
        let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
        let hi = a.max(b).max(c).ceil().min(Vec2::new(w as f32, h as f32));
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let bary = weights(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                if bary.iter().all(|&k| k >= -1e-5) {
                    let i = (y * w + x) as usize;
                    covered += usize::from(!filled[i]);
                    value[i] = radiance.radiance(t, bary.map(|k| k.max(0.0)));
                    filled[i] = true;
                }
            }
        }
        // A sliver may cover no texel centre: its centroid's texel still gets its light.
        let centroid = ((a + b + c) / 3.0).max(Vec2::ZERO);
        let (x, y) = (
            (centroid.x as u32).min(w - 1),
            (centroid.y as u32).min(h - 1),
        );
        let i = (y * w + x) as usize;
        if !filled[i] {
            value[i] = radiance.radiance(t, [1.0 / 3.0; 3]);
            filled[i] = true;
            covered += 1;
        }
    }
    // Dilation: each pass gives every empty texel the mean of its filled 8-neighbours.
    for _ in 0..padding {
        let (before_v, before_f) = (value.clone(), filled.clone());
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if before_f[i] {
                    continue;
                }
                let (mut sum, mut n) = (Rgb::ZERO, 0u32);
                for dy in -1i32..=1 {
                    for dx in -1i32..=1 {
                        let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                        if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                            continue;
                        }
                        let j = (ny as u32 * w + nx as u32) as usize;
                        if before_f[j] {
                            sum += before_v[j];
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    value[i] = sum / n as f32;
                    filled[i] = true;
                }
            }
        }
    }
    (value, filled, covered)
}

/// The asset extras of a lightmap `.glb`: how to read its texture back as radiance.
#[derive(Serialize)]
struct LightmapExtras<'a> {
    twopass: LightmapExtrasBody<'a>,
}

#[derive(Serialize)]
struct LightmapExtrasBody<'a> {
    lightmap: &'static str,
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
}

/// The scene's camera as the lightmap `.glb` records it (`asset.extras.twopass.camera`), so
/// a viewer (the page of `twopass view`) can show the bake from the view twopass renders.
/// Positions in metres, in the `.glb`'s frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CameraRecord {
    /// Eye position, metres.
    pub position: [f32; 3],
    /// The point looked at, metres: on the viewing axis, as far along it as the centre of
    /// the scene's bounding box (the point a viewer orbits around).
    pub target: [f32; 3],
    /// Unit image-up direction.
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    pub vertical_fov_degrees: f32,
    /// The scene's image width, pixels.
    pub width: u32,
    /// The scene's image height, pixels.
    pub height: u32,
}

impl CameraRecord {
    /// The record of `scene`'s camera.
    pub fn of(scene: &Scene) -> Self {
        let c = &scene.camera;
        let m = scene.unit.metres();
        let centre = (scene.bounds.min + scene.bounds.max) * 0.5;
        let along = c.forward.dot(centre - c.position).max(f32::EPSILON);
        let metres = |p: Vec3| (p.as_dvec3() * m).as_vec3().to_array();
        Self {
            position: metres(c.position),
            target: metres(c.position + c.forward * along),
            up: c.up.to_array(),
            vertical_fov_degrees: c.fov_y.to_degrees(),
            width: c.width,
            height: c.height,
        }
    }
}

/// How the lightmap PNG encodes radiance, as recorded in the `.glb`.
pub const PNG_FORMULA: &str = "sRGB-encoded 8-bit of min(1, exposure * L), L the radiance \
     leaving the surface in W/(m^2 sr); the HDR values are in the .exr beside the .glb";

/// Bakes `solution` (anything that gives diffuse radiance on the scene's triangles) into a
/// lightmap over the scene's own triangles, and encodes it: the HDR EXR, the LDR PNG (with
/// `mapping`) and a `.glb` of the scene's triangles (not the element mesh) whose `TEXCOORD_1`
/// addresses the lightmap.
///
/// The atlas is the scene's own texture coordinates (an OBJ's `vt`) when every triangle has
/// them, they lie in [0, 1] and no two triangles overlap (then the atlas is square, sized so
/// that a texel covers `texel_size` x `texel_size` scene units on average); otherwise
/// generated charts ([`AtlasSource`] says which, and why).
///
/// The `.glb` has one mesh and node per object (named after it), `POSITION` in metres,
/// `NORMAL` (the scene's shading normals), `TEXCOORD_1` (and `TEXCOORD_0`, the same atlas:
/// glTF wants sets numbered from 0), and one material: black base colour, metallic 0,
/// roughness 1, and the PNG as `emissiveTexture` with `texCoord` 1 (emissive factor 1); its
/// `asset.extras.twopass` say how the PNG encodes radiance (`exposure`) and where the scene's
/// camera is ([`CameraRecord`]). Any
/// glTF viewer then shows the baked light as the surface's emission without relighting it;
/// engines with a lightmap slot take the same texture on UV set 1 (README, "Bakes for
/// engines"). A vertex is written once per position, shading normal (normals within
/// [`COPLANAR_COS`] count as one) and chart or texture coordinate, so UV seams and creases
/// split vertices and nothing else does.
pub fn bake_lightmap(
    radiance: &dyn DiffuseRadiance,
    scene: &Scene,
    settings: &LightmapSettings,
    mapping: ColorMapping,
) -> Result<Lightmap, BakeError> {
    let s = LightmapSettings {
        padding: settings.padding.max(1),
        ..*settings
    };
    if !(s.texel_size.is_finite() && s.texel_size > 0.0) {
        return Err(BakeError::Encode {
            path: PathBuf::from("lightmap"),
            message: format!("texel size {} must be finite and > 0", s.texel_size),
        });
    }
    let layout = match scene_layout(scene, &s) {
        Ok(layout) => layout,
        Err(why) => generated_layout(scene, &s, why)?,
    };
    let (width, height) = (layout.width, layout.height);
    let filled: Vec<(Vec<Rgb>, Vec<bool>, usize)> = layout
        .regions
        .par_iter()
        .map(|r| fill_region(r, &layout, radiance, s.padding))
        .collect();
    let mut image = Image::new(width, height);
    let mut covered_texels = 0;
    for (r, (value, mask, covered)) in layout.regions.iter().zip(&filled) {
        covered_texels += covered;
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
    let exr = twopass_composite::write::encode_exr_image(Path::new("lightmap.exr"), &image)
        .map_err(encode_err)?;
    let ldr = Rgb8Image::from_fn(width, height, |x, y| {
        let (c, _) = mapping.color(image.pixels()[(y * width + x) as usize]);
        c.to_array().map(|v| quantize(srgb_encode(v)))
    });
    let description = format!(
        "twopass lightmap: {PNG_FORMULA}; exposure {:e}",
        mapping.exposure
    );
    let png =
        twopass_composite::write::encode_png(Path::new("lightmap.png"), &ldr, Some(&description))
            .map_err(encode_err)?;
    let glb = encode_lightmap_glb(scene, &layout, &s, &png, mapping)?;
    Ok(Lightmap {
        width,
        height,
        radiance: image,
        charts: layout.regions.len(),
        covered_texels,
        atlas: layout.source,
        glb,
        exr,
        png,
    })
}

fn encode_lightmap_glb(
    scene: &Scene,
    layout: &Layout,
    s: &LightmapSettings,
    png: &[u8],
    mapping: ColorMapping,
) -> Result<Vec<u8>, BakeError> {
    let m = &scene.mesh;
    let to_metres = scene.unit.metres();
    let mut b = GlbBuilder::new();
    let texture = b.png_texture("twopass lightmap", png);
    let material = b.root.push(json::Material {
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
        let mut shared = crate::vertex::SharedVertices::default();
        let (mut positions, mut normals, mut uvs, mut indices) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for t in object.triangles.clone() {
            let tri = m.triangles[t as usize];
            let nrm = m.normal_indices[t as usize];
            for k in 0..3 {
                let normal = m.normals[nrm[k] as usize];
                let group = layout.groups[t as usize][k];
                let (v, new) = shared.get(group, tri[k], normal, positions.len() as u32);
                if new {
                    let p = m.positions[tri[k] as usize];
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
    let scene_name = scene.path.display().to_string();
    let atlas = layout.source.describe();
    let extras = LightmapExtras {
        twopass: LightmapExtrasBody {
            lightmap: PNG_FORMULA,
            texcoord: 1,
            atlas: &atlas,
            exposure: mapping.exposure,
            radiance_unit: "W/(m^2 sr)",
            texel_size: s.texel_size,
            texel_size_unit: scene.unit.symbol(),
            padding_texels: s.padding,
            position_unit: "m",
            scene_unit: scene.unit.symbol(),
            metres_per_scene_unit: to_metres,
            scene: &scene_name,
            camera: CameraRecord::of(scene),
        },
    };
    b.finish(&scene_name, &extras)
}
