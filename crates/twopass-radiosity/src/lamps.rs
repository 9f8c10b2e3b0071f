//! The lamps' direct light on the element mesh (point, spot and directional lights: delta
//! lights no element can see): at every vertex, exactly, I(w) cos(theta) / r^2 or E cos(theta)
//! at its receiving point by its receiving normal, times one shadow ray's visibility. Both
//! solvers take it as the first bounce of emitted light (direct light, as a shot from an area
//! emitter gives), reflect it from there, and count the lamps' power in the emitted power.

use glam::DVec3;
use rayon::prelude::*;
use twopass_scene::Scene;

use crate::element::ElementMesh;
use crate::form_factor::receiving_point;

/// Irradiance (W/m^2 per channel, scene units) every lamp gives each vertex of `mesh` from
/// `from` on, in vertex order, and the shadow rays it cast. Each vertex is independent of the
/// others, so the result does not depend on the threads.
pub(crate) fn vertex_lamp_irradiance(
    scene: &Scene,
    mesh: &ElementMesh,
    from: usize,
) -> (Vec<DVec3>, u64) {
    if scene.lamps.is_empty() {
        return (
            vec![DVec3::ZERO; mesh.vertices.len().saturating_sub(from)],
            0,
        );
    }
    let per_vertex: Vec<(DVec3, u64)> = mesh.vertices[from.min(mesh.vertices.len())..]
        .par_iter()
        .with_min_len(256)
        .map(|vert| {
            let x = receiving_point(scene, vert);
            let at = scene.mesh.surface_point_at(vert.triangle, x.as_vec3());
            let mut rays = 0;
            let e = scene.lamp_irradiance(&at, vert.normal, &mut rays);
            (e.as_dvec3(), rays)
        })
        .collect();
    let rays = per_vertex.iter().map(|p| p.1).sum();
    (per_vertex.into_iter().map(|p| p.0).collect(), rays)
}

/// Power of the scene's lamps, W per channel ([`twopass_scene::Lamp::power`]; a directional
/// lamp's is what crosses the scene's bounding sphere).
pub(crate) fn lamp_power(scene: &Scene) -> DVec3 {
    scene.lamp_power().as_dvec3()
}
