//! What a progressive solve reports: its progress, the ambient term, the solution at the
//! vertices, the consistency checks, and the rows, weights and per-vertex terms the dense
//! solve and the tests read.

use glam::DVec3;
use twopass_brdf::Rgb;
use twopass_brdf::random::hash;
use twopass_scene::Scene;

use super::state::ProgressiveSolver;
use crate::ambient::ambient;
use crate::element::ElementMesh;
use crate::options::Method;
use crate::report::{Residuals, SolveProgress};
use crate::solution::Solution;
use crate::specular_receivers::SpecularReceivers;

impl ProgressiveSolver<'_> {
    /// Where the solve stands.
    pub fn progress(&self) -> SolveProgress {
        SolveProgress {
            shots: self.shots,
            unshot_fraction: self.unshot_fraction(),
            rays: self.rays,
            elements: self.elements.leaf.len(),
            vertices: self.mesh.vertices.len(),
            patches: self.mesh.patches.len(),
            ..self.bookkeeping.progress(Method::Progressive)
        }
    }

    /// The ambient term (Cohen et al. 1988): the unshot radiosity spread over the scene and
    /// multiplied by the interreflection factor 1 / (1 - mean reflectance), W/m^2.
    pub fn ambient(&self) -> DVec3 {
        let (mut unshot, mut rho, mut area) = (DVec3::ZERO, DVec3::ZERO, 0.0);
        for p in 0..self.mesh.patches.len() {
            let a = self.patch_area(p);
            unshot += (self.unshot_emit[p] + self.unshot_refl[p]) * a;
            rho += self.patch_rho(p) * a;
            area += a;
        }
        ambient(unshot, rho, area)
    }

    /// The current solution, with the ambient term for display of a partial solve. A vertex
    /// inside another object shows its visible neighbours' light ([`crate::hidden`]).
    pub fn solution(&self) -> Solution {
        let ambient = self.ambient();
        let n = self.mesh.vertices.len();
        let mut values: Vec<Option<[Rgb; 4]>> = (0..n)
            .map(|v| {
                (!self.hidden[v]).then(|| {
                    [
                        self.radiosity(v).as_vec3(),
                        (self.rho[v] * self.received_emit[v]).as_vec3(),
                        (self.rho[v] * self.received_indirect(v)).as_vec3(),
                        (self.rho[v] * ambient).as_vec3(),
                    ]
                })
            })
            .collect();
        crate::hidden::fill_hidden(&self.mesh, &mut values);
        let part = |i: usize| -> Vec<Rgb> {
            values
                .iter()
                .map(|x| x.map_or(Rgb::ZERO, |x| x[i]))
                .collect()
        };
        let solution = Solution::new(self.mesh.clone(), part(0), part(1), part(2), part(3));
        if let Some(spec) = &self.specular {
            solution.with_focused_caustics(
                (0..n)
                    .map(|v| (self.rho[v] * spec.focused[v]).as_vec3())
                    .collect(),
            )
        } else {
            solution
        }
    }

    /// Checks of the solve's consistency: the energy balance, the form-factor row sums of up
    /// to `samples` vertices (1 in a closed scene, less where light escapes) and the
    /// reciprocity A_p F_pq = A_q F_qp on up to `samples` pairs of patches, with the patch-to-
    /// patch form factors integrated from the vertex ones. Pairs are picked deterministically.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        let weights = self.patch_weights();
        let areas = self.patch_areas();
        let n_v = self.mesh.vertices.len();
        let n_p = self.mesh.patches.len();
        // A row sum costs one form factor per patch: take no more rows than a tenth of the
        // rays the solve cast pays for, so the report never rivals the solve.
        let per_row = (n_p as u64 * u64::from(self.options.visibility.min)).max(1);
        let rows = (samples as u64).min((self.rays / 10 / per_row).max(1)) as usize;
        let step = (n_v / rows.max(1)).max(1);
        let picked: Vec<usize> = (0..n_v).step_by(step).take(rows).collect();
        let mut sums = vec![0.0f64; picked.len()];
        for q in 0..n_p {
            for (s, f) in sums.iter_mut().zip(self.form_factors_at(q, &picked)) {
                *s += f64::from(f);
            }
        }
        // F_pq from the vertex form factors of p's vertices to q, area-weighted.
        let patch_ff = |s: &mut Self, p: usize, q: usize| {
            let vs: Vec<usize> = weights[p].iter().map(|&(v, _)| v as usize).collect();
            let f = s.form_factors_at(q, &vs);
            weights[p]
                .iter()
                .zip(f)
                .map(|(&(_, w), f)| w * f64::from(f))
                .sum::<f64>()
        };
        let mut pairs = Vec::new();
        for k in 0..samples as u64 {
            let (p, q) = (
                (hash(k) % n_p as u64) as usize,
                (hash(k ^ 0xABCD) % n_p as u64) as usize,
            );
            if p == q {
                continue;
            }
            pairs.push((
                areas[p] * patch_ff(self, p, q),
                areas[q] * patch_ff(self, q, p),
            ));
        }
        Residuals::from_samples(
            self.bookkeeping.worst_imbalance,
            self.bookkeeping.energy.excess_fraction(),
            &sums,
            pairs,
        )
    }

    /// The element mesh.
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

    /// Every vertex-to-patch form factor (with visibility), as the shots use them: row per
    /// patch. Computes what is not cached.
    pub fn form_factor_rows(&mut self) -> Vec<Vec<f32>> {
        (0..self.mesh.patches.len())
            .map(|p| self.patch_row(p))
            .collect()
    }

    /// Per patch: (vertex, weight) pairs with patch radiosity = sum of weight x vertex
    /// radiosity (area-weighted mean over the patch's elements).
    pub fn patch_weights(&self) -> Vec<Vec<(u32, f64)>> {
        (0..self.mesh.patches.len())
            .map(|p| {
                let mut w: Vec<(u32, f64)> = Vec::new();
                let a = self.patch_area(p);
                for &leaf in self.elements.leaves(p) {
                    let node = &self.mesh.nodes[leaf as usize];
                    for &v in &node.vertices {
                        let x = f64::from(node.area) / (3.0 * a);
                        match w.iter_mut().find(|e| e.0 == v) {
                            Some(e) => e.1 += x,
                            None => w.push((v, x)),
                        }
                    }
                }
                w
            })
            .collect()
    }

    /// Per vertex: reflectance and emitted exitance.
    pub fn vertex_terms(&self) -> (&[DVec3], &[DVec3]) {
        (&self.rho, &self.emission)
    }

    /// Per vertex: the irradiance the lamps give it directly, W/m^2 (a source term of the
    /// radiosity system beside the emission: B = E + rho (E_lamp + sum F B)).
    pub fn vertex_lamp_irradiance(&self) -> &[DVec3] {
        &self.lamp
    }

    /// Displayed radiosity of every vertex without the ambient term, W/m^2.
    pub fn vertex_radiosity(&self) -> Vec<DVec3> {
        (0..self.mesh.vertices.len())
            .map(|v| self.radiosity(v))
            .collect()
    }

    /// Per patch: area, scene units squared.
    pub fn patch_areas(&self) -> Vec<f64> {
        (0..self.mesh.patches.len())
            .map(|p| self.patch_area(p))
            .collect()
    }

    /// With the specular transfer: rays it cast and deposits it made so far; `None` when the
    /// scene does not need it ([`crate::specular::decide`]) or the options turned it off.
    pub fn specular_transfer(&self) -> Option<(u64, usize)> {
        self.specular.as_ref().map(SpecularReceivers::counts)
    }
}
