//! A solution whose element-vertex values come from a final gather: what the element-mesh
//! outputs (`.glb`, `.ply`, `.bake`) hold when a bake gathers them.
//!
//! The renderer interpolates those values linearly over each element, so a vertex's value is
//! the gathered light averaged over the elements around it, weighted by the vertex's hat
//! function (1 at the vertex, falling linearly to 0 at the ring's far edges), not the light at
//! the vertex alone. The light at a point can be far from its surroundings' mean where the
//! vertex sits: in a crease where a wall meets the ceiling, under an object standing on the
//! floor, at a shadow's edge. Interpolated from such point values, that light would spread
//! over whole elements, which on a coarse mesh are large (an element a metre across darkened
//! by the corner it touches). The hat-weighted mean conserves what the elements show: the
//! interpolated field's integral over the surface is the gathered light's integral.
//!
//! Points inside other objects (a floor under a box standing on it) take no part, as the
//! lightmap's texels there do not; the vertices of the elements they partly cover are fitted
//! to those elements' visible points instead, so the light shown runs right up to the box.

use glam::Vec2;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_radiosity::element::ElementMesh;
use twopass_radiosity::triangle_rule::DUNAVANT_6 as RULE;
use twopass_scene::{RadianceEstimator, Scene};

use crate::lightmap::MAX_BACK_FACES;

/// The first key of the element vertices' gather sequences (texels from 0, the user's
/// vertices from [`VERTEX_KEYS`](crate::vertex::VERTEX_KEYS) = 2^40, the element mesh's from
/// here, six per node: the points of Dunavant's rule), so no two outputs share a sequence.
pub const ELEMENT_KEYS: u64 = 2 << 40;

/// `solution` with every element vertex's radiosity replaced by a final gather (`estimator`)
/// averaged over the elements around the vertex with its hat function as the weight:
/// radiosity B = pi L per part, W/m^2, emission and direct and indirect kept apart, no ambient
/// term (the gather sees every bounce the solution holds) and no separate focused caustic (the
/// gather carries it whole).
///
/// The mean is a quadrature: each element is gathered at the six points of Dunavant's rule
/// ([`DUNAVANT_6`](twopass_radiosity::triangle_rule::DUNAVANT_6)) (the
/// q-th of node n keyed by [`ELEMENT_KEYS`] + 6 n + q), and each of its corners takes the
/// points weighted by its own barycentric weight there, so the light that varies up to
/// cubically over an element is averaged exactly, with no positional noise for the gather's
/// own noise to add to.
pub fn gathered_solution(
    solution: &Solution,
    scene: &Scene,
    estimator: &dyn RadianceEstimator,
) -> Solution {
    let mesh = solution.mesh();
    let leaves: Vec<u32> = mesh.leaves().collect();
    // Per leaf, the parts (emitted, direct, indirect) gathered at each point of the rule, or
    // `None` for a point inside another object (where a box stands on the floor), whose light
    // is meaningless: as in the lightmap, it takes no part ([`MAX_BACK_FACES`]).
    let points: Vec<[Option<[Rgb; 3]>; 6]> = leaves
        .par_iter()
        .map(|&leaf| {
            let node = &mesh.nodes[leaf as usize];
            std::array::from_fn(|q| {
                let w = RULE[q].0;
                let p: Vec2 = node.uv[0] * w[0] + node.uv[1] * w[1] + node.uv[2] * w[2];
                let b = [1.0 - p.x - p.y, p.x, p.y].map(|x| x.clamp(0.0, 1.0));
                let t = node.scene_triangle;
                let e = estimator.estimate(t, b, ELEMENT_KEYS + 6 * u64::from(leaf) + q as u64);
                (e.back_faces <= MAX_BACK_FACES).then(|| {
                    let e = e.tinted(scene.albedo_tint(t, b));
                    [e.emitted, e.direct, e.indirect]
                })
            })
        })
        .collect();
    // Each vertex's hat-weighted mean over the points that count.
    let mut sums = vec![([Rgb::ZERO; 3], 0.0f32); mesh.vertices.len()];
    for (&leaf, values) in leaves.iter().zip(&points) {
        let node = &mesh.nodes[leaf as usize];
        for (&(w, weight), value) in RULE.iter().zip(values) {
            let Some(value) = value else { continue };
            for (&v, &l) in node.vertices.iter().zip(&w) {
                let hat = l * weight * node.area.max(0.0);
                let sum = &mut sums[v as usize];
                for (x, y) in sum.0.iter_mut().zip(value) {
                    *x += *y * hat;
                }
                sum.1 += hat;
            }
        }
    }
    let mut parts: Vec<Option<[Rgb; 3]>> = sums
        .iter()
        .map(|(p, w)| (*w > 0.0).then(|| p.map(|x| x / *w)))
        .collect();
    extrapolate_hidden(mesh, &leaves, &points, &mut parts);
    let parts: Vec<[Rgb; 3]> = parts
        .into_iter()
        .map(|p| p.unwrap_or([Rgb::ZERO; 3]))
        .collect();
    let pi = std::f32::consts::PI;
    let part = |i: usize| -> Vec<Rgb> { parts.iter().map(|p| p[i] * pi).collect() };
    let (emitted, direct, indirect) = (part(0), part(1), part(2));
    let total = (0..mesh.vertices.len())
        .map(|v| emitted[v] + direct[v] + indirect[v])
        .collect();
    Solution::new(
        mesh.clone(),
        total,
        direct,
        indirect,
        vec![Rgb::ZERO; mesh.vertices.len()],
    )
}

/// Fits the vertices of elements that other objects partly cover (a floor under a box
/// standing on it): the least-squares fit of the elements' linear interpolants to their
/// points that count, over those vertices' values with the others fixed, clamped at zero
/// (projected Gauss-Seidel sweeps from their visible points' mean, or their neighbours' for a
/// vertex with none). Such a vertex's hat function reaches under the box, so its mean
/// over the visible part alone is one-sided, the light from farther out, and would hide the
/// contact's shadow; the hidden points' darkness would spread that shadow over whole
/// elements. The fit sets the light of the visible parts right up to the box's edge.
fn extrapolate_hidden(
    mesh: &ElementMesh,
    leaves: &[u32],
    points: &[[Option<[Rgb; 3]>; 6]],
    parts: &mut [Option<[Rgb; 3]>],
) {
    /// Sweeps over the fitted vertices: each moves the fit by a share of what is left, and a
    /// contact's strip of them is a few elements wide.
    const SWEEPS: usize = 8;
    let mut fitted: Vec<bool> = parts.iter().map(Option::is_none).collect();
    for (&leaf, values) in leaves.iter().zip(points) {
        if values.iter().any(Option::is_none) {
            for &v in &mesh.nodes[leaf as usize].vertices {
                fitted[v as usize] = true;
            }
        }
    }
    let hidden: Vec<usize> = (0..parts.len()).filter(|&v| fitted[v]).collect();
    if hidden.is_empty() {
        return;
    }
    // The elements around each fitted vertex, with its corner in each.
    let mut ring: Vec<Vec<(usize, usize)>> = vec![Vec::new(); parts.len()];
    for (i, &leaf) in leaves.iter().enumerate() {
        for (k, &v) in mesh.nodes[leaf as usize].vertices.iter().enumerate() {
            if fitted[v as usize] {
                ring[v as usize].push((i, k));
            }
        }
    }
    twopass_radiosity::hidden::fill_hidden(mesh, parts);
    for _ in 0..SWEEPS {
        for &h in &hidden {
            let (mut sum, mut norm) = ([Rgb::ZERO; 3], 0.0f32);
            for &(i, k) in &ring[h] {
                let node = &mesh.nodes[leaves[i] as usize];
                let corners = node
                    .vertices
                    .map(|v| parts[v as usize].unwrap_or([Rgb::ZERO; 3]));
                for (&(w, weight), value) in RULE.iter().zip(&points[i]) {
                    let Some(value) = value else { continue };
                    let wq = weight * node.area.max(0.0) * w[k];
                    for (c, x) in sum.iter_mut().enumerate() {
                        let rest: Rgb = (0..3)
                            .filter(|&j| j != k)
                            .map(|j| corners[j][c] * w[j])
                            .sum();
                        *x += (value[c] - rest) * wq;
                    }
                    norm += wq * w[k];
                }
            }
            if norm > 0.0 {
                parts[h] = Some(sum.map(|x| (x / norm).max(Rgb::ZERO)));
            }
        }
    }
}
