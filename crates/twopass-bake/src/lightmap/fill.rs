//! The texels of one atlas region: which triangle covers each texel centre, the light there
//! (the solution's radiance, or a final gather's estimate with its indirect part denoised in
//! atlas space), then the padding filled by dilation within the chart.

use glam::Vec2;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_scene::{DiffuseRadiance, RadianceEstimate, RadianceEstimator, Scene};

use super::filter::{Guide, denoise};
use super::layout::{Layout, Region};
use super::raster::{for_each_overlapped_texel, for_each_texel};
use super::settings::{AtlasSource, LightmapQuantity, Resolved};

/// Where the texels' light comes from.
#[derive(Clone, Copy)]
pub enum TexelSource<'a> {
    /// A solution's radiance interpolated at each texel centre.
    Solution(&'a dyn DiffuseRadiance),
    /// A final gather at each texel centre ([`RadianceEstimator`]), its indirect part
    /// denoised by an edge-aware filter in atlas space.
    Gather(&'a dyn RadianceEstimator),
}

/// One region's texels (its rectangle, row-major), which of them hold a value, how many
/// texel centres lie on a triangle, and the rays a gather traced.
pub(super) struct RegionTexels {
    pub(super) value: Vec<Rgb>,
    pub(super) filled: Vec<bool>,
    pub(super) covered: usize,
    pub(super) rays: u64,
    pub(super) shadow_rays: u64,
}

/// A texel centre on a triangle: its index in the region, the triangle and the barycentrics.
#[derive(Clone, Copy)]
struct Sample {
    texel: u32,
    triangle: u32,
    barycentric: [f32; 3],
}

/// Most back-face hits among a gathered texel's gather rays (as a fraction of those that hit
/// something) for the texel to count: above it, the texel centre lies inside another object
/// (where the two intersect) and its light is meaningless, so the texel is left empty and
/// dilation gives it its valid neighbours' light, as Unity's "backface tolerance" does
/// (which by default needs 90 % front-face hits).
pub const MAX_BACK_FACES: f32 = 0.1;

/// Texel centres per rayon job of the gather: enough to amortise the job, small enough to
/// balance texels of very different cost.
const GATHER_CHUNK: usize = 64;

/// Share of a texel by which a sample outside its texel's centre is pulled from the triangle's
/// edge toward its centroid: a point exactly on an edge shared with another surface (a wall
/// meeting the floor) would start its gather rays on that surface.
const EDGE_INSET: f32 = 0.05;

/// The texels of `region` its triangles touch (conservative rasterization), each with the
/// point it is lit at. A texel whose centre lies on a triangle takes that point (the last
/// triangle drawn owns a texel centre on a shared edge). A texel a triangle only overlaps
/// (at a chart's border, or on a face thinner than a texel) takes the point of the touching
/// triangles nearest its centre, pulled [`EDGE_INSET`] texels inside: the renderer's bilinear
/// lookup reads border texels, so they hold the light at the border, not a copy of their
/// inner neighbours', and a face thinner than a texel is lit along its whole length.
fn rasterize(region: &Region, layout: &Layout) -> Vec<Sample> {
    let [w, h] = region.size;
    // Per texel: the triangle, the barycentrics, and the squared distance (texels) from the
    // centre to the point (0 for a centre on the triangle).
    let mut owner: Vec<Option<(u32, [f32; 3], f32)>> = vec![None; (w * h) as usize];
    let origin = Vec2::new(region.at[0] as f32, region.at[1] as f32);
    for &t in &region.triangles {
        let [a, b, c] = layout.corners[t as usize].map(|p| p - origin);
        for_each_texel(
            [a, b, c],
            [w, h],
            |bary| bary.iter().all(|&k| k >= -1e-5),
            |x, y, bary| {
                owner[(y * w + x) as usize] = Some((t, bary.map(|k| k.max(0.0)), 0.0));
            },
        );
    }
    for &t in &region.triangles {
        let corners = layout.corners[t as usize].map(|p| p - origin);
        for_each_overlapped_texel(corners, [w, h], |x, y| {
            let i = (y * w + x) as usize;
            if owner[i].is_some_and(|(_, _, d)| d == 0.0) {
                return;
            }
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let (point, bary) = inset_closest_point(corners, centre);
            let d = point.distance_squared(centre);
            if owner[i].is_none_or(|(_, _, best)| d < best) {
                owner[i] = Some((t, bary, d.max(f32::MIN_POSITIVE)));
            }
        });
    }
    owner
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            o.map(|(triangle, barycentric, _)| Sample {
                texel: i as u32,
                triangle,
                barycentric,
            })
        })
        .collect()
}

/// The point of triangle `[a, b, c]` nearest `p` (all in texels), moved [`EDGE_INSET`] texels
/// toward the centroid (at most half way), and its barycentrics.
fn inset_closest_point([a, b, c]: [Vec2; 3], p: Vec2) -> (Vec2, [f32; 3]) {
    let q = closest_point_on_triangle([a, b, c], p);
    let centroid = (a + b + c) / 3.0;
    let to_centroid = centroid - q;
    let length = to_centroid.length();
    let q = if length > 0.0 {
        q + to_centroid * (EDGE_INSET / length).min(0.5)
    } else {
        q
    };
    let det = (b - a).perp_dot(c - a);
    let w1 = (q - a).perp_dot(c - a) / det;
    let w2 = (b - a).perp_dot(q - a) / det;
    let bary = [1.0 - w1 - w2, w1, w2].map(|k| k.clamp(0.0, 1.0));
    let sum: f32 = bary.iter().sum();
    (q, bary.map(|k| k / sum))
}

/// The point of triangle `[a, b, c]` nearest `p` (Ericson, *Real-Time Collision Detection*,
/// 5.1.5, in the plane).
fn closest_point_on_triangle([a, b, c]: [Vec2; 3], p: Vec2) -> Vec2 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    // Inside: p itself (its barycentrics are all positive).
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Fills one region: every covered texel from `source`, then `s.padding` rings of dilation.
/// A gathered texel's random sequence is keyed by its index in the whole atlas
/// (`atlas_width`), so it does not depend on how the atlas is split into regions or parts.
pub(super) fn fill_region(
    region: &Region,
    layout: &Layout,
    scene: &Scene,
    source: TexelSource<'_>,
    s: &Resolved,
) -> RegionTexels {
    let [w, h] = region.size;
    let samples = rasterize(region, layout);
    let covered = samples.len();
    let mut value = vec![Rgb::ZERO; (w * h) as usize];
    let mut filled = vec![false; (w * h) as usize];
    let (mut rays, mut shadow_rays) = (0, 0);
    match source {
        TexelSource::Solution(radiance) => {
            let values: Vec<Rgb> = samples
                .par_iter()
                .map(|p| {
                    let l = radiance.radiance(p.triangle, p.barycentric);
                    match s.quantity {
                        LightmapQuantity::Radiance => l,
                        LightmapQuantity::Irradiance => {
                            let object = scene.mesh.object_of(p.triangle);
                            let emitted = scene.objects[object as usize].emission;
                            // The solution reflects with the texture's mean over its elements:
                            // the triangle's mean stands in for it.
                            incoming(l - emitted, scene.triangle_albedo(p.triangle))
                        }
                    }
                })
                .collect();
            for (p, v) in samples.iter().zip(values) {
                value[p.texel as usize] = v;
                filled[p.texel as usize] = true;
            }
        }
        TexelSource::Gather(estimator) => {
            let key = |texel: u32| {
                let (x, y) = (region.at[0] + texel % w, region.at[1] + texel / w);
                u64::from(y) * u64::from(layout.width) + u64::from(x)
            };
            let estimates: Vec<RadianceEstimate> = samples
                .par_iter()
                .with_min_len(GATHER_CHUNK)
                .map(|p| estimator.estimate(p.triangle, p.barycentric, key(p.texel)))
                .collect();
            rays = estimates.iter().map(|e| e.rays).sum();
            shadow_rays = estimates.iter().map(|e| e.shadow_rays).sum();
            let chart = |t: u32| match layout.source {
                AtlasSource::Generated(_) => layout.groups[t as usize][0],
                AtlasSource::Scene => scene.mesh.object_of(t),
            };
            // Texels inside another object take no part.
            let (samples, estimates): (Vec<Sample>, Vec<RadianceEstimate>) = samples
                .into_iter()
                .zip(estimates)
                .filter(|(_, e)| e.back_faces <= MAX_BACK_FACES)
                .unzip();
            let guides: Vec<Guide> = samples
                .iter()
                .zip(&estimates)
                .map(|(p, e)| Guide {
                    texel: p.texel,
                    position: scene.mesh.surface_point(p.triangle, p.barycentric).position,
                    normal: scene.mesh.front_shading_normal(p.triangle, p.barycentric),
                    chart: chart(p.triangle),
                    object: scene.mesh.object_of(p.triangle),
                    error: e.indirect_error,
                })
                .collect();
            let indirect: Vec<Rgb> = estimates.iter().map(|e| e.indirect).collect();
            let indirect = denoise(&guides, &indirect, [w, h], s.texel_size);
            for ((p, e), ind) in samples.iter().zip(&estimates).zip(indirect) {
                value[p.texel as usize] = match s.quantity {
                    LightmapQuantity::Radiance => {
                        e.emitted + (e.direct + ind) * scene.albedo_tint(p.triangle, p.barycentric)
                    }
                    LightmapQuantity::Irradiance => incoming(
                        e.direct + ind,
                        scene.material_of(p.triangle).diffuse_albedo(),
                    ),
                };
                filled[p.texel as usize] = true;
            }
        }
    }
    dilate(&mut value, &mut filled, [w, h], s.padding);
    RegionTexels {
        value,
        filled,
        covered,
        rays,
        shadow_rays,
    }
}

/// Irradiance over pi, W/(m^2 sr), from the radiance `reflected` (no emission) a surface of
/// diffuse reflectance `rho` sends: divided by it per channel, 0 where it is 0 (no reflected
/// light tells of the light that arrived), and never negative (the solution's interpolation
/// may dip below the emission on an emitter's edge). A final gather reflects with the
/// material's own reflectance (a texture's factor, not its value), so the irradiance holds no
/// texture: what an engine multiplies by its own.
fn incoming(reflected: Rgb, rho: Rgb) -> Rgb {
    let rho = rho.to_array();
    let r = reflected.to_array();
    Rgb::from_array(std::array::from_fn(|c| {
        if rho[c] > 0.0 {
            (r[c] / rho[c]).max(0.0)
        } else {
            0.0
        }
    }))
}

/// Dilation: each of `rings` passes gives every empty texel the mean of its filled
/// 8-neighbours.
fn dilate(value: &mut [Rgb], filled: &mut [bool], [w, h]: [u32; 2], rings: u32) {
    for _ in 0..rings {
        let (before_v, before_f) = (value.to_vec(), filled.to_vec());
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
}
