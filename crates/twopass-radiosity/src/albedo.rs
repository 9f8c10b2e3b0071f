//! Reflectance over the element mesh when the scene has base colour textures: each element's
//! the area-weighted mean of the texture over it (from the mip level that fits the element,
//! [`twopass_scene::Scene::diffuse_albedo_over`]), and each vertex's the area-weighted mean of
//! its elements', so that a vertex (where the progressive solver receives) reflects what the
//! surface around it reflects on the whole. Without textures every value is the material's own
//! reflectance and nothing is looked up.

use glam::DVec3;
use rayon::prelude::*;
use twopass_scene::Scene;

use crate::element::ElementMesh;

/// The mean diffuse reflectance over node `n` (an element or a patch) of `mesh`.
pub(crate) fn node_albedo(scene: &Scene, mesh: &ElementMesh, n: u32) -> DVec3 {
    let node = &mesh.nodes[n as usize];
    let corners = node.uv.map(|b| [1.0 - b.x - b.y, b.x, b.y]);
    scene
        .diffuse_albedo_over(node.scene_triangle, corners)
        .as_dvec3()
}

/// Per-element reflectances, kept as the element mesh grows: computed once per node.
#[derive(Debug, Clone, Default)]
pub(crate) struct ElementAlbedo {
    /// Per node of the mesh: its mean reflectance, once asked for.
    nodes: Vec<Option<DVec3>>,
}

impl ElementAlbedo {
    /// Each vertex's reflectance: the mean of its elements' (leaves') reflectances weighted by
    /// their areas ([`vertex_means`]), each element's computed once. `None` when the scene has no textures (the caller keeps the material's reflectance).
    pub(crate) fn vertex_albedo(
        &mut self,
        scene: &Scene,
        mesh: &ElementMesh,
    ) -> Option<Vec<DVec3>> {
        if !scene.has_textures() {
            return None;
        }
        self.nodes.resize(mesh.nodes.len(), None);
        let leaves: Vec<u32> = mesh.leaves().collect();
        let missing: Vec<u32> = leaves
            .iter()
            .copied()
            .filter(|&l| self.nodes[l as usize].is_none())
            .collect();
        let found: Vec<DVec3> = missing
            .par_iter()
            .map(|&l| node_albedo(scene, mesh, l))
            .collect();
        for (l, rho) in missing.into_iter().zip(found) {
            self.nodes[l as usize] = Some(rho);
        }
        let nodes = &self.nodes;
        Some(vertex_means(mesh, |l| {
            nodes[l as usize].unwrap_or(DVec3::ZERO)
        }))
    }
}

/// Each vertex's reflectance: the mean of the reflectances `rho` of the leaves that touch it,
/// weighted by their areas (0 for a vertex no leaf touches, which no element shows).
pub(crate) fn vertex_means(mesh: &ElementMesh, rho: impl Fn(u32) -> DVec3) -> Vec<DVec3> {
    let mut sum = vec![(DVec3::ZERO, 0.0f64); mesh.vertices.len()];
    for l in mesh.leaves() {
        let node = &mesh.nodes[l as usize];
        let r = rho(l);
        let a = f64::from(node.area);
        for &v in &node.vertices {
            let s = &mut sum[v as usize];
            s.0 += r * a;
            s.1 += a;
        }
    }
    sum.into_iter()
        .map(|(r, a)| if a > 0.0 { r / a } else { DVec3::ZERO })
        .collect()
}
