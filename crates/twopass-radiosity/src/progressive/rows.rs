//! The row cache: per shooter patch, the form factors (with visibility) of every vertex to it,
//! computed in parallel, cached while memory allows and extended to the vertices a refinement
//! adds; and what each patch receives of a shot.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::random::hash;

use super::state::{PAIR_CLEAR, PAIR_UNKNOWN, ProgressiveSolver, ROW_BATCH};
use crate::form_factor;

impl ProgressiveSolver<'_> {
    /// Per patch `q`, what it receives of a shot with form factors `row` (per vertex, to the
    /// shooter), per unit of the shooter's unshot exitance: the sum over its elements of area
    /// times the mean of the element's vertices' form factors (elements with a positive mean
    /// only), scene units squared. Patch `q` gains `exitance * weights[q]` W per channel.
    pub(super) fn arrival_weights(&self, row: &[f32]) -> Vec<f64> {
        (0..self.mesh.patches.len())
            .map(|q| {
                let mut weight = 0.0;
                for (h, area) in self.element_means(q, |v| f64::from(row[v])) {
                    if h > 0.0 {
                        weight += h * area;
                    }
                }
                weight
            })
            .collect()
    }

    /// Form factors (with visibility) from every vertex in `vertices` to patch `p`, and the
    /// shadow rays cast. Parallel over vertices; each value depends only on (seed, vertex,
    /// patch), never on scheduling.
    fn form_factors(&self, p: usize, vertices: &[usize]) -> (Vec<f32>, u64) {
        let node = self.mesh.nodes[self.mesh.patches[p] as usize];
        let shooter = form_factor::Shooter::new(
            self.scene,
            self.mesh.corners(self.mesh.patches[p]),
            node.scene_triangle,
        );
        let ns = self
            .scene
            .mesh
            .geometric_normal(shooter.triangle)
            .as_dvec3();
        let hulls = self.patch_hulls(p, vertices);
        // A vertex's own shaft test costs about what one shadow ray does, and where its
        // patch's hull was tested and found blocked it rarely clears more: it pays only for
        // vertices whose hull was not tested (too few of them on their patch) and when it can
        // spare several rays.
        let vertex_shafts = self.options.shaft_culling && self.options.visibility.coarse() > 1;
        const CHUNK: usize = 64;
        let mut row = vec![0.0f32; vertices.len()];
        let mut rays = vec![0u64; vertices.len().div_ceil(CHUNK)];
        row.par_chunks_mut(CHUNK)
            .zip(rays.par_iter_mut())
            .zip(vertices.par_chunks(CHUNK))
            .for_each(|((row, rays), chunk)| {
                // The unoccluded form factors four vertices at a time.
                let mut x = [DVec3::ZERO; CHUNK];
                let mut n = [DVec3::ZERO; CHUNK];
                for (i, &v) in chunk.iter().enumerate() {
                    x[i] = self.receiving[v];
                    n[i] = self.mesh.vertices[v].normal.as_dvec3();
                }
                let mut unoccluded = [0.0; CHUNK];
                let count = chunk.len();
                shooter.source.form_factors_into(
                    &x[..count],
                    &n[..count],
                    Some(ns),
                    &mut unoccluded[..count],
                );
                for ((out, &v), &f) in row.iter_mut().zip(chunk).zip(&unoccluded) {
                    *out = f as f32;
                    if f <= 0.0 || !self.options.occlusion {
                        continue;
                    }
                    let from = &self.receivers[v];
                    let hull = self
                        .elements
                        .vertex_patch
                        .get(v)
                        .and_then(|&q| hulls.get(q as usize).copied())
                        .unwrap_or(PAIR_UNKNOWN);
                    if hull == PAIR_CLEAR
                        || hull == PAIR_UNKNOWN
                            && vertex_shafts
                            && form_factor::shaft_clear(self.scene, from, shooter.source.corners)
                    {
                        continue;
                    }
                    let seed = hash(self.options.seed ^ hash((v as u64) << 32 | p as u64));
                    let (vis, cast) = form_factor::visibility(
                        self.scene,
                        from,
                        self.mesh.vertices[v].normal,
                        &shooter,
                        self.options.visibility,
                        seed,
                    );
                    *out = (f * vis) as f32;
                    *rays += cast;
                }
            });
        (row, rays.iter().sum())
    }

    /// Each element (leaf) of patch `p`: the mean of the per-vertex `value` over its three
    /// vertices, and its area (scene units squared).
    pub(super) fn element_means<'a, T>(
        &'a self,
        p: usize,
        value: impl Fn(usize) -> T + 'a,
    ) -> impl Iterator<Item = (T, f64)> + 'a
    where
        T: std::iter::Sum + std::ops::Div<f64, Output = T>,
    {
        self.elements.range(p).map(move |i| {
            let sum: T = self.elements.vertices[i]
                .iter()
                .map(|&v| value(v as usize))
                .sum();
            (sum / 3.0, self.elements.area[i])
        })
    }

    /// The form factors of every vertex to patch `p`: the cached row, extended to the
    /// vertices it lacks.
    pub(super) fn patch_row(&mut self, p: usize) -> Vec<f32> {
        let n = self.mesh.vertices.len();
        let have = self.cached_len(p);
        if have == n {
            return self.cache[p].clone().expect("cached row");
        }
        let fresh = self.form_factors(p, &(have..n).collect::<Vec<_>>());
        self.extend_row(p, fresh)
    }

    /// How many vertices the cached row of patch `p` covers (from vertex 0).
    fn cached_len(&self, p: usize) -> usize {
        self.cache[p].as_ref().map_or(0, Vec::len)
    }

    /// The rows of `patches` (as [`ProgressiveSolver::patch_row`] gives them, in that order), with
    /// what they lack computed in parallel over patches and vertices at once: after a
    /// refinement every patch shot so far lacks the new vertices, and one small parallel
    /// pass per patch would cost more in starting and joining than in form factors. Rows go
    /// to `each` one by one, computed in batches of at most [`ROW_BATCH`] values.
    pub(super) fn patch_rows(
        &mut self,
        patches: &[usize],
        mut each: impl FnMut(&mut Self, usize, &[f32]),
    ) {
        let n = self.mesh.vertices.len();
        let mut rest = patches;
        while !rest.is_empty() {
            let (mut take, mut values) = (0, 0);
            while take < rest.len() && (take == 0 || values + n <= ROW_BATCH) {
                values += n - self.cached_len(rest[take]);
                take += 1;
            }
            let (batch, tail) = rest.split_at(take);
            rest = tail;
            let fresh: Vec<(Vec<f32>, u64)> = batch
                .par_iter()
                .map(|&p| self.form_factors(p, &(self.cached_len(p)..n).collect::<Vec<_>>()))
                .collect();
            for (&p, fresh) in batch.iter().zip(fresh) {
                let row = self.extend_row(p, fresh);
                each(self, p, &row);
            }
        }
    }

    /// Appends `fresh` (the form factors of the vertices after the cached ones, and the rays
    /// they cast) to the row of patch `p`, caches the row while the cache has room, and
    /// returns it.
    fn extend_row(&mut self, p: usize, (fresh, rays): (Vec<f32>, u64)) -> Vec<f32> {
        self.rays += rays;
        let have = self.cached_len(p);
        let mut row = self.cache[p].take().unwrap_or_default();
        row.extend_from_slice(&fresh);
        let bytes = fresh.len() * 4;
        if self.cached_bytes + bytes <= self.options.cache_bytes {
            self.cached_bytes += bytes;
            self.cache[p] = Some(row.clone());
        } else if have > 0 {
            self.cached_bytes -= have * 4;
        }
        row
    }

    /// Form factors of the given vertices to patch `p`: from the cache where the row is
    /// cached, computed (and counted in the rays) where not.
    pub(super) fn form_factors_at(&mut self, p: usize, vertices: &[usize]) -> Vec<f32> {
        if let Some(row) = &self.cache[p]
            && vertices.iter().all(|&v| v < row.len())
        {
            return vertices.iter().map(|&v| row[v]).collect();
        }
        let (f, rays) = self.form_factors(p, vertices);
        self.rays += rays;
        f
    }
}
