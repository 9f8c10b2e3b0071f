//! Scene builders and statistics shared by the tests.

use std::path::Path;

use twopass_scene::Scene;

/// A scene from TOML text.
pub fn scene(text: &str) -> Scene {
    twopass_scene::load_toml(text, Path::new("test.toml"))
        .expect("test scene loads")
        .0
}

/// A scene of the repository's `scenes/` folder.
pub fn repo_scene(name: &str) -> Scene {
    let path = crate::scene_path(name);
    twopass_scene::load(&path)
        .expect("repository scene loads")
        .0
}

/// Mean and standard error of the mean of `values`.
pub fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}
