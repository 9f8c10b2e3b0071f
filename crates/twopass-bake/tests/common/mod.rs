//! What the bake crate's tests share: the repository root and the Cornell box solved
//! coarsely by progressive refinement (the bake tests check formats and sampling, not the
//! solver's accuracy).

use std::path::{Path, PathBuf};

use twopass_radiosity::{Options, Solution, Solver, Stop};
use twopass_scene::Scene;

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `scenes/cornell-box.toml` solved with elements of about `element_size` mm to an unshot
/// fraction of 1e-2.
pub fn cornell(element_size: f32) -> (Scene, Solution) {
    solved("scenes/cornell-box.toml", element_size)
}

/// The scene at `path` (from the repository root) solved like [`cornell`].
pub fn solved(path: &str, element_size: f32) -> (Scene, Solution) {
    let (scene, _) = twopass_scene::load(repo().join(path)).unwrap();
    let solution = solve(&scene, element_size);
    (scene, solution)
}

/// `scene` solved like [`cornell`].
pub fn solve(scene: &Scene, element_size: f32) -> Solution {
    let options = Options {
        element_size: Some(element_size),
        stop: Stop {
            unshot_fraction: 1e-2,
            ..Stop::default()
        },
        ..Options::default()
    };
    let mut solver = Solver::new(scene, options).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    solver.solution()
}
