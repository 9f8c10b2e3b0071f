//! Reading and checking an MTL library before tobj parses it.

use std::collections::HashMap;
use std::path::Path;

use super::model::MtlOrigin;
use crate::error::SceneError;
use crate::input::{self, InputKind, ReadPolicy};

/// An MTL library's materials and their index by name, as tobj reads them.
pub(super) type MtlMaterials = (Vec<tobj::Material>, HashMap<String, usize>);

/// Reads and checks an MTL library, expands one-value colours (`Kd r` means `Kd r r r`) and
/// has tobj parse the result. `Ok(None)` when the file does not exist.
pub(super) fn load_mtl(
    path: &Path,
    policy: &ReadPolicy,
) -> Result<Option<(MtlMaterials, Vec<MtlOrigin>)>, SceneError> {
    if !path.exists() {
        return Ok(None);
    }
    let text = input::read_text(path, InputKind::Mtl, policy)?;
    let err = |line: usize, problem: String| SceneError::Statement {
        path: path.to_owned(),
        line,
        problem,
    };
    let mut normalized = String::with_capacity(text.len() + 64);
    let mut origins: Vec<MtlOrigin> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut it = line.split_whitespace();
        let keyword = it.next().unwrap_or("");
        let values: Vec<&str> = it.collect();
        let numbers: Option<Vec<f64>> = values.iter().map(|w| w.parse().ok()).collect();
        // tobj slices `newmtl` lines at a byte offset: no leading whitespace may reach it.
        let trimmed = line.trim_start();
        let mut out = trimmed.to_owned();
        match keyword {
            "newmtl" => {
                let name = trimmed["newmtl".len()..].trim();
                if name.is_empty() {
                    return Err(err(n, "`newmtl` needs a material name".into()));
                }
                origins.push(MtlOrigin {
                    path: path.to_owned(),
                    line: n,
                    keys: HashMap::new(),
                });
            }
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => {
                if matches!(values.first(), Some(&"spectral" | &"xyz")) {
                    return Err(err(
                        n,
                        format!(
                            "`{keyword} {}` colours are not supported; give `{keyword} r g b`",
                            values[0]
                        ),
                    ));
                }
                match numbers.as_deref() {
                    Some([r]) => out = format!("{keyword} {r} {r} {r}"),
                    Some([_, _, _]) => {}
                    _ => {
                        return Err(err(
                            n,
                            format!(
                                "`{keyword}` needs 1 or 3 numbers (`{keyword} r` or `{keyword} r g b`), got `{}`",
                                values.join(" ")
                            ),
                        ));
                    }
                }
            }
            "Ns" | "Ni" | "d" | "Tr" if !matches!(numbers.as_deref(), Some([_])) => {
                return Err(err(
                    n,
                    format!("`{keyword}` needs one number, got `{}`", values.join(" ")),
                ));
            }
            "illum" if !matches!(values.as_slice(), [v] if v.parse::<u8>().is_ok_and(|i| i <= 10)) =>
            {
                return Err(err(
                    n,
                    format!(
                        "`illum` needs an illumination model 0 to 10, got `{}`",
                        values.join(" ")
                    ),
                ));
            }
            _ => {}
        }
        if let Some(o) = origins
            .last_mut()
            .filter(|_| !keyword.is_empty() && keyword != "newmtl")
        {
            o.keys.entry(keyword.to_owned()).or_insert(n);
        }
        normalized.push_str(&out);
        normalized.push('\n');
    }
    let (materials, map) = tobj::load_mtl_buf(&mut std::io::Cursor::new(normalized.as_bytes()))
        .map_err(|source| SceneError::Statement {
            path: path.to_owned(),
            line: 1,
            problem: format!("cannot load MTL: {source}"),
        })?;
    Ok(Some(((materials, map.into_iter().collect()), origins)))
}
