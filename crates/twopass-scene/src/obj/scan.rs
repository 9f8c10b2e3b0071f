//! The statement scan: every statement tobj would accept loosely or drop silently, checked
//! with its line, grouped as tobj groups them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::model::ScannedModel;
use crate::error::SceneError;
use crate::input::printable;

/// Checks every statement tobj would accept loosely or drop silently, with its line, and
/// follows tobj's grouping (a new model at `o`/`g`, or at `usemtl` of another material, once
/// the current one has faces) to learn which groups name a normal at every corner.
pub(super) fn scan(
    text: &str,
    path: &Path,
    material_map: &HashMap<String, usize>,
    mtllibs: &[PathBuf],
) -> Result<Vec<ScannedModel>, SceneError> {
    let err = |line: usize, problem: String| SceneError::Statement {
        path: path.to_owned(),
        line,
        problem,
    };
    // Positive indices may refer forward (tobj resolves them after reading the whole file).
    let (mut tv, mut tvt, mut tvn) = (0usize, 0usize, 0usize);
    for l in text.lines() {
        match l.split_whitespace().next() {
            Some("v") => tv += 1,
            Some("vt") => tvt += 1,
            Some("vn") => tvn += 1,
            _ => {}
        }
    }
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    let mut models = Vec::new();
    let mut current = ScannedModel {
        all_normals: true,
        all_texcoords: true,
        ..ScannedModel::default()
    };
    let mut faces = 0usize; // faces (any arity) in the current model, as tobj counts them
    let mut mat_id: Option<usize> = None;
    let numbers = |it: std::str::SplitWhitespace| -> Option<Vec<f64>> {
        it.map(|w| w.parse::<f64>().ok()).collect()
    };
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut it = line.split_whitespace();
        let Some(keyword) = it.next() else { continue };
        match keyword {
            "v" => {
                nv += 1;
                let v = numbers(it).unwrap_or_default();
                if !matches!(v.len(), 3 | 4 | 6) {
                    return Err(err(
                        n,
                        "vertex needs `v x y z`, `v x y z w` or `v x y z r g b`".into(),
                    ));
                }
                if v.len() == 4 && v[3] == 0.0 {
                    return Err(err(n, "vertex weight w is 0".into()));
                }
            }
            "vt" => {
                nvt += 1;
                if !matches!(numbers(it).map(|v| v.len()), Some(1..=3)) {
                    return Err(err(n, "texture coordinate needs `vt u [v [w]]`".into()));
                }
            }
            "vn" => {
                nvn += 1;
                if !matches!(numbers(it).map(|v| v.len()), Some(3)) {
                    return Err(err(n, "normal needs `vn x y z`".into()));
                }
            }
            "f" => {
                let corners: Vec<&str> = it.collect();
                if corners.len() < 3 {
                    return Err(err(
                        n,
                        format!(
                            "face has {} corner(s); a face needs at least 3",
                            corners.len()
                        ),
                    ));
                }
                let (mut normals, mut texcoords) = (0, 0);
                for (c, corner) in corners.iter().enumerate() {
                    let parts: Vec<&str> = corner.split('/').collect();
                    let bad =
                        |what: &str| err(n, format!("face corner {} (`{corner}`): {what}", c + 1));
                    if parts.len() > 3 {
                        return Err(bad("expected v, v/vt, v//vn or v/vt/vn"));
                    }
                    let index = |s: &str, current: usize, total: usize, what: &str| {
                        let valid = s.parse::<i64>().is_ok_and(|i| {
                            (i >= 1 && i as u64 <= total as u64)
                                || (i <= -1 && i.unsigned_abs() <= current as u64)
                        });
                        if valid {
                            Ok(())
                        } else {
                            Err(bad(&format!(
                                "{what} index `{s}` is not in range (the file has {total} {what}s, {current} before this line)"
                            )))
                        }
                    };
                    index(parts[0], nv, tv, "vertex")?;
                    // The `v` statement it names, 0-based (checked in range just above).
                    let i: i64 = parts[0].parse().unwrap_or(1);
                    let v = if i > 0 { i - 1 } else { nv as i64 + i } as u32;
                    if current.used.insert(v) {
                        current.vertices.push(v);
                    }
                    if let Some(t) = parts.get(1).filter(|t| !t.is_empty()) {
                        index(t, nvt, tvt, "texture coordinate")?;
                        texcoords += 1;
                    }
                    if let Some(v) = parts.get(2) {
                        if v.is_empty() {
                            return Err(bad("empty normal index after `//`"));
                        }
                        index(v, nvn, tvn, "normal")?;
                        normals += 1;
                    }
                }
                faces += 1;
                if current.first_face == 0 {
                    current.first_face = n;
                }
                current.triangles += corners.len() - 2;
                current.all_normals &= normals == corners.len();
                current.all_texcoords &= texcoords == corners.len();
            }
            "l" | "p" => faces += 1,
            "o" | "g" if faces > 0 => {
                push_model(&mut models, &mut current);
                faces = 0;
            }
            "usemtl" => {
                // The name is the rest of the line, after any white space.
                let name = line.trim_start()["usemtl".len()..].trim();
                if name.is_empty() {
                    return Err(err(n, "`usemtl` needs a material name".into()));
                }
                let new = material_map.get(name).copied();
                if new.is_none() && !material_map.is_empty() {
                    return Err(err(
                        n,
                        format!(
                            "`usemtl {}`: no material of that name in {}",
                            printable(name),
                            mtllibs
                                .iter()
                                .map(|p| p.display().to_string())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    ));
                }
                if new != mat_id && faces > 0 {
                    push_model(&mut models, &mut current);
                    faces = 0;
                }
                mat_id = new;
                current.usemtl = Some((name.to_owned(), n));
            }
            _ => {}
        }
    }
    push_model(&mut models, &mut current);
    Ok(models)
}

/// Ends the current model (kept if it has triangles) and starts the next with the same
/// `usemtl` in force.
pub(super) fn push_model(models: &mut Vec<ScannedModel>, current: &mut ScannedModel) {
    let next = ScannedModel {
        triangles: 0,
        all_normals: true,
        all_texcoords: true,
        usemtl: current.usemtl.clone(),
        first_face: 0,
        vertices: Vec::new(),
        used: Default::default(),
    };
    let done = std::mem::replace(current, next);
    if done.triangles > 0 {
        models.push(done);
    }
}
