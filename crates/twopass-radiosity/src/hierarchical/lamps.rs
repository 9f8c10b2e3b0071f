//! Refining the surface hierarchy where the lamps' direct light varies. Link refinement splits
//! nodes by the light their links carry; a lamp has no link (its light enters every leaf's
//! corners as a source term), so the leaves it lights are split by the same oracle here,
//! before the first gather: a leaf whose reflected lamp light, rho E, spreads over its corners
//! and centroid by more than the link error threshold over its area is split, down to the
//! smallest element size. Shadow edges and the peak under a lamp get leaves as fine as the
//! threshold asks; evenly lit surfaces keep their triangles. The sky's sun counts as a
//! directional lamp at its centre here (its shadows are as sharp); the dome's smooth light is
//! left to the links' refinement.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;

use super::state::HierarchicalSolver;

impl HierarchicalSolver<'_> {
    /// Splits every leaf whose lamp error ([`Self::lamp_error`]) exceeds the link error
    /// threshold, and the leaves that makes, until none does or they reach twice the smallest
    /// element size. Decided in parallel, split in leaf order: the same on any thread count.
    pub(super) fn refine_for_lamps(&mut self) {
        if self.scene.lamps.is_empty() && self.scene.sky.as_ref().is_none_or(|s| s.sun.is_none()) {
            return;
        }
        let mut todo: Vec<u32> = self.mesh.leaves().collect();
        while !todo.is_empty() {
            let decided: Vec<(bool, u64)> = todo
                .par_iter()
                .with_min_len(64)
                .map(|&n| {
                    if self.mesh.longest_edge_length(n) <= 2.0 * self.min_size {
                        return (false, 0);
                    }
                    let (error, rays) = self.lamp_error(n);
                    (error > self.error_threshold, rays)
                })
                .collect();
            let before = self.mesh.nodes.len();
            for (&n, &(split, rays)) in todo.iter().zip(&decided) {
                self.rays += rays;
                if split && self.mesh.nodes[n as usize].children.is_none() {
                    self.mesh.refine(n);
                }
            }
            self.grow_arrays();
            todo = (before..self.mesh.nodes.len())
                .map(|n| n as u32)
                .filter(|&n| self.mesh.nodes[n as usize].children.is_none())
                .collect();
        }
    }

    /// The error of showing leaf `n`'s lamp light as the linear interpolant of its corners:
    /// the range of rho E's luminance (lamps, and the sun at its centre) over its corners and a lattice of points inside (spaced
    /// at most [`LAMP_PROBES_PER_DIAGONAL`] times finer than the scene's diagonal, the centroid
    /// among them, each lit by a shadow ray per lamp) times its area, W (the units of a link's
    /// BF error). With the rays cast.
    fn lamp_error(&self, n: u32) -> (f64, u64) {
        let node = &self.mesh.nodes[n as usize];
        let rho = self.tri_rho[node.scene_triangle as usize];
        if rho == DVec3::ZERO {
            return (0.0, 0);
        }
        let spacing = self.scene.bounds.diagonal() / LAMP_PROBES_PER_DIAGONAL;
        let m = ((self.mesh.longest_edge_length(n) / spacing).ceil() as u32).clamp(3, 64);
        let corners = self.mesh.corners(n);
        let normals = node.vertices.map(|v| self.mesh.vertices[v as usize].normal);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        // Without a sky the corners' exact lamp light is at hand; a sky's per-vertex light
        // holds the dome's noisy estimate, so then the corners are probed like the lattice.
        let sky = self.scene.sky.is_some();
        if !sky {
            for v in node.vertices {
                let y = luminance_f64(rho * self.lamp[v as usize]);
                (lo, hi) = (lo.min(y), hi.max(y));
            }
        }
        let mut rays = 0;
        for i in 0..=m {
            for j in 0..=m - i {
                let k = m - i - j;
                if !sky && (i == m || j == m || k == m) {
                    continue;
                }
                let w = [i, j, k].map(|x| f64::from(x) / f64::from(m));
                let p = corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2];
                let normal = (normals[0] * w[0] as f32
                    + normals[1] * w[1] as f32
                    + normals[2] * w[2] as f32)
                    .try_normalize()
                    .unwrap_or(self.scene.mesh.geometric_normal(node.scene_triangle));
                let at = self
                    .scene
                    .mesh
                    .surface_point_at(node.scene_triangle, p.as_vec3());
                // The sun as a directional lamp at its centre: deterministic, so the oracle
                // splits where the light changes, not where a sky estimate's noise does.
                let e = self.scene.lamp_irradiance(&at, normal, &mut rays)
                    + self.scene.sun_centre_irradiance(&at, normal, &mut rays);
                let y = luminance_f64(rho * e.as_dvec3());
                (lo, hi) = (lo.min(y), hi.max(y));
            }
        }
        ((hi - lo) * f64::from(node.area), rays)
    }
}

/// A leaf's lamp light is probed at points at most the scene's diagonal over this apart (the
/// progressive solver's default element size), so a shadow or a spot's cone smaller than a
/// large triangle is found inside it.
pub(super) const LAMP_PROBES_PER_DIAGONAL: f32 = 24.0;
