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
/// `NORMAL` (the scene's shading normals), `COLOR_0` (`mapping`, clipped for display) and the
/// HDR radiance with its parts as [`HDR_ATTRIBUTES`](crate::HDR_ATTRIBUTES) (W/(m^2 sr)), under the unlit material of
/// [`encode_glb`](crate::encode_glb). A vertex is one scene position with one shading normal
/// (normals within [`COPLANAR_COS`](crate::weld::COPLANAR_COS) count as one); its value is the mean, over the triangles that use it, of the element mesh's
/// interpolated value at that corner (equal on a smooth surface, different across a crease
/// only when the corner's triangles lie on different patches). A user vertex carries one
/// value, so light that changes inside a large triangle (a shadow on a wall of two triangles)
/// is lost: that is what the lightmap ([`bake_lightmap`](crate::bake_lightmap)) is for.
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
    for object in &scene.objects {
        let mut shared = SharedVertices::default();
        let (mut positions, mut normals, mut sums, mut counts, mut indices) = (
            Vec::new(),
            Vec::new(),
            Vec::<[Rgb; 3]>::new(),
            Vec::new(),
            Vec::new(),
        );
        // Per vertex: the first triangle corner that uses it, where a gather looks.
        let mut first: Vec<(u32, [f32; 3])> = Vec::new();
        for t in object.triangles.clone() {
            let (tri, nrm) = (m.triangles[t as usize], m.normal_indices[t as usize]);
            for k in 0..3 {
                let normal = m.normals[nrm[k] as usize];
                let (v, new) = shared.get(0, tri[k], normal, positions.len() as u32);
                if new {
                    let p = m.positions[tri[k] as usize];
                    positions.push((p.as_dvec3() * to_metres).as_vec3());
                    normals.push(normal);
                    sums.push([Rgb::ZERO; 3]);
                    counts.push(0u32);
                }
                let mut corner = [0.0; 3];
                corner[k] = 1.0;
                if new {
                    first.push((t, corner));
                }
                // A gathered vertex takes its estimate instead of the solution's mean.
                if gather.is_none() {
                    let value = parts_at(solution, &parts, t, corner);
                    for (s, x) in sums[v as usize].iter_mut().zip(value) {
                        *s += x;
                    }
                    counts[v as usize] += 1;
                }
                indices.push(v);
            }
        }
        if indices.is_empty() {
            continue;
        }
        let mean = |i: usize| -> Vec<Vec3> {
            sums.iter()
                .zip(&counts)
                .map(|(s, &n)| s[i] / n as f32)
                .collect()
        };
        let (radiance, direct, indirect) = match gather {
            None => (mean(0), mean(1), mean(2)),
            Some(g) => {
                let base = VERTEX_KEYS + n_vertices as u64;
                let e: Vec<RadianceEstimate> = first
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
        let colours = mapping.colors(&radiance, &mut clamped_vertices);
        b.vertex_radiance_mesh(
            &object.name,
            [&positions, &normals, &colours],
            [&radiance, &direct, &indirect],
            &indices,
            material,
        );
        n_vertices += positions.len();
        n_triangles += indices.len() / 3;
    }
    b.finish_vertex_radiance(scene, &mapping, clamped_vertices, (n_vertices, n_triangles))
}
