//! Ray workloads for measuring and testing the accelerator: the same rays feed `twopass bench
//! rays`, the criterion benches and the BVH tests.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::accel::{Ray, SurfacePoint};
use crate::scene::Scene;

/// The three kinds of query the passes cast.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum QueryKind {
    /// Coherent closest-hit rays: one per pixel centre of the scene's camera, row by row.
    Camera,
    /// Incoherent closest-hit rays: cosine-distributed from random surface points, as bounces
    /// and radiosity shooting cast them.
    Incoherent,
    /// Occlusion (any-hit) rays between random surface points and points on the emitters.
    Occlusion,
}

/// A pseudo-random generator seeded from `seed`: the same seed, the same workload.
pub fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

/// One ray through each pixel centre of the scene's camera (its resolution), rows top down.
pub fn camera_rays(scene: &Scene) -> Vec<Ray> {
    let c = &scene.camera;
    (0..c.height)
        .flat_map(|y| (0..c.width).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .map(|p| Ray::new(c.position, c.direction(p)))
        .collect()
}

/// A uniform point in [0, 1)^2, x drawn first.
fn random_vec2(r: &mut Pcg64Mcg) -> Vec2 {
    let x = r.random::<f32>();
    Vec2::new(x, r.random::<f32>())
}

/// Cumulative triangle areas, for area-weighted surface sampling.
fn area_cdf(scene: &Scene) -> Vec<f64> {
    let mut acc = 0.0;
    scene
        .mesh
        .areas
        .iter()
        .map(|&a| {
            acc += f64::from(a);
            acc
        })
        .collect()
}

fn sample_surface(scene: &Scene, cdf: &[f64], r: &mut Pcg64Mcg) -> SurfacePoint {
    let target = r.random::<f64>() * cdf.last().copied().unwrap_or(0.0);
    let t = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1) as u32;
    scene.mesh.sample_triangle(t, random_vec2(r))
}

/// A cosine-distributed unit direction about unit `n` (Malley's method).
pub fn cosine_direction(n: Vec3, u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = TAU * u.y;
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.x).max(0.0).sqrt()).normalize()
}

/// `count` rays leaving area-uniform random surface points on their front side,
/// cosine-distributed, with offset origins.
pub fn incoherent_rays(scene: &Scene, count: usize, seed: u64) -> Vec<Ray> {
    let cdf = area_cdf(scene);
    let mut r = rng(seed);
    (0..count)
        .map(|_| {
            let p = sample_surface(scene, &cdf, &mut r);
            let d = cosine_direction(p.normal, random_vec2(&mut r));
            Ray::new(p.spawn_origin(d), d)
        })
        .collect()
}

/// `count` pairs (random surface point, random point on an emitter chosen by power), or
/// pairs of random surface points when the scene has no emitter.
pub fn occlusion_pairs(
    scene: &Scene,
    count: usize,
    seed: u64,
) -> Vec<(SurfacePoint, SurfacePoint)> {
    let cdf = area_cdf(scene);
    let mut r = rng(seed);
    let total: f32 = scene.emitters.iter().map(|e| e.power.element_sum()).sum();
    (0..count)
        .map(|_| {
            let a = sample_surface(scene, &cdf, &mut r);
            let b = if total > 0.0 {
                let mut x = r.random::<f32>() * total;
                let e = scene
                    .emitters
                    .iter()
                    .find(|e| {
                        x -= e.power.element_sum();
                        x < 0.0
                    })
                    .unwrap_or(&scene.emitters[scene.emitters.len() - 1]);
                e.sample(scene, r.random::<f32>(), random_vec2(&mut r))
            } else {
                sample_surface(scene, &cdf, &mut r)
            };
            (a, b)
        })
        .collect()
}
