//! Objects: each `[[object]]` of a scene file (a shape, a mesh file or a sphere, with its
//! material, emission and transform) turned into a part waiting to be meshed.

use std::path::Path;

use glam::Vec3;
use twopass_brdf::Rgb;

use super::loader::{Geometry, Loader, MAX_COORDINATE, Part, PlacedPart, in_range, rgb};
use crate::description::{ObjectDesc, ShapeDesc};
use crate::error::SceneError;
use crate::obj;
use crate::shape::{self};
use crate::transform::Transform;

/// One group of a mesh file an object read: the part it became and what its material would
/// be without the object's own (so that another object placing the file again resolves it
/// alike).
#[derive(Debug, Clone)]
pub(super) struct ObjModel {
    /// Index of its part in load order.
    part: usize,
    /// The group's name.
    group: String,
    /// Its MTL material's name, for `material_map`.
    mtl_name: Option<String>,
    /// Its MTL material's id and emission, when the library loaded.
    mtl: Option<(u32, Rgb)>,
}

impl Loader {
    pub(super) fn shape_err(&self, line: usize, object: &str, problem: String) -> SceneError {
        SceneError::Shape {
            path: self.path.clone(),
            line,
            object: object.to_owned(),
            problem,
        }
    }

    pub(super) fn object(
        &mut self,
        o: &ObjectDesc,
        line: usize,
        parts: &mut Vec<PlacedPart>,
    ) -> Result<(), SceneError> {
        let name = o.name.as_str();
        let t = &o.transform;
        let transform = Transform::new(
            t.scale.map_or(Vec3::ONE, |s| Vec3::from_array(s.get())),
            &t.rotate
                .iter()
                .map(|r| (Vec3::from_array(r.axis), r.degrees))
                .collect::<Vec<_>>(),
            t.translate.map_or(Vec3::ZERO, Vec3::from_array),
        )
        .map_err(|p| self.shape_err(line, name, p))?;
        let emission = match o.emission {
            None => None,
            Some(e) => Some(self.emission(rgb(e), name, Some(line))?),
        };
        let lookup = |ld: &mut Self, material: &str| match ld.material_ids.get(material) {
            Some(&id) => Ok(ld.use_material(id)),
            None => Err(SceneError::UnknownMaterial {
                path: ld.path.clone(),
                line,
                object: name.to_owned(),
                material: material.to_owned(),
            }),
        };
        let fixed = |ld: &mut Self| match &o.material {
            Some(m) => lookup(ld, m),
            None => Err(ld.shape_err(line, name, "needs a `material`".into())),
        };
        let v3 = Vec3::from_array;
        // Every coordinate as written, finite and within range, before any arithmetic on it.
        // Each entry: the key as written, what a non-finite value is called (the key's
        // component, or the polygon's vertex), and the three numbers.
        let written: Vec<(&'static str, &'static str, [f32; 3])> = match &o.shape {
            ShapeDesc::Quad {
                origin,
                edge_u,
                edge_v,
            } => vec![
                ("origin", "`origin` component", *origin),
                ("edge_u", "`edge_u` component", *edge_u),
                ("edge_v", "`edge_v` component", *edge_v),
            ],
            ShapeDesc::Polygon { vertices } => vertices
                .iter()
                .map(|v| ("vertices", "polygon vertex", *v))
                .collect(),
            ShapeDesc::Box { min, max } => vec![
                ("min", "`min` component", *min),
                ("max", "`max` component", *max),
            ],
            ShapeDesc::Sphere { center, radius, .. } => vec![
                ("center", "`center` component", *center),
                ("radius", "`radius`", [*radius; 3]),
            ],
            ShapeDesc::Obj { .. } => Vec::new(),
        };
        for (entry, (key, what, v)) in written.into_iter().enumerate() {
            if let Some(component) = v.iter().position(|c| !c.is_finite()) {
                return Err(SceneError::NonFinite {
                    path: self.path.clone(),
                    line: Some(line),
                    object: name.to_owned(),
                    what,
                    // The polygon's vertex, or the component of a point.
                    index: if key == "vertices" { entry } else { component },
                    value: v[component],
                });
            }
            if let Some(c) = v.iter().find(|c| !in_range(**c)) {
                return Err(SceneError::Range {
                    path: self.path.clone(),
                    line: Some(line),
                    object: name.to_owned(),
                    problem: format!(
                        "`{key}` value {c:e} is outside the supported range of +-{MAX_COORDINATE:e} scene units"
                    ),
                });
            }
        }
        let geometry = match &o.shape {
            ShapeDesc::Quad { origin, edge_u, edge_v } => shape::quad(v3(*origin), v3(*edge_u), v3(*edge_v)),
            ShapeDesc::Polygon { vertices } => {
                shape::polygon(&vertices.iter().map(|v| v3(*v)).collect::<Vec<_>>())
            }
            ShapeDesc::Box { min, max } => shape::cuboid(v3(*min), v3(*max)),
            ShapeDesc::Sphere {
                center,
                radius,
                subdivisions,
            } => {
                if !(radius.is_finite() && *radius > 0.0 && v3(*center).is_finite()) {
                    return Err(self.shape_err(line, name, format!("sphere radius {radius} must be finite and > 0, centre finite")));
                }
                if let Some(s) = subdivisions.filter(|&s| s > shape::MAX_SUBDIVISIONS) {
                    return Err(self.shape_err(line, name, format!("sphere subdivisions {s} must be at most {}", shape::MAX_SUBDIVISIONS)));
                }
                let material = fixed(self)?;
                parts.push(PlacedPart {
                    part: Part {
                        name: name.to_owned(),
                        line: Some(line),
                        geometry: Geometry::Sphere {
                            center: v3(*center),
                            radius: *radius,
                            subdivisions: *subdivisions,
                        },
                        material,
                        emission: emission.unwrap_or(Rgb::ZERO),
                    },
                    transform,
                });
                return Ok(());
            }
            ShapeDesc::Obj { file } => {
                let obj_path = self.path.parent().unwrap_or(Path::new(".")).join(file);
                let in_object = |e: SceneError| SceneError::InObject {
                    path: self.path.clone(),
                    line,
                    object: name.to_owned(),
                    source: Box::new(e),
                };
                // A mesh file an earlier object read is placed again, not read again: each of
                // its groups becomes a copy of that object's part ([`crate::Repeat`]).
                if let Some(models) = self.obj_parts.get(&obj_path).cloned() {
                    let single = models.len() == 1;
                    for m in models {
                        let (material, mtl_emission) = match (&o.material, m.mtl_name.as_ref().and_then(|n| o.material_map.get(n))) {
                            (Some(over), _) => (lookup(self, over)?, Rgb::ZERO),
                            (None, Some(mapped)) => (lookup(self, mapped)?, Rgb::ZERO),
                            (None, None) => match m.mtl {
                                Some((id, e)) => (self.use_material(id), e),
                                None => return Err(self.shape_err(line, name, format!(
                                    "OBJ group `{}` in {} has no material of its own; give the object a `material`",
                                    m.group,
                                    obj_path.display()
                                ))),
                            },
                        };
                        parts.push(PlacedPart {
                            part: Part {
                                name: if single { name.to_owned() } else { format!("{name}/{}", m.group) },
                                line: Some(line),
                                geometry: Geometry::Copy { of: m.part },
                                material,
                                emission: emission.unwrap_or(mtl_emission),
                            },
                            transform,
                        });
                    }
                    return Ok(());
                }
                let loaded = obj::load(&obj_path, &self.policy).map_err(in_object)?;
                let needs_mtl = (o.material.is_none()
                    && (!loaded.mtllibs.is_empty() || loaded.models.iter().any(|m| m.material.is_some())))
                    || !o.material_map.is_empty();
                let mtl = match (&loaded.materials, needs_mtl) {
                    (Ok(m), _) => self.mtl_materials(m, &loaded.origins, &obj_path).map_err(|e| SceneError::InObject {
                        path: self.path.clone(),
                        line,
                        object: name.to_owned(),
                        source: Box::new(e),
                    })?,
                    (Err(source), true) => {
                        return Err(SceneError::InObject {
                            path: self.path.clone(),
                            line,
                            object: name.to_owned(),
                            source: Box::new(SceneError::MissingMtl {
                                path: obj_path.clone(),
                                mtl: loaded.missing_mtl.clone().or_else(|| loaded.mtllibs.first().cloned()),
                                source: *source,
                            }),
                        });
                    }
                    (Err(_), false) => Vec::new(),
                };
                let single = loaded.models.len() == 1;
                let mut models = Vec::with_capacity(loaded.models.len());
                for m in loaded.models {
                    let mtl_name = m.material.and_then(|i| loaded.materials.as_ref().ok()?.get(i)).map(|x| x.name.clone());
                    models.push(ObjModel {
                        part: parts.len(),
                        group: m.name.clone(),
                        mtl_name: mtl_name.clone(),
                        mtl: m.material.and_then(|i| mtl.get(i)).copied(),
                    });
                    let (material, mtl_emission) = match (&o.material, mtl_name.as_ref().and_then(|n| o.material_map.get(n))) {
                        (Some(over), _) => (lookup(self, over)?, Rgb::ZERO),
                        (None, Some(mapped)) => (lookup(self, mapped)?, Rgb::ZERO),
                        (None, None) => match m.material.and_then(|i| mtl.get(i)) {
                            Some(&(id, e)) => (self.use_material(id), e),
                            None => {
                                let why = match &m.usemtl {
                                    Some((mtl, at)) => format!(
                                        "uses MTL material `{mtl}` ({}:{at}) but the OBJ names no material library that loads",
                                        obj_path.display()
                                    ),
                                    None => "has no material (no `usemtl`)".to_owned(),
                                };
                                return Err(self.shape_err(line, name, format!(
                                    "OBJ group `{}` in {} {why}; give the object a `material`",
                                    m.name,
                                    obj_path.display()
                                )));
                            }
                        },
                    };
                    parts.push(PlacedPart {
                        part: Part {
                            name: if single { name.to_owned() } else { format!("{name}/{}", m.name) },
                            line: Some(line),
                            geometry: Geometry::Mesh(m.mesh),
                            material,
                            emission: emission.unwrap_or(mtl_emission),
                        },
                        transform,
                    });
                }
                self.obj_parts.insert(obj_path, models);
                return Ok(());
            }
        }
        .map_err(|p| self.shape_err(line, name, p))?;
        let material = fixed(self)?;
        parts.push(PlacedPart {
            part: Part {
                name: name.to_owned(),
                line: Some(line),
                geometry: Geometry::Mesh(geometry),
                material,
                emission: emission.unwrap_or(Rgb::ZERO),
            },
            transform,
        });
        Ok(())
    }

    pub(super) fn emission(
        &self,
        e: Rgb,
        object: &str,
        line: Option<usize>,
    ) -> Result<Rgb, SceneError> {
        for (channel, value) in e.to_array().into_iter().enumerate() {
            if !value.is_finite() {
                return Err(SceneError::NonFinite {
                    path: self.path.clone(),
                    line,
                    object: object.to_owned(),
                    what: "emission channel",
                    index: channel,
                    value,
                });
            }
            if value < 0.0 {
                return Err(SceneError::NegativeEmission {
                    path: self.path.clone(),
                    line,
                    object: object.to_owned(),
                    channel,
                    value,
                });
            }
        }
        Ok(e)
    }
}
