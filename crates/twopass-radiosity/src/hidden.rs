//! Element vertices inside other objects: a floor's vertices under a box standing on it, a
//! ceiling's behind a light fixed just below it. Their irradiance is zero (every ray from them
//! meets the inside of the object), which is right for the hidden surface and wrong for the
//! visible part of every element they share with it: interpolated toward zero, a floor would
//! darken over whole elements around each box, and a patch's light spread over its hidden part
//! would reach its neighbours diluted and partly be lost. So progressive refinement finds them
//! ([`hidden_points`]), shoots each patch's light from its visible area, and shows a hidden
//! vertex with its visible neighbours' light ([`fill_hidden`]), as a lightmap dilates its
//! texels inside objects. (The hierarchical solver's links spread their blocked share over
//! their whole receiver, so its hidden vertices are not at zero and it does not use these.)

use glam::Vec2;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_brdf::frame::Frame;
use twopass_brdf::random::{SplitMix64, hash};
use twopass_brdf::sample::square_to_cosine_hemisphere;
use twopass_scene::{Scene, SurfacePoint};

use crate::element::ElementMesh;
use crate::specular::stratum;

/// Rays per point, a 4 x 4 stratified cosine-weighted grid over its hemisphere.
pub const HIDDEN_RAYS: u32 = 16;

/// Share of a point's rays that hit something whose first hit is the back of a surface, above
/// which the point is inside an object. A point on the very edge of a contact (a floor vertex
/// where the box's side meets the floor) sends half its rays into the box and stays visible.
pub const HIDDEN_BACK_FACES: f32 = 0.75;

/// Whether each point lies inside another object ([`HIDDEN_BACK_FACES`] of its
/// [`HIDDEN_RAYS`] rays that hit something meet a back face first). The rays of the i-th
/// point are seeded by `seed` and `first + i` (its vertex index), so the answer depends on
/// neither threads nor how the points were batched.
pub fn hidden_points(scene: &Scene, points: &[SurfacePoint], first: usize, seed: u64) -> Vec<bool> {
    points
        .par_iter()
        .enumerate()
        .map(|(i, point)| hidden_at(scene, point, hash(seed ^ ((first + i) as u64) << 8)))
        .collect()
}

/// Whether `point` lies inside another object, its rays seeded by `key`.
fn hidden_at(scene: &Scene, point: &SurfacePoint, key: u64) -> bool {
    let mut rng = SplitMix64::new(hash(key ^ 0x4869_6464_656e));
    let frame = Frame::from_normal(point.normal);
    let (mut hits, mut backs) = (0u32, 0u32);
    let k = HIDDEN_RAYS.isqrt();
    for j in 0..k * k {
        let u = stratum(j, k, Vec2::new(rng.next_f32(), rng.next_f32()));
        let dir = frame.to_world(square_to_cosine_hemisphere(u));
        if let Some(hit) = scene.intersect_from(point, dir) {
            hits += 1;
            backs += u32::from(!hit.front_face);
        }
    }
    hits > 0 && backs as f32 > HIDDEN_BACK_FACES * hits as f32
}

/// [`hidden_points`] at the receiving points of `mesh`'s vertices from `from` on (where the
/// solvers measure their irradiance; progressive refinement's own test), and the rays cast.
pub fn hidden_vertices(
    scene: &Scene,
    mesh: &ElementMesh,
    from: usize,
    seed: u64,
) -> (Vec<bool>, u64) {
    let from = from.min(mesh.vertices.len());
    let points: Vec<SurfacePoint> = mesh.vertices[from..]
        .par_iter()
        .map(|v| {
            let x = crate::form_factor::receiving_point(scene, v);
            scene.mesh.surface_point_at(v.triangle, x.as_vec3())
        })
        .collect();
    let rays = u64::from(HIDDEN_RAYS) * points.len() as u64;
    (hidden_points(scene, &points, from, seed), rays)
}

/// Gives every vertex without a value (`None`) the mean of its neighbours' values along the
/// elements' edges, layer by layer outward from the vertices with values, as a lightmap's
/// dilation fills its empty texels; linear in the mesh's size. A surface with no value
/// anywhere stays without.
pub fn fill_hidden<const N: usize>(mesh: &ElementMesh, values: &mut [Option<[Rgb; N]>]) {
    let leaves: Vec<u32> = mesh.leaves().collect();
    // Each vertex's neighbours along the elements' edges (an edge is listed from both of its
    // elements: a repeated neighbour only weighs the mean).
    let mut start = vec![0u32; values.len() + 1];
    for &leaf in &leaves {
        for &v in &mesh.nodes[leaf as usize].vertices {
            start[v as usize + 1] += 2;
        }
    }
    for i in 1..start.len() {
        start[i] += start[i - 1];
    }
    let mut next = start.clone();
    let mut neighbours = vec![0u32; start[values.len()] as usize];
    for &leaf in &leaves {
        let v = mesh.nodes[leaf as usize].vertices;
        for k in 0..3 {
            let at = &mut next[v[k] as usize];
            neighbours[*at as usize] = v[(k + 1) % 3];
            neighbours[*at as usize + 1] = v[(k + 2) % 3];
            *at += 2;
        }
    }
    let around = |v: usize| &neighbours[start[v] as usize..start[v + 1] as usize];
    let mut frontier: Vec<usize> = (0..values.len())
        .filter(|&v| values[v].is_none() && around(v).iter().any(|&n| values[n as usize].is_some()))
        .collect();
    while !frontier.is_empty() {
        let filled: Vec<[Rgb; N]> = frontier
            .iter()
            .map(|&v| {
                let (mut sum, mut n) = ([Rgb::ZERO; N], 0.0f32);
                for p in around(v).iter().filter_map(|&b| values[b as usize]) {
                    for (x, y) in sum.iter_mut().zip(p) {
                        *x += y;
                    }
                    n += 1.0;
                }
                sum.map(|x| x / n)
            })
            .collect();
        for (&v, value) in frontier.iter().zip(filled) {
            values[v] = Some(value);
        }
        let mut following: Vec<usize> = frontier
            .iter()
            .flat_map(|&v| around(v).iter().map(|&n| n as usize))
            .filter(|&n| values[n].is_none())
            .collect();
        following.sort_unstable();
        following.dedup();
        frontier = following;
    }
}
