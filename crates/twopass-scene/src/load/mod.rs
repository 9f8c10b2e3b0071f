//! Loading: a TOML scene file or a bare OBJ, validated once, into a [`Scene`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use toml::Spanned;
use twopass_brdf::{
    BlinnPhongParams, ComplexIor, CookTorranceParams, FresnelModel, Material, PhongParams, Rgb,
};

use crate::accel::triangle_normal;
use crate::camera::Camera;
use crate::description::{
    CameraDesc, FresnelDesc, MaterialDesc, ObjectDesc, SceneFile, ShapeDesc, Triple, VERSION,
};
use crate::camera::CameraProblem;
use crate::error::{SceneError, Warning};
use crate::input::{self, InputKind, LineIndex, ReadPolicy, printable};
use crate::obj;
use crate::scene::{Bounds, Mesh, Object, Scene, SceneMaterial};
use crate::shape::{self, ShapeMesh};
use crate::transform::Transform;

/// Chord error allowed when a sphere's tessellation is chosen from its size, as a fraction of
/// the scene's bounding-box diagonal.
pub const SPHERE_TOLERANCE: f32 = 2e-4;

/// Largest magnitude of a world coordinate, scene units. Ray queries run in f32: the
/// watertight triangle test forms products of three coordinates relative to the ray origin
/// (up to (2e12)^3 = 8e36 here, below f32's 3.4e38), and the BVH's quantized boxes fail from
/// about 1e19. Positions beyond this are refused at load with the object and the value; a scene
/// in this range renders the same image at any scale (checked at 1e9 times the Cornell box).
pub const MAX_COORDINATE: f32 = 1e12;

/// Most triangles of a scene, counted before any sphere is built (a sphere by its icosphere
/// level, 20 * 4^level): 50 million hold about 5 GB with the BVH.
pub const MAX_TRIANGLES: u64 = 50_000_000;

/// Largest emitted power of one object per channel, pi * L_e * area (W in scene units). Sums
/// over emitters and the estimators' intermediate products need headroom below f32's 3.4e38,
/// so a brighter object is refused at load rather than rendered as infinities dropped to black.
pub const MAX_EMITTED_POWER: f64 = 1e34;

/// Loads a scene: a `.toml` scene file, or a bare `.obj` mesh (framed by a default camera, with
/// its MTL materials or a default grey). Returns the scene and the recoverable problems found.
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
        return Err(SceneError::Version {
            path: path.to_owned(),
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
        check_range(path, None, &m.name, &m.mesh.positions)?;
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
                line: None,
                geometry: Geometry::Mesh(m.mesh),
                material,
                emission,
            },
            transform: Transform::default(),
        });
    }
    // Frame the bounds: look down -z at the centre from far enough to see the bounding sphere.
    let bounds = parts
        .iter()
        .fold(Bounds::EMPTY, |b, p| match &p.part.geometry {
            Geometry::Mesh(m) => m.positions.iter().fold(b, |b, q| b.grow(*q)),
            Geometry::Sphere { .. } => b,
        });
    let fov_y = 40f32.to_radians();
    let radius = (bounds.diagonal() * 0.5).max(f32::MIN_POSITIVE);
    let distance = radius / (fov_y * 0.5).sin() * 1.1;
    let center = if bounds.diagonal() > 0.0 {
        bounds.center()
    } else {
        Vec3::ZERO
    };
    let camera = Camera::look_at(
        center + Vec3::Z * distance,
        center,
        Vec3::Y,
        fov_y,
        512,
        512,
    )
    .map_err(|problem| SceneError::Camera {
        path: path.to_owned(),
        line: None,
        problem,
    })?;
    // A bare OBJ states no unit: metres, as the OBJ format's readers assume by default.
    ld.finish(parts, camera, crate::unit::Unit::Metre)
}

/// What an object becomes before meshing: spheres wait for the scene's size.
enum Geometry {
    Mesh(ShapeMesh),
    Sphere {
        center: Vec3,
        radius: f32,
        subdivisions: Option<u32>,
    },
}

struct Part {
    name: String,
    line: Option<usize>,
    geometry: Geometry,
    material: u32,
    emission: Rgb,
}

struct PlacedPart {
    part: Part,
    transform: Transform,
}

struct Loader {
    path: PathBuf,
    lines: LineIndex,
    policy: ReadPolicy,
    warnings: Vec<Warning>,
    materials: Vec<SceneMaterial>,
    material_ids: HashMap<String, u32>,
    used: Vec<bool>,
}

/// For "unknown field `k`" inside a typed table (whose span covers the whole table), the offset
/// of the key `k` itself at or after `from`, so the error points at the offending line.
fn unknown_key_offset(text: &str, from: usize, message: &str) -> Option<usize> {
    let key = message.strip_prefix("unknown field `")?.split('`').next()?;
    let rest = text.get(from..)?;
    rest.match_indices(key)
        .find(|&(i, _)| {
            let before = rest[..i].chars().next_back();
            let after = rest[i + key.len()..].trim_start();
            before.is_none_or(|c| c.is_whitespace() || c == '{' || c == ',')
                && after.starts_with('=')
        })
        .map(|(i, _)| from + i)
}

/// Whether a coordinate is finite and within [`MAX_COORDINATE`].
fn in_range(c: f32) -> bool {
    c.abs() <= MAX_COORDINATE
}

/// Refuses positions beyond [`MAX_COORDINATE`] (and non-finite ones), naming the object.
fn check_range(
    path: &Path,
    line: Option<usize>,
    object: &str,
    positions: &[Vec3],
) -> Result<(), SceneError> {
    for (index, p) in positions.iter().enumerate() {
        if let Some(&value) = p.to_array().iter().find(|c| !in_range(**c)) {
            return Err(SceneError::Range {
                path: path.to_owned(),
                line,
                object: object.to_owned(),
                problem: format!(
                    "vertex {index} at {p} has coordinate {value:e}, outside the supported range of +-{MAX_COORDINATE:e} scene units"
                ),
            });
        }
    }
    Ok(())
}

fn rgb(t: Triple) -> Rgb {
    Rgb::from_array(t.get())
}

impl Loader {
    fn line<T>(&self, s: &Spanned<T>) -> usize {
        self.lines.line_col(s.span().start).0
    }

    fn add_material(&mut self, name: String, material: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.material_ids.insert(name.clone(), id);
        // Names reach terminals and output files: control characters are stored escaped.
        self.materials.push(SceneMaterial {
            name: printable(&name),
            material,
        });
        self.used.push(false);
        id
    }

    fn use_material(&mut self, id: u32) -> u32 {
        self.used[id as usize] = true;
        id
    }

    fn default_material(&mut self) -> u32 {
        const NAME: &str = "(default grey)";
        let id = match self.material_ids.get(NAME) {
            Some(&id) => id,
            None => {
                let grey = Material::lambert(Rgb::splat(0.5)).expect("0.5 is a valid reflectance");
                self.add_material(NAME.to_owned(), grey)
            }
        };
        self.use_material(id)
    }

    fn material(&self, desc: &MaterialDesc, line: usize) -> Result<Material, SceneError> {
        let name = desc.name();
        let spec_err = |problem: &str| SceneError::MaterialSpec {
            path: self.path.clone(),
            line,
            material: name.to_owned(),
            problem: problem.to_owned(),
        };
        let ior_of = |conductor: &Option<String>, ior: &Option<Triple>, k: &Option<Triple>| match (
            conductor, ior,
        ) {
            (Some(c), None) if k.is_none() => ComplexIor::conductor(c).ok_or_else(|| {
                let known: Vec<&str> = twopass_brdf::ior::CONDUCTORS
                    .iter()
                    .map(|c| c.name)
                    .collect();
                spec_err(&format!(
                    "unknown conductor `{c}` (known: {})",
                    known.join(", ")
                ))
            }),
            (None, Some(n)) => Ok(ComplexIor {
                n: rgb(*n),
                k: k.map_or(Rgb::ZERO, rgb),
            }),
            (Some(_), _) => Err(spec_err(
                "give either `conductor` or `ior` (with `k`), not both",
            )),
            (None, None) => Err(spec_err(
                "needs `conductor` (a measured metal) or `ior` (and `k`)",
            )),
        };
        let built = match desc {
            MaterialDesc::Lambert { diffuse, .. } => Material::lambert(rgb(*diffuse)),
            // Bound by their symbols in the text: rho, k_s, k_a, n.
            MaterialDesc::Phong {
                diffuse: rho,
                specular: ks,
                ambient: ka,
                exponent: n,
                normalized,
                ..
            } => Material::phong(PhongParams {
                ambient: ka.map_or(rgb(*rho), rgb),
                diffuse: rgb(*rho),
                specular: rgb(*ks),
                exponent: *n,
                normalized: *normalized,
            }),
            MaterialDesc::BlinnPhong {
                diffuse: rho,
                specular: ks,
                exponent: n,
                normalized,
                ..
            } => Material::blinn_phong(BlinnPhongParams {
                diffuse: rgb(*rho),
                specular: rgb(*ks),
                exponent: *n,
                normalized: *normalized,
            }),
            MaterialDesc::CookTorrance {
                diffuse,
                specular,
                roughness,
                conductor,
                ior,
                k,
                fresnel,
                ..
            } => Material::cook_torrance(CookTorranceParams {
                diffuse: rgb(*diffuse),
                specular: rgb(*specular),
                roughness: *roughness,
                ior: ior_of(conductor, ior, k)?,
                fresnel: match fresnel {
                    FresnelDesc::Exact => FresnelModel::Exact,
                    FresnelDesc::Schlick => FresnelModel::Schlick,
                },
            }),
            MaterialDesc::Mirror { reflectance, .. } => Material::mirror(rgb(*reflectance)),
            MaterialDesc::Dielectric { ior, .. } => Material::dielectric(*ior),
            MaterialDesc::Conductor {
                conductor, ior, k, ..
            } => Material::conductor(ior_of(conductor, ior, k)?),
        };
        built.map_err(|source| SceneError::Material {
            path: self.path.clone(),
            line: Some(line),
            material: name.to_owned(),
            source,
        })
    }

    /// Converts every MTL material once; returns (material id, emission) per MTL index.
    fn mtl_materials(
        &mut self,
        mtl: &[tobj::Material],
        origins: &[obj::MtlOrigin],
        obj_path: &Path,
    ) -> Result<Vec<(u32, Rgb)>, SceneError> {
        let file = obj_path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        let mut out = Vec::with_capacity(mtl.len());
        for (i, m) in mtl.iter().enumerate() {
            let (material, emission) =
                obj::convert_material(m, origins.get(i), obj_path, &mut self.warnings)?;
            let name = format!("{file}:{}", m.name);
            let id = match self.material_ids.get(&name) {
                Some(&id) => id,
                None => self.add_material(name, material),
            };
            out.push((id, emission));
        }
        Ok(out)
    }

    fn shape_err(&self, line: usize, object: &str, problem: String) -> SceneError {
        SceneError::Shape {
            path: self.path.clone(),
            line,
            object: object.to_owned(),
            problem,
        }
    }

    fn object(
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
                for m in loaded.models {
                    let mtl_name = m.material.and_then(|i| loaded.materials.as_ref().ok()?.get(i)).map(|x| x.name.clone());
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

    fn emission(&self, e: Rgb, object: &str, line: Option<usize>) -> Result<Rgb, SceneError> {
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

    fn camera(&mut self, c: &Spanned<CameraDesc>) -> Result<Camera, SceneError> {
        let line = self.line(c);
        let err = |problem| SceneError::Camera {
            path: self.path.clone(),
            line: Some(line),
            problem,
        };
        let d = c.get_ref();
        let [w, h] = d.resolution;
        if w == 0 || h == 0 {
            return Err(SceneError::Toml {
                path: self.path.clone(),
                line,
                column: 1,
                message: format!("camera resolution {w} x {h} must be at least 1 x 1"),
            });
        }
        Camera::check_resolution(u64::from(w), u64::from(h)).map_err(err)?;
        for (key, v) in [("position", d.position), ("look_at", d.look_at)] {
            if let Some(c) = v.iter().find(|c| !in_range(**c)) {
                return Err(SceneError::Toml {
                    path: self.path.clone(),
                    line,
                    column: 1,
                    message: format!(
                        "camera `{key}` value {c:e} is not finite or outside the supported range of +-{MAX_COORDINATE:e} scene units"
                    ),
                });
            }
        }
        let fov_y = match (d.fov_y, d.focal_length) {
            (Some(_), Some(_)) => return Err(err(CameraProblem::FovAndFocalLength)),
            (Some(f), None) => f.to_radians(),
            (None, focal) => {
                let focal = focal.unwrap_or(50.0);
                let [fw, fh] = d.film_size.unwrap_or([36.0, 24.0]);
                for v in [focal, fw, fh] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(err(CameraProblem::Lens(v)));
                    }
                }
                let (film, image) = (fw / fh, w as f32 / h as f32);
                if (film / image - 1.0).abs() > 0.01 {
                    self.warnings.push(Warning::FilmAspect {
                        path: self.path.clone(),
                        film,
                        image,
                    });
                }
                2.0 * (0.5 * fh / focal).atan()
            }
        };
        Camera::look_at(
            Vec3::from_array(d.position),
            Vec3::from_array(d.look_at),
            Vec3::from_array(d.up),
            fov_y,
            w,
            h,
        )
        .map_err(err)
    }

    /// Meshes the parts (spheres from the scene's size), validates the triangles, builds the scene.
    fn finish(
        mut self,
        parts: Vec<PlacedPart>,
        camera: Camera,
        unit: crate::unit::Unit,
    ) -> Result<(Scene, Vec<Warning>), SceneError> {
        let mut bounds = Bounds::EMPTY;
        for p in &parts {
            match &p.part.geometry {
                Geometry::Mesh(m) => {
                    for q in &m.positions {
                        bounds = bounds.grow(p.transform.point(*q));
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
                    Geometry::Mesh(_) => None,
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
        let triangles: u64 = parts
            .iter()
            .zip(&levels)
            .map(|(p, level)| match (&p.part.geometry, level) {
                (Geometry::Mesh(m), _) => m.triangles.len() as u64,
                (_, Some(l)) => 20u64 << (2 * l),
                (_, None) => 0,
            })
            .sum();
        if triangles > MAX_TRIANGLES {
            return Err(SceneError::Input {
                path: self.path.clone(),
                problem: format!(
                    "the scene would have {triangles} triangles, more than the {MAX_TRIANGLES} loaded at most (give fewer spheres or lower their `subdivisions`)"
                ),
            });
        }
        let mut mesh = Mesh::default();
        let mut objects = Vec::with_capacity(parts.len());
        for (PlacedPart { part, transform }, level) in parts.into_iter().zip(levels) {
            let local = match part.geometry {
                Geometry::Mesh(m) => m,
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
            self.push(
                &mut mesh,
                &mut objects,
                part.name,
                part.line,
                local,
                &transform,
                part.material,
                part.emission,
            )?;
        }
        if mesh.triangles.is_empty() {
            return Err(SceneError::EmptyScene { path: self.path });
        }
        if objects
            .iter()
            .all(|o: &Object| o.emission.max_element() <= 0.0)
        {
            self.warnings.push(Warning::NoEmitters {
                path: self.path.clone(),
            });
        }
        Ok((
            Scene::assemble(self.path, unit, mesh, self.materials, objects, camera),
            self.warnings,
        ))
    }

    /// Appends one object: transforms it, checks every number, drops degenerate triangles.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        mesh: &mut Mesh,
        objects: &mut Vec<Object>,
        name: String,
        line: Option<usize>,
        local: ShapeMesh,
        transform: &Transform,
        material: u32,
        emission: Rgb,
    ) -> Result<(), SceneError> {
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
                return Err(SceneError::Range {
                    path: self.path.clone(),
                    line,
                    object: name,
                    problem: format!(
                        "vertex {index} lands at {q} in the world, outside the supported range of +-{MAX_COORDINATE:e} scene units"
                    ),
                });
            }
            mesh.positions.push(q);
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
        let (mut dropped, mut first) = (0, 0);
        for (i, tri) in local.triangles.iter().enumerate() {
            let mut t = tri.map(|v| v + base);
            let mut nt = if smooth {
                local.normal_indices[i].map(|n| n + normal_base)
            } else {
                [0; 3]
            };
            let mut uv = has_uv.then(|| local.texcoord_indices[i].map(|k| k + uv_base));
            if transform.flips {
                t.swap(1, 2);
                nt.swap(1, 2);
                if let Some(uv) = &mut uv {
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
            let n = n.as_vec3();
            if !smooth {
                nt = [mesh.normals.len() as u32; 3];
                mesh.normals.push(n);
            }
            mesh.triangles.push(t);
            mesh.normal_indices.push(nt);
            mesh.texcoord_indices.push(uv);
            mesh.geometric_normals.push(n);
            mesh.areas.push((0.5 * twice_area) as f32);
            mesh.triangle_object.push(object);
        }
        let kept = mesh.triangles.len() as u32 - tri_start;
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
        // The power this object emits, pi * L_e * area, must stay far inside f32.
        if emission.max_element() > 0.0 {
            let area: f64 = mesh.areas[tri_start as usize..]
                .iter()
                .map(|&a| f64::from(a))
                .sum();
            let power = f64::from(emission.max_element()) * std::f64::consts::PI * area;
            if power.is_nan() || power > MAX_EMITTED_POWER {
                return Err(SceneError::Range {
                    path: self.path.clone(),
                    line,
                    object: name,
                    problem: format!(
                        "emitted power pi * L_e * area = {power:e} W (scene units) exceeds the {MAX_EMITTED_POWER:e} W the renderers represent; lower the emission or the scene's scale"
                    ),
                });
            }
        }
        objects.push(Object {
            name: printable(&name),
            material,
            emission,
            triangles: tri_start..tri_start + kept,
            vertices: base..mesh.positions.len() as u32,
        });
        Ok(())
    }
}
