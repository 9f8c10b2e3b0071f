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

pub use entry::{load, load_toml, load_toml_with, load_with};
pub use gltf::SMOOTH_ROUGHNESS;
pub use loader::{MAX_COORDINATE, MAX_EMITTED_POWER, MAX_TRIANGLES, SPHERE_TOLERANCE};
