//! Adaptive subdivision: split the elements whose vertices' radiosities differ too much,
//! gather the new vertices' light and re-estimate the patches' unshot power.

use std::time::Instant;

use glam::DVec3;
use twopass_brdf::colour::luminance_f64;

use super::state::ProgressiveSolver;
use crate::options::AdaptiveOptions;

impl ProgressiveSolver<'_> {
    /// One round of adaptive subdivision: splits (conformingly) every element whose vertices'
    /// luminances differ by more than the threshold, gathers the new vertices' radiosity from
    /// everything shot so far, and re-estimates the patches' unshot radiosity on the finer
    /// mesh. Returns how many elements were split.
    pub fn refine(&mut self, adaptive: &AdaptiveOptions) -> usize {
        let started = Instant::now();
        let splits = self.refine_round(adaptive);
        self.bookkeeping.refining += started.elapsed();
        splits
    }

    fn refine_round(&mut self, adaptive: &AdaptiveOptions) -> usize {
        let lum = luminance_f64;
        let (mut total, mut area) = (0.0, 0.0);
        let leaves: Vec<u32> = self.mesh.leaves().collect();
        for &l in &leaves {
            let node = &self.mesh.nodes[l as usize];
            let y: f64 = node
                .vertices
                .iter()
                .map(|&v| lum(self.radiosity(v as usize)))
                .sum::<f64>()
                / 3.0;
            total += y * f64::from(node.area);
            area += f64::from(node.area);
        }
        let mean = total / area.max(f64::MIN_POSITIVE);
        let min_size = adaptive.min_element_size.unwrap_or(self.element_size / 8.0);
        let split: Vec<u32> = leaves
            .into_iter()
            .filter(|&l| {
                let ys = self.mesh.nodes[l as usize]
                    .vertices
                    .map(|v| lum(self.radiosity(v as usize)));
                let spread = ys.iter().copied().fold(f64::MIN, f64::max)
                    - ys.iter().copied().fold(f64::MAX, f64::min);
                spread > f64::from(adaptive.threshold) * mean
                    && self.mesh.longest_edge_length(l) > 2.0 * min_size
            })
            .collect();
        let mut splits = 0;
        for l in split {
            splits += self.mesh.refine(l);
        }
        if splits == 0 {
            return 0;
        }
        let old = self.rho.len();
        self.sync_vertices();
        // New vertices gather everything shot so far.
        let shot: Vec<usize> = (0..self.mesh.patches.len())
            .filter(|&p| self.shot_emit[p] != DVec3::ZERO || self.shot_refl[p] != DVec3::ZERO)
            .collect();
        self.patch_rows(&shot, |s, p, row| {
            let (se, sr) = (s.shot_emit[p], s.shot_refl[p]);
            for (v, &f) in row.iter().enumerate().skip(old) {
                s.received_emit[v] += se * f64::from(f);
                s.received_refl[v] += sr * f64::from(f);
            }
        });
        self.rebuild_patch_elements();
        self.resplat();
        // Re-estimate each patch's reflected radiosity from its (finer) elements. Their
        // vertices' irradiance is a point value: where a source is closer than the elements
        // resolve, interpolated over an element it would make more light than arrived. A
        // patch reflects at most rho times what arrived at it, so a re-estimate creates none.
        // The rho of the bound is the largest of its vertices' (per channel): on a textured
        // patch the texels' colours need not follow the mean albedo's where the light varies,
        // and a bound by the mean would clip (and tint) light that is really reflected.
        for p in 0..self.mesh.patches.len() {
            let mut reflected = DVec3::ZERO;
            for (r, area) in self.element_means(p, |v| self.rho[v] * self.received(v)) {
                reflected += r * area;
            }
            let rho_max = self
                .elements
                .range(p)
                .flat_map(|i| self.elements.vertices[i].iter())
                .fold(DVec3::ZERO, |m, &v| m.max(self.rho[v as usize]));
            let reflected = reflected.min(rho_max * self.arrived[p]) / self.patch_area(p);
            let new_unshot = reflected - self.shot_refl[p];
            let change = (new_unshot - self.unshot_refl[p]) * self.patch_area(p);
            self.bookkeeping.energy.unshot += change;
            self.bookkeeping.energy.remeshing -= change;
            self.unshot_refl[p] = new_unshot;
            self.note_unshot(p);
        }
        self.bookkeeping.rounds += 1;
        splits
    }
}
