//! The shaft cache: whether nothing can come between a shooter patch and a receiving patch
//! (shaft culling with the two patches' hull), kept per pair of patches.

use std::sync::atomic::Ordering;

use rayon::prelude::*;

use super::state::{HULL_MIN_VERTICES, PAIR_BLOCKED, PAIR_CLEAR, PAIR_UNKNOWN, ProgressiveSolver};
use crate::form_factor;

impl ProgressiveSolver<'_> {
    /// With shaft culling: per patch, whether nothing can come between it and shooter patch
    /// `p` ([`form_factor::patches_clear`]): [`PAIR_CLEAR`] or [`PAIR_BLOCKED`] for the
    /// patches at least [`HULL_MIN_VERTICES`] of `vertices` lie on, [`PAIR_UNKNOWN`] (not
    /// tested) for the others; empty without shaft culling. A vertex on a clear patch needs
    /// neither its own shaft test nor shadow rays: its segments to `p` lie in the hull.
    pub(super) fn patch_hulls(&self, p: usize, vertices: &[usize]) -> Vec<u8> {
        if !(self.options.shaft_culling && self.options.occlusion) {
            return Vec::new();
        }
        let n = self.mesh.patches.len();
        let mut on = vec![0u32; n];
        for &v in vertices {
            if let Some(&q) = self.elements.vertex_patch.get(v)
                && (q as usize) < n
                && q as usize != p
            {
                on[q as usize] += 1;
            }
        }
        // Only the row's own vertices decide which pairs are tested, never what other rows
        // (computed in parallel) have put in the cache: a vertex must take the same path,
        // hull or its own test, on any thread count.
        let wanted: Vec<bool> = on.iter().map(|&c| c >= HULL_MIN_VERTICES).collect();
        let patch = |q: usize| {
            let node = self.mesh.patches[q];
            let tri = self.mesh.nodes[node as usize].scene_triangle;
            (
                self.mesh.corners(node),
                self.scene.mesh.geometric_normal(tri),
            )
        };
        let shooter = patch(p);
        let cached = !self.pair_clear.is_empty();
        wanted
            .par_iter()
            .enumerate()
            .with_min_len(16)
            .map(|(q, &w)| {
                if !w {
                    return PAIR_UNKNOWN;
                }
                if cached {
                    match self.pair_clear[q * n + p].load(Ordering::Relaxed) {
                        PAIR_UNKNOWN => {}
                        state => return state,
                    }
                }
                // The lower index first, whichever row asks: the rounding then never
                // depends on which of the two rows (computed in parallel) asks first.
                let clear = if q < p {
                    form_factor::patches_clear(self.scene, patch(q), shooter)
                } else {
                    form_factor::patches_clear(self.scene, shooter, patch(q))
                };
                let state = if clear { PAIR_CLEAR } else { PAIR_BLOCKED };
                if cached {
                    self.pair_clear[q * n + p].store(state, Ordering::Relaxed);
                    self.pair_clear[p * n + q].store(state, Ordering::Relaxed);
                }
                state
            })
            .collect()
    }
}
