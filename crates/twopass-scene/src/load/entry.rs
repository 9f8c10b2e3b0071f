//! The entry points: a scene file (TOML) or a bare OBJ read from disk or given as text, read
//! within a [`ReadPolicy`]'s bounds and handed to the [`Loader`].

use std::collections::HashMap;
use std::path::Path;

use twopass_brdf::Rgb;

use super::loader::{
    Geometry, Loader, Part, PlacedPart, check_range, framing_camera, unknown_key_offset,
};
use crate::description::{SceneFile, VERSION};
use crate::error::{SceneError, Warning};
use crate::input::{self, InputKind, LineIndex, ReadPolicy};
use crate::obj;
use crate::scene::{Bounds, Scene};
use crate::transform::Transform;

/// Loads a scene: a `.toml` scene file, a bare `.obj` mesh (framed by a default camera, with
/// its MTL materials or a default grey), or a glTF 2.0 file (`.gltf` or `.glb`: its default
/// scene's node hierarchy, materials and first camera; the module docs of `load::gltf` give
/// the mapping). Returns the scene and the recoverable problems found.
/// Any path the scene names is read (see [`load_with`] to confine reads).
pub fn load(path: impl AsRef<Path>) -> Result<(Scene, Vec<Warning>), SceneError> {
    load_with(path, &ReadPolicy::unconfined())
}

/// [`load`] under a [`ReadPolicy`]: with [`ReadPolicy::confined`], meshes and material
/// libraries outside the scene's folder are refused.
pub fn load_with(
    path: impl AsRef<Path>,
    policy: &ReadPolicy,
) -> Result<(Scene, Vec<Warning>), SceneError> {
    let path = path.as_ref();
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("toml") => {
            let text = input::read_text(path, InputKind::Scene, policy)?;
            load_toml_with(&text, path, policy)
        }
        Some("obj") => load_bare_obj(path, policy),
        Some("gltf" | "glb") => super::gltf::load_gltf(path, policy),
        _ => Err(SceneError::UnsupportedFormat {
            path: path.to_owned(),
        }),
    }
}

/// Loads a TOML scene from `text`, as if read from `path` (relative mesh paths resolve against
/// its folder; errors name it).
pub fn load_toml(text: &str, path: &Path) -> Result<(Scene, Vec<Warning>), SceneError> {
    load_toml_with(text, path, &ReadPolicy::unconfined())
}

/// [`load_toml`] under a [`ReadPolicy`] for the meshes and libraries the scene names.
pub fn load_toml_with(
    text: &str,
    path: &Path,
    policy: &ReadPolicy,
) -> Result<(Scene, Vec<Warning>), SceneError> {
    let lines = LineIndex::new(text);
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let start = e.span().map_or(0, |s| s.start);
        let start = unknown_key_offset(text, start, e.message()).unwrap_or(start);
        let (line, column) = lines.line_col(start);
        SceneError::Toml {
            path: path.to_owned(),
            line,
            column,
            message: e.message().to_owned(),
        }
    })?;
    if file.version != VERSION {
        let line = text
            .lines()
            .position(|l| {
                l.trim_start()
                    .strip_prefix("version")
                    .is_some_and(|rest| rest.trim_start().starts_with('='))
            })
            .map_or(1, |i| i + 1);
        return Err(SceneError::Version {
            path: path.to_owned(),
            line,
            found: file.version,
            supported: VERSION,
        });
    }
    let mut ld = Loader {
        path: path.to_owned(),
        lines,
        policy: policy.clone(),
        warnings: Vec::new(),
        materials: Vec::new(),
        material_ids: HashMap::new(),
        used: Vec::new(),
        textures: Vec::new(),
        texture_ids: HashMap::new(),
        lamps: Vec::new(),
        sky: None,
        obj_parts: HashMap::new(),
    };
    let mut material_lines = Vec::new();
    for m in &file.materials {
        let line = ld.line(m);
        let name = m.get_ref().name().to_owned();
        if ld.material_ids.contains_key(&name) {
            return Err(SceneError::DuplicateName {
                path: ld.path.clone(),
                line,
                kind: "material",
                name,
            });
        }
        let material = ld.material(m.get_ref(), line)?;
        ld.add_material(name, material);
        material_lines.push(line);
    }
    let mut parts = Vec::new();
    let mut names = HashMap::new();
    for o in &file.objects {
        let line = ld.line(o);
        if names.insert(o.get_ref().name.clone(), line).is_some() {
            return Err(SceneError::DuplicateName {
                path: ld.path.clone(),
                line,
                kind: "object",
                name: o.get_ref().name.clone(),
            });
        }
        ld.object(o.get_ref(), line, &mut parts)?;
    }
    for (i, l) in file.lights.iter().enumerate() {
        let line = ld.line(l);
        let lamp = ld.lamp(l.get_ref(), line, i + 1)?;
        ld.lamps.push(lamp);
    }
    ld.sky = ld.sky(file.sky.as_ref(), &file.portals)?;
    for (i, line) in material_lines.into_iter().enumerate() {
        if !ld.used[i] {
            ld.warnings.push(Warning::UnusedMaterial {
                path: ld.path.clone(),
                line,
                material: ld.materials[i].name.clone(),
            });
        }
    }
    let camera = ld.camera(&file.camera)?;
    ld.finish(parts, camera, file.unit)
}

fn load_bare_obj(path: &Path, policy: &ReadPolicy) -> Result<(Scene, Vec<Warning>), SceneError> {
    let mut ld = Loader {
        path: path.to_owned(),
        lines: LineIndex::new(""),
        policy: policy.clone(),
        warnings: Vec::new(),
        materials: Vec::new(),
        material_ids: HashMap::new(),
        used: Vec::new(),
        textures: Vec::new(),
        texture_ids: HashMap::new(),
        lamps: Vec::new(),
        sky: None,
        obj_parts: HashMap::new(),
    };
    let file = obj::load(path, policy)?;
    let materials = match &file.materials {
        Ok(m) => ld.mtl_materials(m, &file.origins, path)?,
        Err(_) => Vec::new(),
    };
    if let Some(mtl) = &file.missing_mtl {
        ld.warnings.push(Warning::MissingMtl {
            path: path.to_owned(),
            mtl: Some(mtl.clone()),
        });
    }
    for m in &file.models {
        check_range(path, file.range_line, &m.name, &m.mesh.positions)?;
    }
    // Every vertex at one point: every triangle is degenerate. Said of the triangles, with
    // their lines, before a camera is made up to frame a point.
    let collapsed = file
        .models
        .iter()
        .flat_map(|m| m.mesh.positions.iter())
        .fold(Bounds::EMPTY, |b, q| b.grow(*q))
        .diagonal()
        == 0.0;
    if let Some(m) = file.models.first().filter(|_| collapsed) {
        return Err(SceneError::DegenerateObject {
            path: path.to_owned(),
            line: m.first_face,
            object: m.name.clone(),
            triangles: m.mesh.triangles.len(),
        });
    }
    let mut parts = Vec::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for m in file.models {
        let (material, emission) = match m.material.and_then(|i| materials.get(i)) {
            Some(&(id, e)) => (id, e),
            None => (ld.default_material(), Rgb::ZERO),
        };
        let count = seen.entry(m.name.clone()).or_default();
        *count += 1;
        let name = if *count == 1 {
            m.name
        } else {
            format!("{}#{}", m.name, count)
        };
        parts.push(PlacedPart {
            part: Part {
                name,
                // A group's refusals (every triangle degenerate, emission too strong) point
                // at its first face.
                line: m.first_face,
                geometry: Geometry::Mesh(m.mesh),
                material,
                emission,
            },
            transform: Transform::default(),
        });
    }
    let camera = framing_camera(path, &parts)?;
    // A bare OBJ states no unit: metres, as the OBJ format's readers assume by default.
    ld.finish(parts, camera, crate::unit::Unit::Metre)
}
