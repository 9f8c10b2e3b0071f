//! The light that truly leaves a scene, sampled with rays, against what a solve's bookkeeping
//! says escaped: the difference was lost in the solve. A closed room lets nothing out, yet a
//! solve whose form factors miss part of what a surface sends (a light a hair's breadth from
//! a wall, whose vertices see the wall as a whole hemisphere or not at all) books that light
//! as escaped. Only rays, which know nothing of the mesh, can tell the two apart.
//!
//! Light that lands on the back of a surface leaves the solve as surely as light that leaves
//! the scene: surfaces are one-sided, so the back of a strip light hung under a ceiling
//! absorbs what the ceiling sends it, in the solvers as in the path tracer. A ray that ends on
//! a back face counts as leaving.

use glam::{DVec3, Vec2};
use rayon::prelude::*;
use twopass_brdf::colour::luminance;
use twopass_brdf::random::{hash, unit_f32};
use twopass_scene::Scene;
use twopass_scene::targets::specular_objects;
use twopass_scene::workload::cosine_direction;

use crate::lamps::lamp_power;
use crate::report::Energy;
use crate::solution::Solution;

/// Cosine-distributed rays from each sampled surface point.
const RAYS_PER_POINT: u32 = 64;

/// The power a solve lost, as a share of the emitted power: what its bookkeeping booked as
/// escaped beyond what rays find leaving the scene, and the standard error of that share.
/// `None` where rays from the surfaces alone cannot tell (a scene with lamps or a sky, whose
/// light does not leave from a surface, or with mirrors or glass, which pass light on), or
/// where nothing was sent.
///
/// The share of the surfaces' light that leaves is sampled at `points` points drawn over the
/// element mesh with probability proportional to the power each element sends (its vertices'
/// mean radiosity times its area, luminance), [`RAYS_PER_POINT`] cosine-distributed rays each;
/// the lost power is `escaped - sent x share`, the largest over the channels, over `emitted`.
pub(crate) fn lost_fraction(
    scene: &Scene,
    solution: &Solution,
    energy: &Energy,
    points: usize,
    seed: u64,
) -> Option<(f64, f64)> {
    let specular = !specular_objects(scene).is_empty();
    if specular || lamp_power(scene) != DVec3::ZERO || points == 0 {
        return None;
    }
    let (share, error) = escaping_share(scene, solution, points, seed)?;
    let e = energy.emitted.max(DVec3::splat(f64::MIN_POSITIVE));
    let lost = ((energy.escaped - energy.sent * share) / e).max_element();
    let error = (energy.sent * error / e).max_element();
    (lost.is_finite() && error.is_finite()).then_some((lost, error))
}

/// The share of the light the surfaces send that leaves the scene or lands on the back of a
/// surface, and its standard error.
fn escaping_share(
    scene: &Scene,
    solution: &Solution,
    points: usize,
    seed: u64,
) -> Option<(f64, f64)> {
    let mesh = solution.mesh();
    let shot = solution.shot_radiosity();
    let leaves: Vec<u32> = mesh.leaves().collect();
    let mut cdf = Vec::with_capacity(leaves.len());
    let mut total = 0.0f64;
    for &leaf in &leaves {
        let node = &mesh.nodes[leaf as usize];
        let b = node
            .vertices
            .iter()
            .map(|&v| shot[v as usize])
            .sum::<glam::Vec3>()
            / 3.0;
        total += f64::from(luminance(b).max(0.0)) * f64::from(node.area.max(0.0));
        cdf.push(total);
    }
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let shares: Vec<f64> = (0..points as u64)
        .into_par_iter()
        .map(|k| {
            let key = hash(seed ^ hash(0xe5ca_9e00_0000_0000 ^ k));
            // Stratified over the power: point k in the k-th of `points` equal slices.
            let u = (k as f64 + f64::from(unit_f32(key))) / points as f64 * total;
            let i = cdf.partition_point(|&c| c < u).min(leaves.len() - 1);
            let node = &mesh.nodes[leaves[i] as usize];
            let (r1, r2) = (unit_f32(hash(key ^ 1)).sqrt(), unit_f32(hash(key ^ 2)));
            let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
            let p: Vec2 = node.uv[0] * w[0] + node.uv[1] * w[1] + node.uv[2] * w[2];
            let b = [1.0 - p.x - p.y, p.x, p.y].map(|x| x.clamp(0.0, 1.0));
            let point = scene.mesh.surface_point(node.scene_triangle, b);
            let out = (0..RAYS_PER_POINT)
                .filter(|&j| {
                    let h = hash(key ^ hash(u64::from(j) + 3));
                    let u = Vec2::new(unit_f32(h), unit_f32(hash(h)));
                    let dir = cosine_direction(point.normal, u);
                    let origin = point.spawn_origin(dir);
                    scene
                        .accel()
                        .closest(origin, dir, f32::INFINITY)
                        .is_none_or(|h| scene.mesh.geometric_normal(h.triangle).dot(dir) > 0.0)
                })
                .count();
            out as f64 / f64::from(RAYS_PER_POINT)
        })
        .collect();
    let n = shares.len() as f64;
    let mean = shares.iter().sum::<f64>() / n;
    let variance = shares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Some((mean, (variance / n).sqrt()))
}
