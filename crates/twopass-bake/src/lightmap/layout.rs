//! The atlas: the scene's own texture coordinates when they can serve, else charts generated
//! by [`uvunwrap`] and packed into one page, at one texel per `texel_size` scene units.

use std::collections::HashMap;
use std::path::PathBuf;

use glam::Vec2;
use twopass_scene::Scene;

use super::raster::for_each_texel;
use super::settings::{AtlasSource, Resolved};
use crate::error::BakeError;

/// Largest lightmap side, texels: 8192 x 8192 RGB f32 is 805 MB in memory.
pub const MAX_LIGHTMAP_SIDE: u32 = 8192;

/// The smallest texel edge (scene units) at which `scene`'s surface could fit in one
/// [`MAX_LIGHTMAP_SIDE`] x [`MAX_LIGHTMAP_SIDE`] atlas even if the charts filled it without a
/// gap: the square root of the total area over the atlas's texels. A smaller texel can never
/// fit (a bake can refuse it before solving); a somewhat larger one may still not, once charts
/// and their padding are packed.
pub fn smallest_texel_size(scene: &Scene) -> f32 {
    let texels = f64::from(MAX_LIGHTMAP_SIDE).powi(2);
    (scene.total_area() / texels).sqrt() as f32
}

/// Largest ratio between a triangle's share of its chart's atlas area and its share of the
/// chart's surface area that the unwrapper accepts before it splits the chart.
pub const MAX_AREA_DISTORTION: f32 = 2.0;

/// Largest angle, radians, that one texel may span on a curved object: a texel of edge h on a
/// surface of curvature radius R spans h / R, and the renderer's bilinear reconstruction of
/// the light between texel centres that far apart misses its curvature and its terminator,
/// more the wider the angle (a sphere of radius 0.28 under texels of 0.147 units, 0.53 rad,
/// showed 3.7 % too bright; under texels of 0.037, 0.13 rad, 0.8 %). An object whose surface
/// curves more tightly gets finer texels ([`curvature_scale`]).
pub const MAX_TEXEL_ANGLE: f32 = 0.125;

/// Most a curved object's texel edge is divided by ([`MAX_TEXEL_ANGLE`]): 16 times the texels
/// of its area at the bake's texel size, so a scene of many tiny spheres cannot blow up the
/// atlas.
pub const MAX_CURVATURE_SCALE: f32 = 4.0;

/// Largest angle between the normals of two triangles sharing an edge, radians, for the edge
/// to count as part of a smooth curved surface rather than a crease (a box's edge, 90
/// degrees), which the charts split at and which no texel density resolves.
const CREASE_ANGLE: f32 = std::f32::consts::FRAC_PI_4;

/// The factor by which an object's texels are made finer than `texel_size` so that one spans
/// at most [`MAX_TEXEL_ANGLE`] of its surface's curvature (at least 1, at most
/// [`MAX_CURVATURE_SCALE`]), from the triangles `indices` over `positions` (scene units).
///
/// The curvature radius is the area-weighted median over the object's edges shared by two
/// triangles of the centroid distance over the angle between their normals (a sphere's
/// radius, a cylinder's); flat edges count as infinitely far from curving and creases (more
/// than 45 degrees between the normals) do not count. A mostly flat object, a box or a wall,
/// keeps the bake's texel size.
pub fn curvature_scale(positions: &[[f32; 3]], indices: &[u32], texel_size: f32) -> f32 {
    let Some(radius) = curvature_radius(positions, indices) else {
        return 1.0;
    };
    let scale = texel_size / (MAX_TEXEL_ANGLE * radius);
    if scale.is_finite() {
        scale.clamp(1.0, MAX_CURVATURE_SCALE)
    } else {
        1.0
    }
}

/// The area-weighted median curvature radius of [`curvature_scale`], scene units; `None` for a
/// mostly flat object (or one without shared edges).
fn curvature_radius(positions: &[[f32; 3]], indices: &[u32]) -> Option<f32> {
    use glam::Vec3;
    let triangle = |t: usize| -> (Vec3, Vec3, f32) {
        let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(positions[indices[3 * t + k] as usize]));
        let cross = (b - a).cross(c - a);
        (
            cross.normalize_or_zero(),
            (a + b + c) / 3.0,
            cross.length() / 2.0,
        )
    };
    let mut first: HashMap<(u32, u32), usize> = HashMap::new();
    // (radius, weight) per shared smooth edge; infinity for a flat one.
    let mut edges: Vec<(f32, f32)> = Vec::new();
    for t in 0..indices.len() / 3 {
        for k in 0..3 {
            let (u, v) = (indices[3 * t + k], indices[3 * t + (k + 1) % 3]);
            let Some(other) = first.insert((u.min(v), u.max(v)), t) else {
                continue;
            };
            let ((na, ca, aa), (nb, cb, ab)) = (triangle(t), triangle(other));
            if na == Vec3::ZERO || nb == Vec3::ZERO {
                continue;
            }
            // Not the arc cosine of the dot product, which loses the small angles of a
            // finely tessellated surface to rounding.
            let angle = na.cross(nb).length().atan2(na.dot(nb));
            if angle > CREASE_ANGLE {
                continue;
            }
            let radius = if angle > 1e-4 {
                ca.distance(cb) / angle
            } else {
                f32::INFINITY
            };
            edges.push((radius, aa + ab));
        }
    }
    edges.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f32 = edges.iter().map(|e| e.1).sum();
    let mut seen = 0.0;
    for &(radius, weight) in &edges {
        seen += weight;
        if seen >= total / 2.0 {
            return (radius.is_finite() && radius > 0.0).then_some(radius);
        }
    }
    None
}

/// A lightmap's layout: the atlas size, each triangle's corners in the atlas (texels, y
/// down), the rectangles filled and dilated separately, and per corner the group that keeps
/// vertices apart in the `.glb` (a chart, or a texture-coordinate index).
pub(super) struct Layout {
    /// Charts in the atlas (one for the scene's own coordinates).
    pub(super) charts: usize,
    /// Objects given finer texels for their curvature ([`curvature_scale`] above 1).
    pub(super) curved_objects: usize,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) corners: Vec<[Vec2; 3]>,
    pub(super) regions: Vec<Region>,
    pub(super) groups: Vec<[u32; 3]>,
    pub(super) source: AtlasSource,
}

/// A rectangle of the atlas with the triangles inside it.
pub(super) struct Region {
    pub(super) at: [u32; 2],
    pub(super) size: [u32; 2],
    pub(super) triangles: Vec<u32>,
}

/// One object as the unwrapper takes it: its own vertex list and indices, and the scene
/// triangle behind each of its triangles.
struct ObjectMesh {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    triangles: Vec<u32>,
}

/// The generated layout: every object unwrapped into charts and all packed into one atlas
/// page by [`uvunwrap`]; one region, since the charts lie `2 padding` texels apart.
pub(super) fn generated_layout(
    scene: &Scene,
    s: &Resolved,
    why: String,
) -> Result<Layout, BakeError> {
    let m = &scene.mesh;
    let too_big = |detail: String| BakeError::Encode {
        path: PathBuf::from("lightmap"),
        message: detail,
    };
    // One input mesh per object, its triangles in scene order.
    let inputs: Vec<ObjectMesh> = scene
        .objects
        .iter()
        .map(|o| {
            let mut index = HashMap::new();
            let (mut positions, mut indices, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
            for t in o.triangles.clone() {
                triangles.push(t);
                for v in m.triangle(t) {
                    let k = *index.entry(v).or_insert_with(|| {
                        positions.push(m.position(v).to_array());
                        positions.len() as u32 - 1
                    });
                    indices.push(k);
                }
            }
            ObjectMesh {
                positions,
                indices,
                triangles,
            }
        })
        .collect();
    let scales: Vec<f32> = inputs
        .iter()
        .map(|o| curvature_scale(&o.positions, &o.indices, s.texel_size))
        .collect();
    let meshes: Vec<uvunwrap::MeshInput<'_>> = inputs
        .iter()
        .zip(&scales)
        .map(|(o, &scale)| uvunwrap::MeshInput {
            scale,
            ..uvunwrap::MeshInput::new(&o.positions, &o.indices)
        })
        .collect();
    let options = uvunwrap::Options {
        density: uvunwrap::Density::Fixed {
            texels_per_unit: 1.0 / s.texel_size,
            page_size: None,
        },
        padding: s.padding,
        max_area_distortion: MAX_AREA_DISTORTION,
        ..uvunwrap::Options::default()
    };
    let atlas = uvunwrap::generate(&meshes, &options)
        .map_err(|e| too_big(format!("the UV unwrap failed: {e}")))?;
    if atlas.page_count > 1 || atlas.width > MAX_LIGHTMAP_SIDE || atlas.height > MAX_LIGHTMAP_SIDE {
        return Err(too_big(format!(
            "the charts need more than {MAX_LIGHTMAP_SIDE} x {MAX_LIGHTMAP_SIDE} texels at a \
             texel size of {} scene units; choose a larger texel size",
            s.texel_size
        )));
    }
    let (width, height) = (atlas.width.max(1), atlas.height.max(1));
    let size = Vec2::new(width as f32, height as f32);
    let mut corners = vec![[Vec2::ZERO; 3]; m.triangle_count()];
    let mut groups = vec![[0; 3]; m.triangle_count()];
    let mut chart_ids: HashMap<(usize, u32), u32> = HashMap::new();
    let mut all = Vec::with_capacity(m.triangle_count());
    for (o, (out, input)) in atlas.meshes.iter().zip(&inputs).enumerate() {
        for (k, &t) in input.triangles.iter().enumerate() {
            let vs: [&uvunwrap::OutputVertex; 3] =
                std::array::from_fn(|c| &out.vertices[out.indices[3 * k + c] as usize]);
            corners[t as usize] = vs.map(|v| Vec2::from(v.uv) * size);
            groups[t as usize] = vs.map(|v| {
                let next = chart_ids.len() as u32;
                *chart_ids
                    .entry((o, v.chart.unwrap_or(u32::MAX)))
                    .or_insert(next)
            });
            all.push(t);
        }
    }
    Ok(Layout {
        charts: chart_ids.len(),
        curved_objects: scales.iter().filter(|&&k| k > 1.0).count(),
        width,
        height,
        corners,
        regions: vec![Region {
            at: [0, 0],
            size: [width, height],
            triangles: all,
        }],
        groups,
        source: AtlasSource::Generated(why),
    })
}

/// The layout of the scene's own texture coordinates, or why they cannot serve. The atlas is
/// square, with as many texels as the surface area holds at `texel_size` spread over the
/// coordinates' own area; OBJ's v points up, the atlas's y down.
pub(super) fn scene_layout(scene: &Scene, s: &Resolved) -> Result<Layout, String> {
    let m = &scene.mesh;
    let mut uv = Vec::with_capacity(m.triangle_count());
    for (t, idx) in (0..m.triangle_count() as u32)
        .map(|t| m.texcoord_indices(t))
        .enumerate()
    {
        let Some(idx) = idx else {
            return Err(format!(
                "object `{}` has no texture coordinates",
                scene.objects[m.object_of(t as u32) as usize].name
            ));
        };
        let q = idx.map(|k| m.texcoord(k));
        if q.iter()
            .any(|p| !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y))
        {
            return Err(format!(
                "object `{}` has texture coordinates outside [0, 1]",
                scene.objects[m.object_of(t as u32) as usize].name
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
                scene.objects[m.object_of(t as u32) as usize].name
            ));
        }
        let mut overlap = None;
        for_each_texel(
            [a, b, d],
            [side, side],
            |[w0, w1, w2]| w1 > 1e-4 && w2 > 1e-4 && w0 > 1e-4,
            |x, y, _| {
                let i = (y * side + x) as usize;
                if owner[i] != u32::MAX {
                    overlap.get_or_insert(owner[i]);
                }
                owner[i] = t as u32;
            },
        );
        if let Some(other) = overlap {
            let name = |t: usize| &scene.objects[m.object_of(t as u32) as usize].name;
            return Err(format!(
                "texture coordinates overlap (objects `{}` and `{}`)",
                name(other as usize),
                name(t)
            ));
        }
    }
    let groups = (0..m.triangle_count() as u32)
        .map(|t| m.texcoord_indices(t).unwrap_or([0; 3]))
        .collect();
    Ok(Layout {
        charts: 1,
        curved_objects: 0,
        width: side,
        height: side,
        corners,
        regions: vec![Region {
            at: [0, 0],
            size: [side, side],
            triangles: (0..m.triangle_count() as u32).collect(),
        }],
        groups,
        source: AtlasSource::Scene,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use twopass_scene::shape::{self, ShapeMesh};

    fn lists(mesh: &ShapeMesh) -> (Vec<[f32; 3]>, Vec<u32>) {
        (
            mesh.positions.iter().map(|p| p.to_array()).collect(),
            mesh.triangles.iter().flatten().copied().collect(),
        )
    }

    #[test]
    fn a_sphere_gets_texels_that_span_at_most_the_texel_angle() {
        for (r, level) in [(2.0f32, 1), (0.3, 3), (50.0, 5)] {
            let (p, i) = lists(&shape::sphere(Vec3::splat(1.0), r, level).unwrap());
            let radius = curvature_radius(&p, &i).expect("a sphere curves");
            // An icosphere's faces are not all alike, and the median falls on one kind of
            // edge: a few percent off (measured -3.1 % to +3.2 % over levels 1 to 5), which
            // moves the texel's angle by as much.
            assert!(
                (radius / r - 1.0).abs() < 0.05,
                "{radius} for a radius of {r}"
            );
            // The scale makes one texel span MAX_TEXEL_ANGLE of the sphere.
            let texel = 0.07;
            let k = curvature_scale(&p, &i, texel);
            let expected = (texel / (MAX_TEXEL_ANGLE * radius)).clamp(1.0, MAX_CURVATURE_SCALE);
            assert!((k - expected).abs() < 1e-5, "{k} against {expected}");
            assert!(texel / k / r <= MAX_TEXEL_ANGLE * 1.02 || k == MAX_CURVATURE_SCALE);
        }
        // A sphere far smaller than a texel is capped.
        let (p, i) = lists(&shape::sphere(Vec3::ZERO, 1e-3, 3).unwrap());
        assert_eq!(curvature_scale(&p, &i, 0.07), MAX_CURVATURE_SCALE);
    }

    #[test]
    fn flat_objects_and_creases_keep_the_texel_size() {
        let quad = shape::quad(Vec3::ZERO, Vec3::X, Vec3::Z).unwrap();
        let cuboid = shape::cuboid(Vec3::ZERO, Vec3::splat(0.01)).unwrap();
        for mesh in [quad, cuboid] {
            let (p, i) = lists(&mesh);
            assert_eq!(curvature_radius(&p, &i), None);
            assert_eq!(curvature_scale(&p, &i, 0.07), 1.0);
        }
    }
}
