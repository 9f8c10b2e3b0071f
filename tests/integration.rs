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
mod instancing;
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

/// The integral over the element mesh's leaves that `keep` (by node) of the field linear over
/// each leaf with `value` at each vertex: each leaf's area (scene units squared) times its
/// corners' mean. With the kept area, so a caller can take the mean.
pub fn element_integral(
    mesh: &twopass_radiosity::element::ElementMesh,
    keep: impl Fn(&twopass_radiosity::element::Node) -> bool,
    value: impl Fn(u32) -> f64,
) -> (f64, f64) {
    let (mut sum, mut area) = (0.0, 0.0);
    for leaf in mesh.leaves() {
        let node = &mesh.nodes[leaf as usize];
        if keep(node) {
            let mean = node.vertices.iter().map(|&v| value(v)).sum::<f64>() / 3.0;
            sum += mean * f64::from(node.area);
            area += f64::from(node.area);
        }
    }
    (sum, area)
}

/// Runs `f` on a rayon pool of `threads` threads (the determinism tests compare one and two).
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}
