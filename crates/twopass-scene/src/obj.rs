//! Wavefront OBJ + MTL through tobj, with the file and line context tobj does not give, and
//! the mapping of MTL materials onto ours.

use std::path::{Path, PathBuf};

use glam::Vec3;
use twopass_brdf::{BlinnPhongParams, Material, Rgb};

use crate::error::{SceneError, Warning};
use crate::shape::ShapeMesh;

/// One OBJ group (tobj model) as a shape, with its MTL material index.
pub(crate) struct ObjModel {
    pub name: String,
    pub mesh: ShapeMesh,
    pub material: Option<usize>,
}

/// A loaded OBJ: its groups and its MTL materials (or why they failed).
pub(crate) struct ObjFile {
    pub models: Vec<ObjModel>,
    pub materials: Result<Vec<tobj::Material>, tobj::LoadError>,
    /// The `mtllib` files it names, resolved against its folder.
    pub mtllibs: Vec<PathBuf>,
}

pub(crate) fn load(path: &Path) -> Result<ObjFile, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|source| SceneError::Obj {
        path: path.to_owned(),
        line: find_bad_line(&text, source),
        source,
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mtllibs = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mtllib "))
        .map(|f| dir.join(f.trim()))
        .collect();
    let mut out = Vec::with_capacity(models.len());
    for m in models {
        let mesh = &m.mesh;
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .collect();
        if let Some((index, value)) = first_non_finite(&positions) {
            return Err(SceneError::NonFinite {
                path: path.to_owned(),
                line: find_non_finite_line(&text, "v"),
                object: m.name.clone(),
                what: "vertex",
                index,
                value,
            });
        }
        let normals: Vec<Vec3> = mesh.normals.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some((index, value)) = first_non_finite(&normals) {
            return Err(SceneError::NonFinite {
                path: path.to_owned(),
                line: find_non_finite_line(&text, "vn"),
                object: m.name.clone(),
                what: "normal",
                index,
                value,
            });
        }
        let triangles: Vec<[u32; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        // Normals are used only when every corner has one; zero-length ones fall back to flat.
        let smooth = !normals.is_empty()
            && mesh.normal_indices.len() == mesh.indices.len()
            && normals.iter().all(|n| n.length_squared() > 0.0);
        let (normals, normal_indices) = if smooth {
            (
                normals.iter().map(|n| n.normalize()).collect(),
                mesh.normal_indices
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            )
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
            },
            material: mesh.material_id,
        });
    }
    Ok(ObjFile {
        models: out,
        materials,
        mtllibs,
    })
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
    obj: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(Material, Rgb), SceneError> {
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
            return Err(SceneError::NonFinite {
                path: obj.to_owned(),
                line: None,
                object: m.name.clone(),
                what: "Ke channel",
                index: channel,
                value,
            });
        }
        if value < 0.0 {
            return Err(SceneError::NegativeEmission {
                path: obj.to_owned(),
                line: None,
                object: m.name.clone(),
                channel,
                value,
            });
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
    .map_err(|source| SceneError::Material {
        path: obj.to_owned(),
        line: None,
        material: m.name.clone(),
        source,
    })?;
    Ok((material, emission))
}

#[cfg(test)]
mod tests {
    use super::*;

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
