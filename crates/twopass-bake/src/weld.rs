//! Welding the scene's vertices for output: the `.glb` files on the scene's own mesh (the
//! per-vertex bake and the lightmap) write one vertex per scene position and shading normal
//! within a group, so creases and seams split vertices and nothing else does.

use std::collections::HashMap;

use glam::Vec3;

/// Two shading normals at one scene position make one output vertex when the cosine between
/// them is at least this (about 0.8 degrees).
pub const COPLANAR_COS: f32 = 0.9999;

/// Output vertices of the scene mesh: one per scene position and shading normal, where
/// normals closer than [`COPLANAR_COS`] count as one (a
/// polygon's triangles each have their own normal, equal up to rounding or the polygon's
/// slight non-planarity), within one group (an object, or a chart of one).
#[derive(Default)]
pub(crate) struct SharedVertices {
    by_position: HashMap<(u32, u32), Vec<(Vec3, u32)>>,
}

impl SharedVertices {
    /// The output vertex of scene position `position` with normal `normal` in group `group`,
    /// and whether it is new (then numbered `next`).
    pub(crate) fn get(
        &mut self,
        group: u32,
        position: u32,
        normal: Vec3,
        next: u32,
    ) -> (u32, bool) {
        let list = self.by_position.entry((group, position)).or_default();
        match list.iter().find(|(n, _)| n.dot(normal) >= COPLANAR_COS) {
            Some(&(_, v)) => (v, false),
            None => {
                list.push((normal, next));
                (next, true)
            }
        }
    }
}
