//! Loading: a TOML scene file, a bare OBJ or a glTF, validated once, into a [`Scene`](crate::scene::Scene).

mod assemble;
mod camera;
mod coincident;
mod entry;
mod gltf;
mod lamps;
mod loader;
mod materials;
mod objects;
mod sky;
mod texture;
#[cfg(test)]
mod texture_tests;

/// A 2 x 2 grey floor seen by a camera, the scene the lamp and sky tables' tests append to.
#[cfg(test)]
const TEST_FLOOR: &str = "version = 1\n\
    [camera]\nposition = [0, 1, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
    [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[object]]\nname = \"floor\"\nmaterial = \"w\"\n\
    shape = { type = \"quad\", origin = [-1, 0, 1], edge_u = [2, 0, 0], edge_v = [0, 0, -2] }\n";

pub use entry::{load, load_toml, load_toml_with, load_with};
pub use gltf::{SMOOTH_ROUGHNESS, gltf_image_problem};
pub use loader::{
    MAX_COORDINATE, MAX_EMITTED_POWER, MAX_PLACED_TRIANGLES, MAX_TRIANGLES, SPHERE_TOLERANCE,
};
