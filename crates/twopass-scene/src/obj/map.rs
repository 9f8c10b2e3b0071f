//! An MTL `map_Kd` statement: its options and file name.

use std::path::{Path, PathBuf};

use glam::Vec2;

use super::model::MtlOrigin;
use crate::error::Warning;

/// A `map_Kd` statement read: the texture file (beside the MTL library), where it was
/// written, and the options the loader uses.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DiffuseMap {
    /// The image file, resolved against the library's folder.
    pub file: PathBuf,
    /// The MTL library and the line of the statement.
    pub library: PathBuf,
    /// See [`DiffuseMap::library`].
    pub line: Option<usize>,
    /// `-s u v`: texture coordinates scaled (1 1 without it).
    pub scale: Vec2,
    /// `-o u v`: texture coordinates offset (0 0 without it).
    pub offset: Vec2,
    /// `-clamp on`: coordinates clamped to the image's edge instead of repeating it.
    pub clamp: bool,
}

/// Arguments each option of the MTL specification's texture statements takes (numbers for
/// `-s`, `-o`, `-t`: one to three, read while they parse).
const OPTIONS: [(&str, usize); 10] = [
    ("-blendu", 1),
    ("-blendv", 1),
    ("-bm", 1),
    ("-boost", 1),
    ("-cc", 1),
    ("-clamp", 1),
    ("-imfchan", 1),
    ("-mm", 2),
    ("-texres", 1),
    ("-type", 1),
];

/// Reads the value tobj keeps of `map_Kd` (the rest of the line): `-s` and `-o` (u and v; w is
/// ignored) and `-clamp` are used; every other option is skipped with its arguments and
/// warned about with the line. `None` when no file name follows the options.
pub(crate) fn diffuse_map(
    value: &str,
    material: &str,
    origin: Option<&MtlOrigin>,
    obj: &Path,
    warnings: &mut Vec<Warning>,
) -> Option<DiffuseMap> {
    let library = origin.map_or_else(|| obj.to_owned(), |o| o.path.clone());
    let line = origin.map(|o| o.line_of("map_Kd"));
    let mut map = DiffuseMap {
        file: PathBuf::new(),
        library: library.clone(),
        line,
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        clamp: false,
    };
    let words: Vec<&str> = value.split_whitespace().collect();
    let mut i = 0;
    let mut skipped = Vec::new();
    while i < words.len() && words[i].starts_with('-') {
        let option = words[i];
        i += 1;
        let numbers = |i: &mut usize| {
            let mut v = Vec::new();
            while v.len() < 3
                && let Some(x) = words.get(*i).and_then(|w| w.parse::<f32>().ok())
            {
                v.push(x);
                *i += 1;
            }
            v
        };
        match option {
            "-s" | "-o" => {
                let v = numbers(&mut i);
                let pair = Vec2::new(
                    v.first()
                        .copied()
                        .unwrap_or(if option == "-s" { 1.0 } else { 0.0 }),
                    v.get(1)
                        .copied()
                        .unwrap_or(if option == "-s" { 1.0 } else { 0.0 }),
                );
                if !pair.is_finite() {
                    skipped.push(format!("{option} (not finite)"));
                } else if option == "-s" {
                    map.scale = pair;
                } else {
                    map.offset = pair;
                }
            }
            "-t" => {
                numbers(&mut i);
                skipped.push(option.to_owned());
            }
            "-clamp" => {
                map.clamp = words.get(i) == Some(&"on");
                i += 1;
            }
            _ => {
                let n = OPTIONS
                    .iter()
                    .find(|(name, _)| *name == option)
                    .map_or(0, |(_, n)| *n);
                i += n;
                skipped.push(option.to_owned());
            }
        }
    }
    if !skipped.is_empty() {
        warnings.push(Warning::Texture {
            path: library.clone(),
            line,
            at: format!("MTL material `{material}`"),
            problem: format!(
                "map_Kd option(s) {} not modelled: ignored (-s, -o and -clamp are read)",
                skipped.join(", ")
            ),
        });
    }
    let name = words.get(i..).map(|w| w.join(" ")).unwrap_or_default();
    if name.is_empty() {
        warnings.push(Warning::Texture {
            path: library,
            line,
            at: format!("MTL material `{material}`"),
            problem: "map_Kd names no file after its options: Kd alone is the albedo".into(),
        });
        return None;
    }
    let dir = map.library.parent().unwrap_or(Path::new("")).to_owned();
    map.file = dir.join(name);
    Some(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `-s` and `-o` are read (their w dropped), `-clamp on` clamps, other options are skipped
    /// with their arguments and warned about; the rest of the line, spaces and all, is the file.
    #[test]
    fn options_are_read_or_warned() {
        let mut w = Vec::new();
        let m = diffuse_map(
            "-s 2 3 1 -o 0.5 0.25 -bm 0.3 -clamp on my tex.png",
            "m",
            None,
            Path::new("dir/a.obj"),
            &mut w,
        )
        .expect("a file");
        assert_eq!(m.file, Path::new("dir/my tex.png"));
        assert_eq!(
            (m.scale, m.offset, m.clamp),
            (Vec2::new(2.0, 3.0), Vec2::new(0.5, 0.25), true)
        );
        assert_eq!(w.len(), 1);
        assert_eq!(
            w[0].to_string(),
            "dir/a.obj: MTL material `m`: map_Kd option(s) -bm not modelled: ignored (-s, -o and -clamp are read)"
        );
    }
}
