//! Test helpers that the test suites of several crates share (as wgpu's tests crate serves its
//! crates): the library of `twopass-tests`, a dev-dependency only. Each helper checks a file
//! independently of the twopass code that wrote it.

use std::path::Path;

pub mod gltf;
pub mod instancing;

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

/// Writes a textured floor into `dir`: `floor.obj`, the 1 m square from (0, 0, 0) to (1, 0, 1)
/// facing +y with texture coordinates (0, 0) to (1, 1) on its corners; `floor.mtl`, its
/// material `checker` with `Kd` = `kd` and `map_Kd checker.png`; and `checker.png`, an `n` x
/// `n` checker of the 8-bit sRGB colours `even` (where column + row is even) and `odd`.
pub fn write_checker_floor(dir: &Path, n: u32, even: [u8; 3], odd: [u8; 3], kd: f32) {
    let texels: Vec<u8> = (0..n * n)
        .flat_map(|i| {
            if (i % n + i / n).is_multiple_of(2) {
                even
            } else {
                odd
            }
        })
        .collect();
    let mut png_bytes = Vec::new();
    let mut e = png::Encoder::new(&mut png_bytes, n, n);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()
        .and_then(|mut w| w.write_image_data(&texels))
        .expect("a PNG encodes in memory");
    std::fs::write(dir.join("checker.png"), png_bytes).expect("checker.png is written");
    std::fs::write(
        dir.join("floor.mtl"),
        format!("newmtl checker\nKd {kd} {kd} {kd}\nmap_Kd checker.png\n"),
    )
    .expect("floor.mtl is written");
    std::fs::write(
        dir.join("floor.obj"),
        "mtllib floor.mtl\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nvt 0 0\nvt 0 1\nvt 1 1\nvt 1 0\n\
         usemtl checker\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .expect("floor.obj is written");
}
