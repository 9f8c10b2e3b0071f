//! The lamps' and the sky's direct light on the element mesh (point, spot and directional
//! lights: delta lights no element can see; the sky: light from infinitely far away that no
//! element can see either). At every vertex, at its receiving point by its receiving normal:
//! exactly, I(w) cos(theta) / r^2 or E cos(theta) times one shadow ray's visibility per lamp;
//! the sky's and its sun's irradiance by stratified sampling with shadow rays
//! ([`Scene::sky_irradiance`], [`SKY_GRID`]^2 directions each, keyed by the solver's seed and
//! the vertex's index, so the same on any thread count). Both solvers take it as the first
//! bounce of emitted light (direct light, as a shot from an area emitter gives), reflect it
//! from there, and count the lamps' and the sky's power in the emitted power.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::random::hash;
use twopass_scene::{SKY_GRID, Scene};

use crate::element::ElementMesh;
use crate::form_factor::receiving_point;

/// Mixed into the seed of a vertex's sky samples (keeps them apart from the solvers' other
/// streams).
const SKY_STREAM: u64 = 0x5c1e_0000_0000_0000;

/// Irradiance (W/m^2 per channel, scene units) every lamp and the sky give each vertex of
/// `mesh` from `from` on, in vertex order, and the shadow rays it cast. Each vertex is
/// independent of the others and its sky samples are keyed by `seed` and its index, so the
/// result does not depend on the threads.
pub(crate) fn vertex_lamp_irradiance(
    scene: &Scene,
    mesh: &ElementMesh,
    from: usize,
    seed: u64,
) -> (Vec<DVec3>, u64) {
    if scene.lamps.is_empty() && scene.sky.is_none() {
        return (
            vec![DVec3::ZERO; mesh.vertices.len().saturating_sub(from)],
            0,
        );
    }
    let from = from.min(mesh.vertices.len());
    let per_vertex: Vec<(DVec3, u64)> = mesh.vertices[from..]
        .par_iter()
        .enumerate()
        .with_min_len(64)
        .map(|(i, vert)| {
            let x = receiving_point(scene, vert);
            let at = scene.mesh.surface_point_at(vert.triangle, x.as_vec3());
            let mut rays = 0;
            let mut e = scene.lamp_irradiance(&at, vert.normal, &mut rays);
            if scene.sky.is_some() {
                let key = hash(seed ^ hash(SKY_STREAM ^ (from + i) as u64));
                e += scene.sky_irradiance(&at, vert.normal, key, SKY_GRID, &mut rays);
            }
            (e.as_dvec3(), rays)
        })
        .collect();
    let rays = per_vertex.iter().map(|p| p.1).sum();
    (per_vertex.into_iter().map(|p| p.0).collect(), rays)
}

/// Power of the scene's lamps and sky, W per channel ([`twopass_scene::Lamp::power`]; a
/// directional lamp's and the sky's is what crosses the scene's bounding sphere,
/// [`twopass_scene::Sky::power`]).
pub(crate) fn lamp_power(scene: &Scene) -> DVec3 {
    let sky = scene
        .sky
        .as_ref()
        .map_or(glam::Vec3::ZERO, |s| s.power(scene.bounds.diagonal()));
    (scene.lamp_power() + sky).as_dvec3()
}
