//! The per-vertex bake on the scene's own mesh: the solution sampled at the user's vertices
//! (not the element mesh's), for engines that take vertex colours on the asset they ship.

use glam::Vec3;
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_scene::Scene;

use rayon::prelude::*;
use twopass_scene::{RadianceEstimate, RadianceEstimator};

use crate::colour::{ColorMapping, RadianceParts};
use crate::error::BakeError;
use crate::gltf::{Glb, GlbBuilder, unlit_vertex_colour_material};
use crate::weld::SharedVertices;

/// One object's vertices as the per-vertex bake writes them: the user's own vertex list.
struct UserVertices {
    /// The scene vertex of each output vertex.
    scene_vertex: Vec<u32>,
    /// The shading normal of each output vertex.
    normals: Vec<Vec3>,
    /// The first triangle corner (triangle, barycentrics) that uses each output vertex, where
    /// a gather looks.
    first: Vec<(u32, [f32; 3])>,
    /// Three output vertices per triangle, in the object's triangle order.
    indices: Vec<u32>,
}

impl UserVertices {
    /// Output vertices.
    fn len(&self) -> usize {
        self.scene_vertex.len()
    }

    /// Every triangle corner of `object` as (triangle, corner, output vertex).
    fn corners<'a>(
        &'a self,
        object: &'a twopass_scene::Object,
    ) -> impl Iterator<Item = (u32, usize, u32)> + 'a {
        object
            .triangles
            .clone()
            .zip(self.indices.chunks_exact(3))
            .flat_map(|(t, v)| (0..3).map(move |k| (t, k, v[k])))
    }
}

/// The output vertices of `object` (`None` without triangles): one per user vertex where the
/// user gave no normals (a flat OBJ group or glTF primitive: the vertex's normal is the
/// area-weighted mean of its triangles' normals), else one per user vertex and shading normal
/// (normals within [`COPLANAR_COS`](crate::weld::COPLANAR_COS) count as one: where the user's
/// normals split a vertex, so does the output, as glTF wants one normal per vertex). Ordered
/// by the user's vertex index ([`Mesh::source_vertices`](twopass_scene::Mesh::source_vertices)),
/// a split vertex's copies in the order the triangles first use them.
fn user_vertices(scene: &Scene, object: &twopass_scene::Object) -> Option<UserVertices> {
    let m = &scene.mesh;
    let mut shared = SharedVertices::default();
    let (mut scene_vertex, mut normals, mut first, mut indices) =
        (Vec::new(), Vec::<Vec3>::new(), Vec::new(), Vec::new());
    for t in object.triangles.clone() {
        let (tri, nrm) = (m.triangle(t), m.normal_indices(t));
        let flat = m.is_flat(t);
        for k in 0..3 {
            let (normal, weight) = if flat {
                (m.geometric_normal(t), m.area(t))
            } else {
                (m.normal(nrm[k]), 1.0)
            };
            // A flat triangle's corners weld by position alone: one normal stands for all.
            let key_normal = if flat { Vec3::Z } else { normal };
            let (v, new) = shared.get(0, tri[k], key_normal, scene_vertex.len() as u32);
            if new {
                scene_vertex.push(tri[k]);
                normals.push(Vec3::ZERO);
                let mut corner = [0.0; 3];
                corner[k] = 1.0;
                first.push((t, corner));
            }
            normals[v as usize] += normal * weight;
            indices.push(v);
        }
    }
    if indices.is_empty() {
        return None;
    }
    // The user's order: by source index, ties (split copies) in first-use order.
    let mut order: Vec<u32> = (0..scene_vertex.len() as u32).collect();
    order.sort_by_key(|&v| (m.source_vertex(scene_vertex[v as usize]), v));
    let mut rank = vec![0u32; order.len()];
    for (new, &old) in order.iter().enumerate() {
        rank[old as usize] = new as u32;
    }
    Some(UserVertices {
        scene_vertex: order.iter().map(|&o| scene_vertex[o as usize]).collect(),
        normals: order
            .iter()
            .map(|&o| normals[o as usize].try_normalize().unwrap_or(Vec3::Z))
            .collect(),
        first: order.iter().map(|&o| first[o as usize]).collect(),
        indices: indices.iter().map(|&v| rank[v as usize]).collect(),
    })
}

/// The first key of the vertices' gather sequences: lightmap texels take the keys from 0
/// (their index in the atlas, below 2^26), vertices this and up, so the two never share a
/// sequence.
pub const VERTEX_KEYS: u64 = 1 << 40;

/// The radiance parts at barycentrics `b` of scene triangle `t`, interpolated on the element
/// mesh (zero where the triangle takes no part in the solve).
fn parts_at(solution: &Solution, parts: &RadianceParts, t: u32, b: [f32; 3]) -> [Rgb; 3] {
    let mesh = solution.mesh();
    match mesh.locate(t, b[1], b[2]) {
        None => [Rgb::ZERO; 3],
        Some((leaf, w)) => {
            let v = mesh.nodes[leaf as usize].vertices;
            let w = w.map(|x| x.clamp(0.0, 1.0));
            let sum = (w[0] + w[1] + w[2]).max(f32::MIN_POSITIVE);
            let mix = |values: &[Rgb]| {
                (values[v[0] as usize] * w[0]
                    + values[v[1] as usize] * w[1]
                    + values[v[2] as usize] * w[2])
                    / sum
            };
            [
                mix(&parts.radiance),
                mix(&parts.direct),
                mix(&parts.indirect),
            ]
        }
    }
}

/// Encodes the scene's own triangles (not the element mesh) as a glTF binary with the
/// solution sampled at their vertices: one mesh and node per object, `POSITION` in metres,
/// `NORMAL`, `COLOR_0` (`mapping`, clipped for display), the HDR radiance with its parts as
/// [`HDR_ATTRIBUTES`](crate::HDR_ATTRIBUTES) (W/(m^2 sr)) and each vertex's index in the
/// user's vertex list as [`SOURCE_INDEX`](crate::SOURCE_INDEX), under the unlit material of
/// [`encode_glb`](crate::encode_glb). The vertices are the user's own, in the user's order
/// (`user_vertices`): an object without normals of its own (an OBJ group without `vn`) has
/// exactly one vertex per user vertex it uses, so an OBJ whose groups use every `v` comes
/// back with its `v` list; where the user's normals split a vertex the output does too, and
/// the index names the vertex both copies come from. A vertex's value is the mean, over the
/// triangle corners that use it, of the element mesh's interpolated value there. A user
/// vertex carries one value, so light that changes inside a large triangle (a shadow on a
/// wall of two triangles) is lost: that is what the lightmap
/// ([`bake_lightmap`](crate::bake_lightmap)) is for.
///
/// With `gather`, each vertex's value is instead a final gather at the vertex (at the corner
/// of the first of its triangles, keyed by [`VERTEX_KEYS`] plus the vertex's index in the
/// file), so light that the element mesh blurs or misses reaches the vertex as it is there.
pub fn encode_vertex_glb(
    solution: &Solution,
    scene: &Scene,
    mapping: ColorMapping,
    gather: Option<&dyn RadianceEstimator>,
) -> Result<Glb, BakeError> {
    let m = &scene.mesh;
    let parts = RadianceParts::of(solution);
    let to_metres = scene.unit.metres();
    let mut b = GlbBuilder::new();
    let material = unlit_vertex_colour_material(&mut b);
    let (mut clamped_vertices, mut n_vertices, mut n_triangles) = (0, 0, 0);
    let parts = &parts;
    for object in &scene.objects {
        let Some(list) = user_vertices(scene, object) else {
            continue;
        };
        let sums: Vec<[Rgb; 3]> = match gather {
            Some(_) => Vec::new(),
            // A vertex's value is the mean over the corners that use it.
            None => {
                let mut sums = vec![[Rgb::ZERO; 3]; list.len()];
                let mut counts = vec![0u32; list.len()];
                for (t, k, v) in list.corners(object) {
                    let mut corner = [0.0; 3];
                    corner[k] = 1.0;
                    let value = parts_at(solution, parts, t, corner);
                    for (s, x) in sums[v as usize].iter_mut().zip(value) {
                        *s += x;
                    }
                    counts[v as usize] += 1;
                }
                for (s, &n) in sums.iter_mut().zip(&counts) {
                    *s = s.map(|x| x / n.max(1) as f32);
                }
                sums
            }
        };
        let (radiance, direct, indirect): (Vec<Vec3>, Vec<Vec3>, Vec<Vec3>) = match gather {
            None => (
                sums.iter().map(|s| s[0]).collect(),
                sums.iter().map(|s| s[1]).collect(),
                sums.iter().map(|s| s[2]).collect(),
            ),
            Some(g) => {
                let base = VERTEX_KEYS + n_vertices as u64;
                let e: Vec<RadianceEstimate> = list
                    .first
                    .par_iter()
                    .enumerate()
                    .map(|(i, &(t, b))| {
                        g.estimate(t, b, base + i as u64)
                            .tinted(scene.albedo_tint(t, b))
                    })
                    .collect();
                (
                    e.iter().map(RadianceEstimate::total).collect(),
                    e.iter().map(|e| e.direct).collect(),
                    e.iter().map(|e| e.indirect).collect(),
                )
            }
        };
        let positions: Vec<Vec3> = list
            .scene_vertex
            .iter()
            .map(|&v| (m.position(v).as_dvec3() * to_metres).as_vec3())
            .collect();
        let sources: Vec<u32> = list
            .scene_vertex
            .iter()
            .map(|&v| m.source_vertex(v))
            .collect();
        let colours = mapping.colors(&radiance, &mut clamped_vertices);
        b.vertex_radiance_mesh(
            &object.name,
            [&positions, &list.normals, &colours],
            [&radiance, &direct, &indirect],
            (&list.indices, Some(&sources)),
            material,
        );
        n_vertices += positions.len();
        n_triangles += list.indices.len() / 3;
    }
    b.finish_vertex_radiance(scene, &mapping, clamped_vertices, (n_vertices, n_triangles))
}
