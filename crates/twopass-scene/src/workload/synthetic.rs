//! The synthetic scene generator: the Cornell room filled with a jittered grid of icospheres,
//! as large as asked, for measuring the accelerator and the solvers at scale.

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::query::rng;
use crate::error::{SceneError, Warning};
use crate::scene::Scene;

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
