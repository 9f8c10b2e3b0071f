//! A solution whose element-vertex values come from a final gather: what the element-mesh
//! outputs (`.glb`, `.ply`, `.bake`) hold when a bake gathers them.

use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_radiosity::Solution;
use twopass_scene::{RadianceEstimate, RadianceEstimator, Scene};

/// The first key of the element vertices' gather sequences (texels from 0, the user's
/// vertices from [`VERTEX_KEYS`](crate::vertex::VERTEX_KEYS) = 2^40, element vertices from
/// here), so no two outputs share a sequence.
pub const ELEMENT_KEYS: u64 = 2 << 40;

/// `solution` with every element vertex's radiosity replaced by a final gather there
/// (`estimator`, keyed by [`ELEMENT_KEYS`] plus the vertex index): radiosity B = pi L per part,
/// W/m^2, emission and direct and indirect kept apart, no ambient term (the gather sees every
/// bounce the solution holds) and no separate focused caustic (the gather carries it whole).
pub fn gathered_solution(
    solution: &Solution,
    scene: &Scene,
    estimator: &dyn RadianceEstimator,
) -> Solution {
    let mesh = solution.mesh();
    let estimates: Vec<RadianceEstimate> = mesh
        .vertices
        .par_iter()
        .enumerate()
        .map(|(i, v)| {
            let b = scene
                .mesh
                .barycentric(v.triangle, v.position.as_dvec3())
                .map(|x| x.clamp(0.0, 1.0) as f32);
            estimator
                .estimate(v.triangle, b, ELEMENT_KEYS + i as u64)
                .tinted(scene.albedo_tint(v.triangle, b))
        })
        .collect();
    let pi = std::f32::consts::PI;
    let part = |f: fn(&RadianceEstimate) -> Rgb| -> Vec<Rgb> {
        estimates.iter().map(|e| f(e) * pi).collect()
    };
    Solution::new(
        mesh.clone(),
        part(RadianceEstimate::total),
        part(|e| e.direct),
        part(|e| e.indirect),
        vec![Rgb::ZERO; mesh.vertices.len()],
    )
}
