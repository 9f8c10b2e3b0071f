//! Cross-crate integration tests: one binary, one link step.

use std::path::{Path, PathBuf};

mod accel;
mod architecture;
mod bad_input;
mod closed_form;
mod fuzz;
mod gathered_bake;
mod hardening;
mod hierarchical;
mod lamps;
mod radiosity;
mod scenes;
mod sky;
mod specular;
mod terminator;
mod trace;

/// A scene under the repository's `scenes/`.
pub fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name)
}

/// A fixture under `tests/data/`.
pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(name)
}

/// Runs `f` on a rayon pool of `threads` threads (the determinism tests compare one and two).
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}
