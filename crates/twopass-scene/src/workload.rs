//! Ray workloads for measuring and testing the accelerator, and a synthetic scene generator:
//! the same rays feed `twopass bench rays`, the criterion benches and the BVH tests.

use std::f32::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::accel::{Ray, SurfacePoint};
use crate::error::{SceneError, Warning};
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

/// The generated room's quads as (name, origin, edge u, edge v), TOML arrays in scene units:
/// the Cornell room's five walls (facing in, open toward the camera), then its light.
const ROOM: [(&str, &str, &str, &str); 6] = [
    ("floor", "[0, 0, 0]", "[0, 0, 559.2]", "[556, 0, 0]"),
    ("ceiling", "[0, 548.8, 0]", "[556, 0, 0]", "[0, 0, 559.2]"),
    ("back", "[0, 0, 559.2]", "[0, 548.8, 0]", "[556, 0, 0]"),
    ("left", "[556, 0, 0]", "[0, 0, 559.2]", "[0, 548.8, 0]"),
    ("right", "[0, 0, 0]", "[0, 548.8, 0]", "[0, 0, 559.2]"),
    ("light", "[213, 548.7, 227]", "[130, 0, 0]", "[0, 0, 105]"),
];

/// Appends one white object of the generated scene to `s`: its `extra` lines (each ending in a
/// newline), then its inline `shape` table.
fn push_object(s: &mut String, name: &str, extra: &str, shape: &str) {
    let _ = write!(
        s,
        "[[object]]\nname = \"{name}\"\nmaterial = \"white\"\n{extra}shape = {shape}\n"
    );
}

/// Triangles of one generated sphere (icosphere level 4).
const SPHERE_TRIANGLES: usize = 20 * 4usize.pow(4);

/// A scene file (TOML text) of at least `triangles` triangles: the Cornell room (five walls
/// facing in, open toward the camera) filled with a jittered grid of level-4 icospheres of
/// varied sizes. Deterministic for a `seed`.
pub fn synthetic_scene_toml(triangles: usize, seed: u64) -> String {
    let spheres = triangles.div_ceil(SPHERE_TRIANGLES).max(1);
    let per_axis = (spheres as f64).cbrt().ceil() as usize;
    let cell = 540.0 / per_axis as f32;
    let mut r = rng(seed);
    let mut s = String::from(
        r#"version = 1
[camera]
position = [278, 273, -800]
look_at = [278, 273, 0]
focal_length = 35
film_size = [25, 25]
resolution = [512, 512]

[[material]]
name = "white"
type = "lambert"
diffuse = [0.725, 0.71, 0.68]

# The room: five walls facing in, open toward the camera.
"#,
    );
    for (k, (name, origin, edge_u, edge_v)) in ROOM.iter().enumerate() {
        if k > 0 {
            s.push('\n');
        }
        // The last quad is the light, under the ceiling.
        let emission = if k + 1 == ROOM.len() {
            "emission = [17, 12, 4]\n"
        } else {
            ""
        };
        let shape = format!(
            "{{ type = \"quad\", origin = {origin}, edge_u = {edge_u}, edge_v = {edge_v} }}"
        );
        push_object(&mut s, name, emission, &shape);
    }
    for i in 0..spheres {
        let (x, y, z) = (
            i % per_axis,
            (i / per_axis) % per_axis,
            i / (per_axis * per_axis),
        );
        let jitter = |r: &mut Pcg64Mcg| (r.random::<f32>() - 0.5) * 0.3 * cell;
        let c = Vec3::new(
            8.0 + cell * (x as f32 + 0.5) + jitter(&mut r),
            4.0 + cell * (y as f32 + 0.5) * 0.98 + jitter(&mut r),
            8.0 + cell * (z as f32 + 0.5) + jitter(&mut r),
        );
        let radius = cell * (0.15 + 0.2 * r.random::<f32>());
        s.push('\n');
        let shape = format!(
            "{{ type = \"sphere\", center = [{}, {}, {}], radius = {radius}, subdivisions = 4 }}",
            c.x, c.y, c.z
        );
        push_object(&mut s, &format!("sphere{i}"), "", &shape);
    }
    s
}

/// Loads the synthetic scene of [`synthetic_scene_toml`].
pub fn synthetic_scene(triangles: usize, seed: u64) -> Result<(Scene, Vec<Warning>), SceneError> {
    crate::load::load_toml(
        &synthetic_scene_toml(triangles, seed),
        Path::new(&format!("synthetic-{triangles}.toml")),
    )
}
