//! Assembling the scene: every part meshed (spheres from the scene's size), transformed and
//! checked, degenerate triangles dropped, the accelerator built over the result.

use std::collections::HashMap;

use glam::{Affine3A, Mat4, Vec3};
use twopass_brdf::Rgb;

use super::coincident::{Coincident, Seen, corner_key};
use super::loader::{
    Geometry, Loader, MAX_COORDINATE, MAX_EMITTED_POWER, MAX_PLACED_TRIANGLES, MAX_TRIANGLES,
    PlacedPart, SPHERE_TOLERANCE, in_range,
};
use crate::accel::triangle_normal;
use crate::camera::Camera;
use crate::error::{SceneError, Warning};
use crate::input::printable;
use crate::mesh::StoredSpans;
use crate::scene::{Bounds, Mesh, Object, Scene};
use crate::shape::{self, ShapeMesh};
use crate::transform::Transform;

impl Loader {
    /// Meshes the parts (spheres from the scene's size), validates the triangles, builds the scene.
    pub(super) fn finish(
        self,
        parts: Vec<PlacedPart>,
        camera: Camera,
        unit: crate::unit::Unit,
    ) -> Result<(Scene, Vec<Warning>), SceneError> {
        self.finish_parts(parts, camera, unit)
            .map(|(scene, warnings, _)| (scene, warnings))
    }

    /// [`finish`](Self::finish), also saying which parts became objects: a part whose every
    /// triangle repeats an earlier object's is removed (the scene's objects are the kept
    /// parts, in order).
    pub(super) fn finish_parts(
        mut self,
        parts: Vec<PlacedPart>,
        camera: Camera,
        unit: crate::unit::Unit,
    ) -> Result<(Scene, Vec<Warning>, Vec<bool>), SceneError> {
        let mut bounds = Bounds::EMPTY;
        for p in &parts {
            match &p.part.geometry {
                Geometry::Mesh(m) => {
                    for q in &m.positions {
                        bounds = bounds.grow(p.transform.point(*q));
                    }
                }
                Geometry::Copy { of } => {
                    if let Geometry::Mesh(m) = &parts[*of].part.geometry {
                        for q in &m.positions {
                            bounds = bounds.grow(p.transform.point(*q));
                        }
                    }
                }
                Geometry::Sphere { center, radius, .. } => {
                    for corner in 0..8 {
                        let s = Vec3::new(
                            if corner & 1 == 0 { -1.0 } else { 1.0 },
                            if corner & 2 == 0 { -1.0 } else { 1.0 },
                            if corner & 4 == 0 { -1.0 } else { 1.0 },
                        );
                        let q = p.transform.point(*center + s * *radius);
                        if !q.to_array().into_iter().all(in_range) {
                            return Err(SceneError::Range {
                                path: self.path.clone(),
                                line: p.part.line,
                                object: p.part.name.clone(),
                                problem: format!(
                                    "the sphere reaches {q} in the world, outside the supported range of +-{MAX_COORDINATE:e} scene units"
                                ),
                            });
                        }
                        bounds = bounds.grow(q);
                    }
                }
            }
        }
        let tolerance = SPHERE_TOLERANCE * bounds.diagonal();
        // Each sphere's icosphere level, from its world radius (at most the largest axis scale
        // times the radius) unless given; level l has 20 * 4^l triangles. The whole scene's
        // count is checked before any sphere is built.
        let levels: Vec<Option<u32>> =
            parts
                .iter()
                .map(|p| match &p.part.geometry {
                    Geometry::Mesh(_) | Geometry::Copy { .. } => None,
                    Geometry::Sphere {
                        radius,
                        subdivisions,
                        ..
                    } => {
                        let scale = p.transform.matrix.to_scale_rotation_translation().0;
                        let world_radius = radius * scale.abs().max_element();
                        Some(subdivisions.unwrap_or_else(|| {
                            shape::sphere_subdivisions_for(world_radius, tolerance)
                        }))
                    }
                })
                .collect();
        let count =
            |p: &PlacedPart, level: &Option<u32>, copies: bool| match (&p.part.geometry, level) {
                (Geometry::Mesh(m), _) => m.triangles.len() as u64,
                (Geometry::Copy { of }, _) if copies => match &parts[*of].part.geometry {
                    Geometry::Mesh(m) => m.triangles.len() as u64,
                    _ => 0,
                },
                (_, Some(l)) => 20u64 << (2 * l),
                (_, None) => 0,
            };
        // Stored triangles bound the memory; placed ones (copies counted) the passes' work.
        let limits = [
            (
                true,
                MAX_PLACED_TRIANGLES,
                "place",
                " (instanced copies counted)",
                "place fewer copies",
            ),
            (
                false,
                MAX_TRIANGLES,
                "have",
                "",
                "give fewer spheres or lower their `subdivisions`",
            ),
        ];
        for (copies, limit, verb, counted, advice) in limits {
            let n: u64 = parts
                .iter()
                .zip(&levels)
                .map(|(p, l)| count(p, l, copies))
                .sum();
            if n > limit {
                return Err(SceneError::Input {
                    path: self.path.clone(),
                    problem: format!(
                        "the scene would {verb} {n} triangles{counted}, more than the {limit} loaded at most ({advice})"
                    ),
                });
            }
        }
        let mut mesh = Mesh::default();
        let mut objects = Vec::with_capacity(parts.len());
        let mut coincident = Coincident::default();
        let mut kept = Vec::with_capacity(parts.len());
        // The parts later parts copy (glTF meshes several nodes show): their shapes, the spans
        // of what they stored (when they stored every triangle) and their transforms.
        let mut copied: Vec<Option<Source>> = parts.iter().map(|_| None::<Source>).collect();
        for p in &parts {
            if let Geometry::Copy { of } = p.part.geometry {
                copied[of] = Some(Source::default());
            }
        }
        // Each source's placements so far, by matrix: a copy in the same place as another adds
        // no surface.
        let mut placements: HashMap<(usize, [u32; 16]), usize> = HashMap::new();
        for (index, (PlacedPart { part, transform }, level)) in
            parts.into_iter().zip(levels).enumerate()
        {
            coincident.begin(&part.name, part.line);
            let local = match part.geometry {
                Geometry::Mesh(m) => m,
                Geometry::Copy { of } => {
                    let source = copied[of]
                        .as_ref()
                        .expect("a copy's source comes before it");
                    let key = |m: &Mat4| m.to_cols_array().map(f32::to_bits);
                    let here = (of, key(&transform.matrix));
                    if let Some(&earlier) = placements.get(&here) {
                        let triangles = source.spans.as_ref().map_or_else(
                            || source.shape.triangles.len(),
                            |s| (s.triangles.end - s.triangles.start) as usize,
                        );
                        coincident.whole_copy(earlier, triangles);
                        kept.push(false);
                        continue;
                    }
                    placements.insert(here, index);
                    if let Some(spans) = &source.spans {
                        let to_world =
                            transform.matrix.as_dmat4() * source.matrix.as_dmat4().inverse();
                        let to_world = Affine3A::from_mat4(to_world.as_mat4());
                        self.push_copy(
                            &mut mesh,
                            &mut objects,
                            spans,
                            to_world,
                            part.name,
                            part.line,
                            part.material,
                            part.emission,
                        )?;
                        kept.push(true);
                        continue;
                    }
                    // The source lost triangles to earlier objects' copies: what it stored is
                    // not its whole mesh, so this placement stores its own.
                    source.shape.clone()
                }
                Geometry::Sphere { center, radius, .. } => {
                    shape::sphere(center, radius, level.unwrap_or(0)).map_err(|p| {
                        SceneError::Shape {
                            path: self.path.clone(),
                            line: part.line.unwrap_or(1),
                            object: part.name.clone(),
                            problem: p,
                        }
                    })?
                }
            };
            let shape = copied[index].is_some().then(|| local.clone());
            let (normals, texcoords) = (mesh.normals.len() as u32, mesh.texcoords.len() as u32);
            let object = self.push(
                &mut mesh,
                &mut objects,
                &mut coincident,
                part.name,
                part.line,
                local,
                &transform,
                part.material,
                part.emission,
            )?;
            if let (Some(shape), Some(source)) = (shape, copied[index].as_mut()) {
                placements.insert(
                    (index, transform.matrix.to_cols_array().map(f32::to_bits)),
                    index,
                );
                // Stored whole (no triangle went to an earlier object's copy): its copies
                // repeat what it stored.
                source.spans = objects
                    .last()
                    .filter(|_| object && !coincident.part_had_copies())
                    .map(|o| StoredSpans {
                        triangles: o.triangles.clone(),
                        vertices: o.vertices.clone(),
                        normals: normals..mesh.normals.len() as u32,
                        texcoords: texcoords..mesh.texcoords.len() as u32,
                    });
                source.shape = shape;
                source.matrix = transform.matrix;
            }
            kept.push(object);
        }
        // The sources' shapes are not needed once every copy is placed.
        drop(copied);
        if let Some(w) = coincident.warning(self.path.clone()) {
            self.warnings.push(w);
        }
        if mesh.triangles.is_empty() {
            return Err(SceneError::EmptyScene { path: self.path });
        }
        if !mesh.albedo_uvs.is_empty() {
            mesh.albedo_uvs.resize(mesh.triangles.len(), None);
        }
        if objects
            .iter()
            .all(|o: &Object| o.emission.max_element() <= 0.0)
            && self.lamps.iter().all(|l| l.intensity.max_element() <= 0.0)
            && self.sky.is_none()
        {
            self.warnings.push(Warning::NoEmitters {
                path: self.path.clone(),
            });
        }
        let mut scene = Scene::assemble(
            self.path,
            unit,
            mesh,
            self.materials,
            objects,
            self.lamps,
            camera,
        );
        scene.textures = self.textures;
        scene.sky = self.sky;
        Ok((scene, self.warnings, kept))
    }

    /// Appends a placed copy of a stored object (`source`, moved by `to_world` from its
    /// world place) as an object of its own, checking where its vertices land and what it
    /// emits as [`push`](Self::push) does.
    #[allow(clippy::too_many_arguments)]
    fn push_copy(
        &mut self,
        mesh: &mut Mesh,
        objects: &mut Vec<Object>,
        source: &StoredSpans,
        to_world: Affine3A,
        name: String,
        line: Option<usize>,
        material: u32,
        emission: Rgb,
    ) -> Result<(), SceneError> {
        let triangles = mesh.push_repeat(source, to_world, objects.len() as u32);
        let vertices = mesh.repeats.last().map_or(0..0, |r| r.vertices.clone());
        for (index, v) in vertices.clone().enumerate() {
            let q = mesh.position(v);
            if !q.is_finite() || !q.to_array().into_iter().all(in_range) {
                return Err(self.outside(line, name, index, q));
            }
        }
        if emission.max_element() > 0.0 {
            let area: f64 = triangles.clone().map(|t| f64::from(mesh.area(t))).sum();
            self.check_power(emission, area, line, &name)?;
        }
        objects.push(Object {
            name: printable(&name),
            material,
            emission,
            triangles,
            vertices,
        });
        Ok(())
    }

    /// The error for vertex `index` of object `name` landing at `q`, outside the range.
    fn outside(&self, line: Option<usize>, name: String, index: usize, q: Vec3) -> SceneError {
        SceneError::Range {
            path: self.path.clone(),
            line,
            object: name,
            problem: format!(
                "vertex {index} lands at {q} in the world, outside the supported range of +-{MAX_COORDINATE:e} scene units"
            ),
        }
    }

    /// Refuses an object whose emitted power, pi * L_e * `area`, leaves the range f32 holds.
    fn check_power(
        &self,
        emission: Rgb,
        area: f64,
        line: Option<usize>,
        name: &str,
    ) -> Result<(), SceneError> {
        let power = f64::from(emission.max_element()) * std::f64::consts::PI * area;
        if power.is_nan() || power > MAX_EMITTED_POWER {
            return Err(SceneError::Range {
                path: self.path.clone(),
                line,
                object: name.to_owned(),
                problem: format!(
                    "emitted power pi * L_e * area = {power:e} W (scene units) exceeds the {MAX_EMITTED_POWER:e} W the renderers represent; lower the emission or the scene's scale"
                ),
            });
        }
        Ok(())
    }

    /// Appends one object: transforms it, checks every number, drops degenerate triangles and
    /// copies of triangles kept before (`coincident`, the whole scene's). Returns whether the
    /// object was kept: one whose every triangle repeats an earlier object's is not.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push(
        &mut self,
        mesh: &mut Mesh,
        objects: &mut Vec<Object>,
        coincident: &mut Coincident,
        name: String,
        line: Option<usize>,
        local: ShapeMesh,
        transform: &Transform,
        material: u32,
        emission: Rgb,
    ) -> Result<bool, SceneError> {
        let base = mesh.positions.len() as u32;
        let tri_start = mesh.triangles.len() as u32;
        for (index, p) in local.positions.iter().enumerate() {
            let q = transform.point(*p);
            if let Some(value) = p
                .to_array()
                .into_iter()
                .chain(q.to_array())
                .find(|c| !c.is_finite())
            {
                return Err(SceneError::NonFinite {
                    path: self.path.clone(),
                    line,
                    object: name,
                    what: "vertex",
                    index,
                    value,
                });
            }
            if !q.to_array().into_iter().all(in_range) {
                return Err(self.outside(line, name, index, q));
            }
            mesh.positions.push(q);
        }
        if local.source_vertices.len() == local.positions.len() {
            mesh.source_vertices
                .extend_from_slice(&local.source_vertices);
        } else {
            mesh.source_vertices.extend(0..local.positions.len() as u32);
        }
        let normal_base = mesh.normals.len() as u32;
        let smooth = !local.normal_indices.is_empty();
        mesh.normals
            .extend(local.normals.iter().map(|n| transform.normal(*n)));
        let object = objects.len() as u32;
        let uv_base = mesh.texcoords.len() as u32;
        let has_uv = local.texcoord_indices.len() == local.triangles.len();
        if has_uv {
            mesh.texcoords.extend_from_slice(&local.texcoords);
        }
        let textured = self.materials[material as usize].albedo_texture.is_some();
        let albedo_uvs = textured && local.albedo_uvs.len() == local.triangles.len();
        if textured && !albedo_uvs {
            self.warnings.push(Warning::Texture {
                path: self.path.clone(),
                line,
                at: format!("object `{}`", printable(&name)),
                problem: format!(
                    "material `{}` has a base colour texture, but the object has no texture coordinates for it: its factor alone is the albedo",
                    self.materials[material as usize].name
                ),
            });
        }
        if textured {
            mesh.albedo_uvs.resize(tri_start as usize, None);
        }
        let (mut dropped, mut first) = (0, 0);
        // Exact copies of a triangle kept before (the same three world corners, bit for bit, in
        // the same cyclic order), in this object or an earlier one, are dropped: a repeated
        // face is a common export glitch, and a copy adds no surface (see `coincident`).
        let mut copies: Option<(usize, usize)> = None;
        let mut copied = 0;
        for (i, tri) in local.triangles.iter().enumerate() {
            let mut t = tri.map(|v| v + base);
            let mut nt = if smooth {
                local.normal_indices[i].map(|n| n + normal_base)
            } else {
                [0; 3]
            };
            let mut uv = has_uv.then(|| local.texcoord_indices[i].map(|k| k + uv_base));
            let mut albedo_uv = albedo_uvs.then(|| local.albedo_uvs[i]);
            if transform.flips {
                t.swap(1, 2);
                nt.swap(1, 2);
                if let Some(uv) = &mut uv {
                    uv.swap(1, 2);
                }
                if let Some(uv) = &mut albedo_uv {
                    uv.swap(1, 2);
                }
            }
            let Some((twice_area, n)) = triangle_normal(t.map(|v| mesh.positions[v as usize]))
            else {
                if dropped == 0 {
                    first = i;
                }
                dropped += 1;
                continue;
            };
            match coincident.see(corner_key(t.map(|v| mesh.positions[v as usize])), i) {
                Seen::New => {}
                Seen::InObject(original) => {
                    copies.get_or_insert((i, original));
                    copied += 1;
                    continue;
                }
                Seen::Earlier => continue,
            }
            let n = n.as_vec3();
            if !smooth {
                nt = [mesh.normals.len() as u32; 3];
                mesh.normals.push(n);
            }
            mesh.triangles.push(t);
            mesh.normal_indices.push(nt);
            mesh.flat.push(!smooth);
            mesh.texcoord_indices.push(uv);
            if textured {
                mesh.albedo_uvs.push(albedo_uv);
            }
            mesh.geometric_normals.push(n);
            mesh.areas.push((0.5 * twice_area) as f32);
            mesh.triangle_object.push(object);
        }
        let kept = mesh.triangles.len() as u32 - tri_start;
        if kept == 0 && coincident.part_had_copies() {
            // Nothing of its own: the object is the copy of earlier ones, and goes with the
            // vertices, normals and texture coordinates it appended.
            mesh.positions.truncate(base as usize);
            mesh.normals.truncate(normal_base as usize);
            mesh.texcoords.truncate(uv_base as usize);
            coincident.remove_part();
            return Ok(false);
        }
        if kept == 0 {
            return Err(SceneError::DegenerateObject {
                path: self.path.clone(),
                line,
                object: name,
                triangles: local.triangles.len(),
            });
        }
        if dropped > 0 {
            self.warnings.push(Warning::DegenerateTriangles {
                path: self.path.clone(),
                object: name.clone(),
                dropped,
                first,
            });
        }
        if let Some((first, original)) = copies {
            self.warnings.push(Warning::DuplicateTriangles {
                path: self.path.clone(),
                object: name.clone(),
                dropped: copied,
                first,
                original,
            });
        }
        // The power this object emits, pi * L_e * area, must stay far inside f32.
        if emission.max_element() > 0.0 {
            let area: f64 = mesh.areas[tri_start as usize..]
                .iter()
                .map(|&a| f64::from(a))
                .sum();
            self.check_power(emission, area, line, &name)?;
        }
        objects.push(Object {
            name: printable(&name),
            material,
            emission,
            triangles: tri_start..tri_start + kept,
            vertices: base..mesh.positions.len() as u32,
        });
        Ok(true)
    }
}

/// A part that later parts copy: its shape (for a copy that must store its own), what it
/// stored when it stored every triangle, and its transform.
#[derive(Default)]
struct Source {
    shape: ShapeMesh,
    spans: Option<StoredSpans>,
    matrix: Mat4,
}
