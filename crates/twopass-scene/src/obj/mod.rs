//! Wavefront OBJ + MTL through tobj, with the file and line context tobj does not give, and
//! the mapping of MTL materials onto ours.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use twopass_brdf::{BlinnPhongParams, Material, Rgb};

use crate::error::{SceneError, Warning};
use crate::input::{self, InputKind, ReadPolicy, printable};
use crate::shape::ShapeMesh;

/// One OBJ group (tobj model) as a shape, with its MTL material index.
pub(crate) struct ObjModel {
    pub name: String,
    pub mesh: ShapeMesh,
    pub material: Option<usize>,
    /// The `usemtl` statement in force for this group (name, line), if any.
    pub usemtl: Option<(String, usize)>,
}

/// Where an MTL material was defined: its library and the lines of its statements.
#[derive(Debug, Clone)]
pub(crate) struct MtlOrigin {
    pub path: PathBuf,
    /// Line of `newmtl`.
    pub line: usize,
    /// Line of each key (`Kd`, `Ke`, ...) within the material.
    pub keys: HashMap<String, usize>,
}

impl MtlOrigin {
    /// The line of `key` in this material, or of its `newmtl`.
    pub fn line_of(&self, key: &str) -> usize {
        self.keys.get(key).copied().unwrap_or(self.line)
    }
}

/// A loaded OBJ: its groups and its MTL materials (or why they failed).
pub(crate) struct ObjFile {
    pub models: Vec<ObjModel>,
    pub materials: Result<Vec<tobj::Material>, tobj::LoadError>,
    /// Where each of `materials` was defined (same order).
    pub origins: Vec<MtlOrigin>,
    /// The `mtllib` files it names, resolved against its folder.
    pub mtllibs: Vec<PathBuf>,
    /// The first library that could not be opened, if any.
    pub missing_mtl: Option<PathBuf>,
}

/// What the statement scan learned about one tobj model.
#[derive(Debug, Default, Clone)]
struct ScannedModel {
    /// Triangles its faces become (a polygon of n corners gives n - 2).
    triangles: usize,
    /// Whether every corner of every face names a normal.
    all_normals: bool,
    /// Whether every corner of every face names a texture coordinate.
    all_texcoords: bool,
    usemtl: Option<(String, usize)>,
}

/// One MTL library, read and checked by us, parsed by tobj.
struct MtlLib {
    written: String,
    result: tobj::MTLLoadResult,
    origins: Vec<MtlOrigin>,
}

pub(crate) fn load(path: &Path, policy: &ReadPolicy) -> Result<ObjFile, SceneError> {
    let text = input::read_text(path, InputKind::Obj, policy)?;
    // An empty parent joins to the bare name, which is how the user wrote it.
    let dir = path.parent().unwrap_or(Path::new(""));
    // The libraries, in the order tobj asks for them (it takes the rest of the line as one
    // file name).
    let mut libs: Vec<MtlLib> = Vec::new();
    let mut mtllibs = Vec::new();
    let mut missing_mtl = None;
    for line in text.lines() {
        let Some(rest) = line.trim_start().strip_prefix("mtllib") else {
            continue;
        };
        if !rest.starts_with(char::is_whitespace) {
            continue;
        }
        let written = line.split_once(' ').unwrap_or_default().1.trim().to_owned();
        let mtl_path = dir.join(&written);
        mtllibs.push(mtl_path.clone());
        let lib = match load_mtl(&mtl_path, policy)? {
            Some((result, origins)) => MtlLib {
                written,
                result,
                origins,
            },
            None => {
                missing_mtl.get_or_insert(mtl_path);
                MtlLib {
                    written,
                    result: Err(tobj::LoadError::OpenFileFailed),
                    origins: Vec::new(),
                }
            }
        };
        libs.push(lib);
    }
    // The merged name -> index map, as tobj builds it (later libraries win).
    let mut material_map: HashMap<String, usize> = HashMap::new();
    let mut origins = Vec::new();
    for lib in &libs {
        if let Ok((mats, map)) = &lib.result {
            let offset = origins.len();
            for (name, i) in map {
                material_map.insert(name.clone(), i + offset);
            }
            origins.extend(lib.origins.iter().cloned());
            debug_assert_eq!(mats.len(), lib.origins.len());
        }
    }
    let scanned = scan(&text, path, &material_map, &mtllibs)?;

    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let loader = |p: &Path| -> tobj::MTLLoadResult {
        libs.iter()
            .find(|l| Path::new(&l.written) == p)
            .map_or(Err(tobj::LoadError::OpenFileFailed), |l| l.result.clone())
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(text.as_bytes()), &opts, loader).map_err(
            |source| SceneError::Obj {
                path: path.to_owned(),
                line: find_bad_line(&text, source),
                source,
            },
        )?;
    // tobj's models in order, empty ones (a trailing `g`, lines only) left out as the scan
    // does; when the two disagree, no group gets smooth normals rather than wrong ones.
    let models: Vec<tobj::Model> = models
        .into_iter()
        .filter(|m| !m.mesh.indices.is_empty())
        .collect();
    let agree = models.len() == scanned.len()
        && models
            .iter()
            .zip(&scanned)
            .all(|(m, s)| m.mesh.indices.len() == 3 * s.triangles);
    let mut out = Vec::with_capacity(models.len());
    for (k, m) in models.into_iter().enumerate() {
        let mesh = &m.mesh;
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .collect();
        // The first non-finite vector of a list read from `keyword` lines, as an error.
        let finite = |vectors: &[Vec3], keyword: &str, what| match first_non_finite(vectors) {
            Some((index, value)) => Err(SceneError::NonFinite {
                path: path.to_owned(),
                line: find_non_finite_line(&text, keyword),
                object: m.name.clone(),
                what,
                index,
                value,
            }),
            None => Ok(()),
        };
        finite(&positions, "v", "vertex")?;
        let normals: Vec<Vec3> = mesh.normals.chunks_exact(3).map(Vec3::from_slice).collect();
        finite(&normals, "vn", "normal")?;
        let triangles = triples(&mesh.indices);
        // Normals are used only when every corner of the group names one (tobj invents the
        // missing ones); zero-length ones fall back to flat.
        let smooth = agree
            && scanned[k].all_normals
            && !normals.is_empty()
            && mesh.normal_indices.len() == mesh.indices.len()
            && normals.iter().all(|n| n.length_squared() > 0.0);
        let (normals, normal_indices) = if smooth {
            (
                normals.iter().map(|n| n.normalize()).collect(),
                triples(&mesh.normal_indices),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        // Texture coordinates (OBJ `vt`, v up) are kept only when every corner of the group
        // names one and all are finite: the lightmap bake may take them as its atlas.
        let texcoords: Vec<glam::Vec2> = mesh
            .texcoords
            .chunks_exact(2)
            .map(glam::Vec2::from_slice)
            .collect();
        let keep_uv = scanned.get(k).is_some_and(|s| s.all_texcoords)
            && !texcoords.is_empty()
            && mesh.texcoord_indices.len() == mesh.indices.len()
            && texcoords.iter().all(|t| t.is_finite());
        let (texcoords, texcoord_indices) = if keep_uv {
            (texcoords, triples(&mesh.texcoord_indices))
        } else {
            (Vec::new(), Vec::new())
        };
        out.push(ObjModel {
            name: m.name,
            mesh: ShapeMesh {
                positions,
                triangles,
                normals,
                normal_indices,
                texcoords,
                texcoord_indices,
            },
            material: mesh.material_id,
            usemtl: scanned.get(k).and_then(|s| s.usemtl.clone()),
        });
    }
    if out.is_empty() {
        return Err(SceneError::Input {
            path: path.to_owned(),
            problem: "the OBJ has no faces (`f` statements with 3 or more corners)".into(),
        });
    }
    Ok(ObjFile {
        models: out,
        materials,
        origins,
        mtllibs,
        missing_mtl,
    })
}

/// Checks every statement tobj would accept loosely or drop silently, with its line, and
/// follows tobj's grouping (a new model at `o`/`g`, or at `usemtl` of another material, once
/// the current one has faces) to learn which groups name a normal at every corner.
fn scan(
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
                let name = line.split_once(' ').unwrap_or_default().1.trim();
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
fn push_model(models: &mut Vec<ScannedModel>, current: &mut ScannedModel) {
    let next = ScannedModel {
        triangles: 0,
        all_normals: true,
        all_texcoords: true,
        usemtl: current.usemtl.clone(),
    };
    let done = std::mem::replace(current, next);
    if done.triangles > 0 {
        models.push(done);
    }
}

/// Reads and checks an MTL library, expands one-value colours (`Kd r` means `Kd r r r`) and
/// has tobj parse the result. `Ok(None)` when the file does not exist.
fn load_mtl(
    path: &Path,
    policy: &ReadPolicy,
) -> Result<Option<(tobj::MTLLoadResult, Vec<MtlOrigin>)>, SceneError> {
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
    let result = tobj::load_mtl_buf(&mut std::io::Cursor::new(normalized.as_bytes()));
    if let Err(source) = &result {
        return Err(SceneError::Statement {
            path: path.to_owned(),
            line: 1,
            problem: format!("cannot load MTL: {source}"),
        });
    }
    Ok(Some((result, origins)))
}

/// A triangulated group's flat index list (positions, normals or texture coordinates) as one
/// triple per triangle.
fn triples(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

fn first_non_finite(v: &[Vec3]) -> Option<(usize, f32)> {
    v.iter().enumerate().find_map(|(i, p)| {
        p.to_array()
            .into_iter()
            .find(|c| !c.is_finite())
            .map(|c| (i, c))
    })
}

/// The 1-based line of the first `keyword` statement holding a non-finite number.
fn find_non_finite_line(text: &str, keyword: &str) -> Option<usize> {
    text.lines().enumerate().find_map(|(i, l)| {
        let mut it = l.split_whitespace();
        (it.next() == Some(keyword) && it.any(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite())))
            .then_some(i + 1)
    })
}

/// The 1-based line tobj most likely failed on: the first statement of the kind its error
/// names that does not parse (tobj reports no position).
fn find_bad_line(text: &str, err: tobj::LoadError) -> Option<usize> {
    use tobj::LoadError as E;
    let (mut nv, mut nvt, mut nvn) = (0i64, 0i64, 0i64);
    let index_ok = |s: &str, n: i64| {
        s.parse::<i64>()
            .is_ok_and(|i| (1..=n).contains(&i) || (-n..=-1).contains(&i))
    };
    let floats = |it: std::str::SplitWhitespace, min: usize, max: usize| {
        let v: Vec<&str> = it.collect();
        (min..=max).contains(&v.len()) && v.iter().all(|w| w.parse::<f32>().is_ok())
    };
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        let bad = match it.next() {
            Some("v") => {
                nv += 1;
                matches!(err, E::PositionParseError | E::ColorParseError) && !floats(it, 3, 7)
            }
            Some("vt") => {
                nvt += 1;
                matches!(err, E::TexcoordParseError) && !floats(it, 1, 3)
            }
            Some("vn") => {
                nvn += 1;
                matches!(err, E::NormalParseError) && !floats(it, 3, 3)
            }
            Some("f") => {
                let corners: Vec<&str> = it.collect();
                let face_err = matches!(
                    err,
                    E::FaceParseError
                        | E::InvalidPolygon
                        | E::FaceVertexOutOfBounds
                        | E::FaceTexCoordOutOfBounds
                        | E::FaceNormalOutOfBounds
                );
                face_err
                    && (corners.len() < 3
                        || !corners.iter().all(|c| {
                            let parts: Vec<&str> = c.split('/').collect();
                            parts.len() <= 3
                                && index_ok(parts[0], nv)
                                && parts
                                    .get(1)
                                    .is_none_or(|t| t.is_empty() || index_ok(t, nvt))
                                && parts
                                    .get(2)
                                    .is_none_or(|n| n.is_empty() || index_ok(n, nvn))
                        }))
            }
            _ => false,
        };
        if bad {
            return Some(i + 1);
        }
    }
    None
}

/// The MTL material as one of ours, its emission (Ke), and warnings for what was clamped or
/// ignored. Mapping: `Kd` -> diffuse; `Ks` > 0 with `Ns` -> classic Blinn-Phong (the MTL
/// specification's illumination models 2 and up use (N.H)^Ns); `illum` 4, 6, 7 with `Ni` ->
/// smooth dielectric; `illum` 3 or 5 with `Ks` -> mirror of reflectance `Ks`; `Ke` -> emitted
/// radiance. Reflectances >= 1 are clamped to 0.999 with a warning.
pub(crate) fn convert_material(
    m: &tobj::Material,
    origin: Option<&MtlOrigin>,
    obj: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(Material, Rgb), SceneError> {
    let mtl_err = |key: &str, problem: String| SceneError::MtlMaterial {
        path: origin.map_or_else(|| obj.to_owned(), |o| o.path.clone()),
        line: origin.map(|o| o.line_of(key)),
        material: m.name.clone(),
        problem,
    };
    let clamp = |key: &'static str, v: [f32; 3], max: f32, w: &mut Vec<Warning>| {
        Rgb::from_array(v.map(|c| {
            let to = if c.is_nan() { 0.0 } else { c.clamp(0.0, max) };
            if to != c {
                w.push(Warning::MtlClamped {
                    path: obj.to_owned(),
                    material: m.name.clone(),
                    key,
                    from: c,
                    to,
                });
            }
            to
        }))
    };
    let diffuse = clamp("Kd", m.diffuse.unwrap_or([0.5; 3]), 0.999, warnings);
    let specular = clamp("Ks", m.specular.unwrap_or([0.0; 3]), 1.0, warnings);
    let emission = Rgb::from_array(m.emissive.unwrap_or([0.0; 3]));
    for (channel, value) in emission.to_array().into_iter().enumerate() {
        if !value.is_finite() {
            return Err(mtl_err(
                "Ke",
                format!("Ke channel {channel} is not finite ({value})"),
            ));
        }
        if value < 0.0 {
            return Err(mtl_err(
                "Ke",
                format!("Ke channel {channel} is negative ({value} W/(m^2 sr))"),
            ));
        }
    }
    let mut ignored: Vec<String> = m.unknown_param.keys().cloned().collect();
    for (key, present) in [
        ("map_Ka", m.ambient_texture.is_some()),
        ("map_Kd", m.diffuse_texture.is_some()),
        ("map_Ks", m.specular_texture.is_some()),
        ("map_Bump", m.normal_texture.is_some()),
        ("map_Ns", m.shininess_texture.is_some()),
        ("map_d", m.dissolve_texture.is_some()),
        ("d", m.dissolve.is_some_and(|d| d < 1.0)),
    ] {
        if present {
            ignored.push(key.to_owned());
        }
    }
    if !ignored.is_empty() {
        ignored.sort();
        warnings.push(Warning::MtlIgnored {
            path: obj.to_owned(),
            material: m.name.clone(),
            keys: ignored,
        });
    }
    let illum = m.illumination_model.unwrap_or(2);
    let material = match (illum, m.optical_density) {
        (4 | 6 | 7, Some(ni)) if ni != 1.0 => Material::dielectric(ni),
        (3 | 5, _) if specular.max_element() > 0.0 => Material::mirror(specular),
        _ if illum >= 2 && specular.max_element() > 0.0 => {
            Material::blinn_phong(BlinnPhongParams {
                diffuse,
                specular,
                exponent: m.shininess.unwrap_or(0.0).clamp(0.0, 1e6),
                normalized: false,
            })
        }
        _ => Material::lambert(diffuse),
    }
    .map_err(|source| mtl_err("newmtl", source.to_string()))?;
    Ok((material, emission))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Loads `obj` (and `mtl` as `m.mtl`) from a scratch folder.
    fn load_text(name: &str, obj: &str, mtl: &str) -> ObjFile {
        let dir = std::env::temp_dir().join(format!("twopass-obj-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m.mtl"), mtl).unwrap();
        std::fs::write(dir.join("x.obj"), obj).unwrap();
        let file = load(&dir.join("x.obj"), &ReadPolicy::default()).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        file
    }

    #[test]
    fn groups_are_smooth_only_when_every_corner_names_a_normal() {
        // Group a: all corners have normals. Group b: none, while the file has normals (tobj
        // would invent them). Then a material change splits b's faces into a third model, and
        // a face with normals on some corners only (group c) stays flat.
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\n\
                   g a\nf 1//1 2//1 3//1\n\
                   g b\nusemtl red\nf 2 4 3\nusemtl blue\nf 1 2 4\n\
                   g c\nf 1//1 2 3//1\n";
        let mtl = "newmtl red\nKd 0.5 0 0\nnewmtl blue\nKd 0 0 0.5\n";
        let file = load_text("smooth", obj, mtl);
        let smooth: Vec<(&str, bool)> = file
            .models
            .iter()
            .map(|m| (m.name.as_str(), !m.mesh.normal_indices.is_empty()))
            .collect();
        assert_eq!(
            smooth,
            [("a", true), ("b", false), ("b", false), ("c", false)]
        );
        let materials: Vec<Option<usize>> = file.models.iter().map(|m| m.material).collect();
        assert_eq!(materials, [None, Some(0), Some(1), Some(1)]);
        assert_eq!(file.models[1].usemtl.as_ref().map(|u| u.1), Some(10));
    }

    #[test]
    fn bad_lines_are_found() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 x\nf 1 2 3\n";
        assert_eq!(
            find_bad_line(text, tobj::LoadError::PositionParseError),
            Some(3)
        );
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
        assert_eq!(
            find_bad_line(text, tobj::LoadError::FaceVertexOutOfBounds),
            Some(5)
        );
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 -1 -3\nf 1 2\n";
        assert_eq!(
            find_bad_line(text, tobj::LoadError::FaceParseError),
            Some(5)
        );
        assert_eq!(find_non_finite_line("v 0 0 0\nv nan 0 0\n", "v"), Some(2));
    }
}
