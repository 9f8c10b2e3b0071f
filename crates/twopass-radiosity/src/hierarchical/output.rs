//! What a hierarchical solve reports: its progress, the ambient term, the solution at the
//! vertices (with a final gather through the link hierarchy), the consistency checks and its
//! mesh and counts.

use glam::DVec3;
use rayon::prelude::*;
use twopass_scene::Scene;

use super::link::{Eval, Link};
use super::state::HierarchicalSolver;
use crate::ambient::ambient;
use crate::cluster::{Kind, NodeRef};
use crate::element::{ElementMesh, barycentric_2d};
use crate::options::Method;
use crate::report::{Residuals, SolveProgress};
use crate::solution::Solution;
use crate::specular;
use crate::specular_receivers::SpecularReceivers;

impl HierarchicalSolver<'_> {
    /// Where the solve stands.
    pub fn progress(&self) -> SolveProgress {
        SolveProgress {
            iterations: self.iterations,
            links: self.links.len(),
            clusters: self.clusters.nodes.len(),
            unshot_fraction: self.residual_fraction,
            rays: self.rays,
            elements: self.mesh.leaves().count(),
            vertices: self.mesh.vertices.len(),
            ..self.bookkeeping.progress(Method::Hierarchical)
        }
    }

    /// The ambient term (as in progressive refinement): the residual power spread over the
    /// scene times the interreflection factor 1 / (1 - mean reflectance), W/m^2.
    pub fn ambient(&self) -> DVec3 {
        if self.iterations == 0 {
            return DVec3::ZERO;
        }
        let (mut rho, mut area) = (DVec3::ZERO, 0.0);
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let a = f64::from(node.area);
            rho += self.node_rho(n) * a;
            area += a;
        }
        ambient(self.residual.max(DVec3::ZERO), rho, area)
    }

    /// The light each leaf's corners show: [`Self::corners_in`] with every unblocked
    /// surface-to-surface link above the leaf evaluated again at the leaf's own corners (a
    /// final gather at the vertices through the link hierarchy).
    ///
    /// A link attached above a leaf reaches the leaf's corners by linear interpolation of its
    /// corner values, and a uniform shift makes up what that interpolant misses of the
    /// receiver's area average. That is right for the power the receiver gets, and wrong
    /// pointwise wherever the form factor is curved over the receiver: a piece of the wall
    /// across a crease that touches the receiver's corner gives that corner close to 1/2
    /// (the half-plane limit) whatever its size, while a point a little way along the crease
    /// gets far less from it. Interpolated, that value spreads along the whole edge, and the
    /// links of every level above a crease vertex add up to more than its irradiance. The
    /// sources linked above a receiver partition
    /// what it sees, so their exact point values at a vertex sum to its point irradiance.
    /// Those links show their point values and no shift; the leaf's power, and so the
    /// transport between leaves, is unchanged: only what the vertices show. Partly blocked
    /// links keep their per-corner visibility (the shadow edges) and cluster links their
    /// far-field values.
    fn display_corners(&self) -> Vec<[[DVec3; 4]; 2]> {
        let mut out = self.corners_in.clone();
        if self.links.is_empty() {
            return out;
        }
        // The unblocked surface-to-surface links a surface node receives.
        let received = |n: u32| {
            self.received(NodeRef::surface(n))
                .iter()
                .filter(|l| matches!(l.source.kind(), Kind::Surface(_)) && !l.partial)
        };
        let fixes: Vec<(u32, [[DVec3; 4]; 2])> = self
            .mesh
            .roots
            .par_iter()
            .filter(|&&root| (root as usize) < self.mesh.nodes.len())
            .flat_map_iter(|&root| {
                let mut fixes = Vec::new();
                // A node and the links above it, each with the node it is attached to and its
                // visible fraction.
                type Above = Vec<(Link, u32, f64)>;
                let mut stack: Vec<(u32, Above)> = vec![(root, Vec::new())];
                while let Some((n, mut above)) = stack.pop() {
                    let node = &self.mesh.nodes[n as usize];
                    if let Some(children) = node.children {
                        above.extend(received(n).filter_map(|l| {
                            let Kind::Surface(q) = l.source.kind() else {
                                return None;
                            };
                            // What the link carries over what its receiver's corners see of
                            // the source unoccluded (1 unless a later visibility estimate
                            // found some of it blocked).
                            let open: f64 = self.corner_form_factors(n, q).iter().sum();
                            let k: f64 = l.transport.iter().map(|&k| f64::from(k)).sum();
                            (open > 0.0).then(|| (*l, n, (k / open).clamp(0.0, 1.0)))
                        }));
                        stack.push((children[0], above.clone()));
                        stack.push((children[1], above));
                        continue;
                    }
                    let mut fix = [[DVec3::ZERO; 4]; 2];
                    for (l, a, vis) in &above {
                        let Kind::Surface(q) = l.source.kind() else {
                            continue;
                        };
                        let f = self.corner_form_factors(n, q);
                        let at = &self.mesh.nodes[*a as usize];
                        let sv = self.source_value(l);
                        for c in 0..3 {
                            let w = barycentric_2d(at.uv, node.uv[c]);
                            let interpolated = f64::from(l.transport[0]) * f64::from(w[0])
                                + f64::from(l.transport[1]) * f64::from(w[1])
                                + f64::from(l.transport[2]) * f64::from(w[2]);
                            let d = f[c] * vis - interpolated;
                            fix[0][c] += sv[0] * d;
                            fix[1][c] += sv[1] * d;
                        }
                        fix[0][3] -= sv[0] * f64::from(l.area_correction);
                        fix[1][3] -= sv[1] * f64::from(l.area_correction);
                    }
                    // The leaf's own links are exact at its corners already: no shift.
                    for l in received(n) {
                        let sv = self.source_value(l);
                        fix[0][3] -= sv[0] * f64::from(l.area_correction);
                        fix[1][3] -= sv[1] * f64::from(l.area_correction);
                    }
                    fixes.push((n, fix));
                }
                fixes
            })
            .collect();
        for (n, fix) in fixes {
            for (o, f) in fix.iter().enumerate() {
                for (k, d) in f.iter().enumerate() {
                    out[n as usize][o][k] += *d;
                }
            }
        }
        out
    }

    /// The current solution: per-vertex radiosity over the leaves, the area-weighted mean of
    /// the leaves' corner values at each vertex. Each vertex shows the point values of the
    /// unblocked surface links above it (a final gather), not their linear interpolation.
    pub fn solution(&self) -> Solution {
        let corners = self.display_corners();
        let nv = self.mesh.vertices.len();
        let mut sum = vec![[DVec3::ZERO; 2]; nv];
        let mut weight = vec![0.0f64; nv];
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let a = f64::from(node.area).max(f64::MIN_POSITIVE);
            let [e, r] = corners[n as usize];
            for (k, &v) in node.vertices.iter().enumerate() {
                // Corner values plus the links' shifts, so the displayed light is the light
                // the leaf gets (see [`Link::area_correction`]).
                sum[v as usize][0] += (e[k] + e[3]) * a;
                sum[v as usize][1] += (r[k] + r[3]) * a;
                weight[v as usize] += a;
            }
        }
        let ambient = self.ambient();
        // Each vertex reflects with the mean of its leaves' reflectances (textured scenes).
        let vertex_rho = (!self.node_rho.is_empty())
            .then(|| crate::albedo::vertex_means(&self.mesh, |n| self.node_rho(n)));
        let rho_of = |v: usize, t: usize| vertex_rho.as_ref().map_or(self.tri_rho[t], |r| r[v]);
        let (mut radiosity, mut direct, mut indirect, mut amb) = (
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
        );
        for (v, vert) in self.mesh.vertices.iter().enumerate() {
            let t = vert.triangle as usize;
            let (rho, e) = (rho_of(v, t), self.tri_emission[t]);
            let w = weight[v].max(f64::MIN_POSITIVE);
            // A corner's value is a point value plus its leaf's uniform shift, and a negative
            // shift (the links' interpolants overshooting the leaf's mean) can outweigh a
            // small point value: where the light is nearly zero (a contact shadow), the mean
            // of such corners can fall below zero. Irradiance cannot; what the vertices show
            // is clamped (the leaves' power, and so the transport, is unchanged).
            let d = rho * (sum[v][0] / w).max(DVec3::ZERO);
            let i = rho * (sum[v][1] / w).max(DVec3::ZERO);
            radiosity.push((e + d + i).as_vec3());
            direct.push(d.as_vec3());
            indirect.push(i.as_vec3());
            amb.push((rho * ambient).as_vec3());
        }
        let solution = Solution::new(self.mesh.clone(), radiosity, direct, indirect, amb);
        if let Some(spec) = &self.specular {
            // Splatted afresh when the mesh changed since the last gather.
            let fresh;
            let per_vertex = if self.specular_stale {
                let areas = specular::VertexAreas::new(&self.mesh);
                let mut deposits = spec.transfer.deposits.clone();
                let mut values = vec![DVec3::ZERO; nv];
                let part = specular::focused;
                specular::splat(
                    &self.mesh,
                    &areas,
                    &mut deposits,
                    &mut Vec::new(),
                    part,
                    &mut values,
                );
                fresh = values;
                &fresh
            } else {
                &spec.focused
            };
            let focused = self
                .mesh
                .vertices
                .iter()
                .zip(per_vertex)
                .enumerate()
                .map(|(v, (vert, &f))| (rho_of(v, vert.triangle as usize) * f).as_vec3())
                .collect();
            solution.with_focused_caustics(focused)
        } else {
            solution
        }
    }

    /// Consistency checks, their cost bounded by `samples`: the energy balance; the row sums
    /// (irradiance per unit exitance of every source: 1 in a closed scene) of up to `samples`
    /// leaves; and reciprocity A_r K_rs = A_s K_sr of up to `samples` surface-to-surface links,
    /// each against a fresh estimate of its reverse link.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        // Row sums: gather with every source at unit exitance, pushed down to the leaves.
        let leaves: Vec<u32> = self.mesh.leaves().collect();
        let step = (leaves.len() / samples.max(1)).max(1);
        let picked: Vec<u32> = leaves.iter().copied().step_by(step).take(samples).collect();
        let sums: Vec<f64> = picked.par_iter().map(|&leaf| self.row_sum(leaf)).collect();
        let ss: Vec<Link> = self
            .links
            .iter()
            .filter(|l| {
                matches!(
                    (l.receiver.kind(), l.source.kind()),
                    (Kind::Surface(_), Kind::Surface(_))
                )
            })
            .copied()
            .collect();
        let step = (ss.len() / samples.max(1)).max(1);
        let pairs: Vec<(f64, f64)> = ss
            .iter()
            .step_by(step)
            .take(samples)
            .collect::<Vec<_>>()
            .par_iter()
            .map(|l| {
                let back = self.evaluate(l.source, l.receiver, self.options.visibility.max);
                let fwd = self.evaluate(l.receiver, l.source, self.options.visibility.max);
                // Area-averaged form factors: the corners' mean plus the shift.
                let average = |e: &Eval| {
                    (e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction
                };
                (
                    self.ends(l.receiver).area * average(&fwd),
                    self.ends(l.source).area * average(&back),
                )
            })
            .collect();
        Residuals::from_samples(
            self.bookkeeping.worst_imbalance,
            self.bookkeeping.energy.excess_fraction(),
            &sums,
            pairs,
        )
    }

    /// The sum of the transport coefficients that reach `leaf` (its own links and its
    /// ancestors', interpolated to it), averaged over its corners.
    fn row_sum(&self, leaf: u32) -> f64 {
        // Walk from the root to the leaf, summing the links of every node on the way.
        let path = self.mesh.path_to(leaf);
        let t = self.mesh.nodes[leaf as usize].scene_triangle;
        let sum_links = |r: NodeRef| -> f64 {
            self.received(r)
                .iter()
                .map(|l| self.unit_transport(l))
                .sum()
        };
        let mut total: f64 = path.iter().map(|&n| sum_links(NodeRef::surface(n))).sum();
        // Then the clusters above the triangle, up to the root.
        let mut c = self.clusters.triangle_parent[t as usize];
        while c != u32::MAX {
            total += sum_links(NodeRef::cluster(c));
            c = self.clusters.nodes[c as usize].parent;
        }
        total
    }

    /// A link's mean irradiance at its receiver per unit exitance of a uniform source: a
    /// cluster source sends its projected area toward the receiver, a cluster receiver spreads
    /// what it intercepts over its area.
    fn unit_transport(&self, l: &Link) -> f64 {
        let mean =
            (f64::from(l.transport[0]) + f64::from(l.transport[1]) + f64::from(l.transport[2]))
                / 3.0;
        let sent = match l.source.kind() {
            Kind::Cluster(c) => self.cluster_projected(c, l.dir),
            Kind::Surface(_) => 1.0,
        };
        match l.receiver.kind() {
            Kind::Cluster(c) => {
                mean * sent * self.cluster_projected(c, l.dir.opposite())
                    / self.clusters.nodes[c as usize].area.max(f64::MIN_POSITIVE)
            }
            Kind::Surface(_) => (mean + f64::from(l.area_correction)) * sent,
        }
    }

    /// The element mesh (the leaves of the surface hierarchy).
    pub fn mesh(&self) -> &ElementMesh {
        &self.mesh
    }

    /// The options the solve runs with.
    pub(crate) fn options(&self) -> &crate::options::Options {
        &self.options
    }

    /// The scene being solved.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// Links now.
    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// With the specular transfer: rays it cast and deposits it made so far; `None` when the
    /// scene does not need it ([`specular::decide`]) or the options turned it off.
    pub fn specular_transfer(&self) -> Option<(u64, usize)> {
        self.specular.as_ref().map(SpecularReceivers::counts)
    }
}
