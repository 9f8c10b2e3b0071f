//! Loading: a TOML scene file or a bare OBJ, validated once, into a [`Scene`](crate::scene::Scene).

mod assemble;
mod camera;
mod entry;
mod loader;
mod materials;
mod objects;

pub use entry::{load, load_toml, load_toml_with, load_with};
pub use loader::{MAX_COORDINATE, MAX_EMITTED_POWER, MAX_TRIANGLES, SPHERE_TOLERANCE};
