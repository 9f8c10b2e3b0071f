//! Lights that face a surface closer than that surface's elements. The light trapped between
//! such a light and the surface is conserved (the solvers integrate the near field), but the
//! elements that the outline of the light's footprint crosses hold it as one uniform
//! radiosity and send it out beside the light, where the surface truly gets almost none: the
//! room around comes out too bright, silently, since no energy is lost or created. A light
//! 1e-4 of a 1 m room in front of a wall lights the room's walls to a median of 0.0074 in the
//! default render where the path tracer finds 8e-8. [`close_lights`] finds such lights with
//! rays, so that a bake can say so.

use glam::Vec2;
use twopass_brdf::random::{hash, unit_f32};
use twopass_scene::Scene;

use crate::element::ElementMesh;

/// Points sampled over each light, at most (fewer per light when there are many lights).
const POINTS_PER_LIGHT: usize = 64;

/// Points sampled over all lights together, at most (at least [`MIN_POINTS_PER_LIGHT`] each).
const POINTS_IN_ALL: usize = 1 << 14;

/// Points sampled over each light, at least.
const MIN_POINTS_PER_LIGHT: usize = 8;

/// Share of a light's points that must face a surface closer than its elements for the light
/// to be reported: a light whose corner merely touches a wall is not.
const CLOSE_SHARE: f64 = 0.25;

/// A light that faces a surface across a gap narrower than the elements of that surface.
#[derive(Debug, Clone, PartialEq)]
pub struct CloseLight {
    /// The light's object name.
    pub light: String,
    /// The name of the object it faces (where most of its close points look).
    pub facing: String,
    /// The smallest gap sampled along the light's normal, scene units.
    pub gap: f32,
    /// The longest edge of the faced surface's elements where the gaps were sampled, the
    /// largest of them, scene units.
    pub element: f32,
    /// Share of the light's sampled points (by area) that face a surface closer than its
    /// elements.
    pub share: f64,
}

/// The emitting objects of `scene` that face, over at least a quarter of their area, a surface
/// closer (along their normal) than the longest edge of the elements of `mesh` there. Points
/// are drawn over each light's area, the same for the same scene and mesh.
pub fn close_lights(scene: &Scene, mesh: &ElementMesh) -> Vec<CloseLight> {
    let points =
        (POINTS_IN_ALL / scene.emitters.len().max(1)).clamp(MIN_POINTS_PER_LIGHT, POINTS_PER_LIGHT);
    let m = &scene.mesh;
    let mut found = Vec::new();
    for (i, emitter) in scene.emitters.iter().enumerate() {
        let mut close = 0usize;
        let mut gap = f32::INFINITY;
        let mut element = 0.0f32;
        let mut facing = std::collections::HashMap::<u32, usize>::new();
        for k in 0..points {
            let key = hash(0xc105_e000_0000_0000 ^ (i as u64) << 20 ^ k as u64);
            // Stratified over the light's area: point k in the k-th of `points` equal slices.
            let pick = (k as f32 + unit_f32(key)) / points as f32;
            let u = Vec2::new(unit_f32(hash(key ^ 1)), unit_f32(hash(key ^ 2)));
            let p = emitter.sample(scene, pick, u);
            let dir = p.normal;
            let Some(hit) = scene
                .accel()
                .closest(p.spawn_origin(dir), dir, f32::INFINITY)
            else {
                continue;
            };
            // Only a surface that faces the light back holds its light.
            if m.geometric_normal(hit.triangle).dot(dir) >= 0.0 {
                continue;
            }
            let [_, b1, b2] = hit.barycentric;
            let Some((leaf, _)) = mesh.locate(hit.triangle, b1, b2) else {
                continue;
            };
            let size = mesh.longest_edge_length(leaf);
            if hit.t < size {
                close += 1;
                gap = gap.min(hit.t);
                element = element.max(size);
                *facing.entry(m.object_of(hit.triangle)).or_default() += 1;
            }
        }
        let share = close as f64 / points as f64;
        if share >= CLOSE_SHARE {
            let most = facing
                .iter()
                .max_by_key(|&(o, n)| (*n, std::cmp::Reverse(*o)))
                .map(|(&o, _)| o);
            found.push(CloseLight {
                light: scene.objects[emitter.object as usize].name.clone(),
                facing: most.map_or_else(String::new, |o| scene.objects[o as usize].name.clone()),
                gap,
                element,
                share,
            });
        }
    }
    found
}
