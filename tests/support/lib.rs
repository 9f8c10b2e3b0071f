//! Test helpers that the test suites of several crates share (as wgpu's tests crate serves its
//! crates): the library of `twopass-tests`, a dev-dependency only. Each helper checks a file
//! independently of the twopass code that wrote it.

use std::path::Path;

pub mod gltf;

use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::LayerAttributes;

/// The names of the entries of the folder `dir`, sorted. Panics when it cannot be read.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The text attribute `name` of an EXR layer as the exr crate reads it. Panics, naming it, when
/// the attribute is missing or not text.
pub fn exr_text(attributes: &LayerAttributes, name: &str) -> String {
    match attributes.other.get(&Text::from(name)) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        other => panic!("{name}: {other:?}"),
    }
}
