//! Reading an OBJ file and its MTL libraries through tobj, within the read policy's bounds,
//! with the file and line context tobj does not give.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::lines::{
    find_bad_line, find_non_finite_line, find_value_line, first_non_finite, triples,
};
use super::model::{MtlLib, ObjFile, ObjModel};
use super::mtl::{MtlMaterials, load_mtl};
use super::normalize::normalize;
use super::scan::scan;
use crate::error::SceneError;
use crate::input::{self, InputKind, ReadPolicy};
use crate::shape::ShapeMesh;

pub(crate) fn load(path: &Path, policy: &ReadPolicy) -> Result<ObjFile, SceneError> {
    let text = input::read_text(path, InputKind::Obj, policy)?;
    // An empty parent joins to the bare name, which is how the user wrote it.
    let dir = path.parent().unwrap_or(Path::new(""));
    // The libraries, in the order tobj asks for them. tobj takes the rest of an `mtllib` line
    // as one file name; the OBJ format lists several, separated by spaces. So a line names
    // one library when a file of that whole name exists, else one per word, and tobj's
    // request for the line gets their materials merged (later ones win, as between lines).
    let mut libs: Vec<MtlLib> = Vec::new();
    let mut mtllibs = Vec::new();
    let mut missing_mtl = None;
    for (at, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.split_whitespace().next() != Some("mtllib") {
            continue;
        }
        let written = trimmed["mtllib".len()..].trim().to_owned();
        if written.is_empty() {
            continue;
        }
        let names: Vec<&str> = if dir.join(&written).is_file() {
            vec![written.as_str()]
        } else {
            written.split_whitespace().collect()
        };
        let mut merged: Option<MtlMaterials> = None;
        let mut origins = Vec::new();
        for name in names {
            let mtl_path = dir.join(name);
            mtllibs.push(mtl_path.clone());
            // A library refused before it is read (not a regular file, too large, outside the
            // confined folder) has no line of its own: the `mtllib` statement is where it is.
            let loaded = load_mtl(&mtl_path, policy).map_err(|e| match e {
                SceneError::Input { .. } | SceneError::Io { .. } => SceneError::Statement {
                    path: path.to_owned(),
                    line: at + 1,
                    problem: format!("mtllib: {e}"),
                },
                located => located,
            })?;
            match loaded {
                Some(((materials, map), found)) => {
                    let (all, all_map) = merged.get_or_insert_with(Default::default);
                    let offset = all.len();
                    for (name, i) in map {
                        all_map.insert(name, i + offset);
                    }
                    all.extend(materials);
                    origins.extend(found);
                }
                None => {
                    missing_mtl.get_or_insert(mtl_path);
                }
            }
        }
        libs.push(MtlLib {
            written,
            result: merged
                .map(|(materials, map)| (materials, map.into_iter().collect()))
                .ok_or(tobj::LoadError::OpenFileFailed),
            origins,
        });
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
    let mut scanned = scan(&text, path, &material_map, &mtllibs)?;

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
    let parsed = normalize(&text);
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(parsed.as_bytes()), &opts, loader).map_err(
            |source| SceneError::Obj {
                path: path.to_owned(),
                line: find_bad_line(&parsed, source),
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
        let m_positions = positions.len();
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
        // The same coordinates as a texture reads them (v down, glTF's convention).
        let albedo_uvs = texcoord_indices
            .iter()
            .map(|c| {
                c.map(|k| {
                    let t = texcoords[k as usize];
                    glam::Vec2::new(t.x, 1.0 - t.y)
                })
            })
            .collect();
        out.push(ObjModel {
            name: m.name,
            mesh: ShapeMesh {
                positions,
                triangles,
                normals,
                normal_indices,
                texcoords,
                texcoord_indices,
                albedo_uvs,
                // The OBJ `v` statement of each position, where the scan followed tobj's
                // groups and names as many positions as tobj made.
                source_vertices: scanned
                    .get_mut(k)
                    .filter(|s| agree && s.vertices.len() == m_positions)
                    .map(|s| std::mem::take(&mut s.vertices))
                    .unwrap_or_default(),
            },
            material: mesh.material_id,
            usemtl: scanned.get(k).and_then(|s| s.usemtl.clone()),
            first_face: scanned
                .get(k)
                .filter(|_| agree)
                .map(|s| s.first_face)
                .filter(|&l| l > 0),
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
        range_line: find_value_line(&text, "v", |c| c.abs() > crate::MAX_COORDINATE),
    })
}
