//! The loader's state while a scene is read (its materials, warnings, parts waiting to be
//! meshed), the load limits, and the checks every part shares.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use toml::Spanned;
use twopass_brdf::{Material, Rgb};

use crate::camera::Camera;
use crate::description::Triple;
use crate::error::{SceneError, Warning};
use crate::input::{LineIndex, ReadPolicy, printable};
use crate::scene::{Bounds, SceneMaterial};
use crate::shape::ShapeMesh;
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

/// Most triangles of a scene counting every placed copy of an instanced mesh (copies are not
/// stored, but each is a surface of its own to the passes, which keep data per triangle).
pub const MAX_PLACED_TRIANGLES: u64 = 1_000_000_000;

/// Largest emitted power of one object per channel, pi * L_e * area (W in scene units). Sums
/// over emitters and the estimators' intermediate products need headroom below f32's 3.4e38,
/// so a brighter object is refused at load rather than rendered as infinities dropped to black.
pub const MAX_EMITTED_POWER: f64 = 1e34;

/// What an object becomes before meshing: spheres wait for the scene's size.
pub(super) enum Geometry {
    Mesh(ShapeMesh),
    /// Another placement of the mesh of part `of` (an earlier part, a `Mesh`): a glTF mesh
    /// that several nodes show. Stored once and placed again ([`crate::Repeat`]).
    Copy {
        of: usize,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        subdivisions: Option<u32>,
    },
}

pub(super) struct Part {
    pub(super) name: String,
    pub(super) line: Option<usize>,
    pub(super) geometry: Geometry,
    pub(super) material: u32,
    pub(super) emission: Rgb,
}

pub(super) struct PlacedPart {
    pub(super) part: Part,
    pub(super) transform: Transform,
}

pub(super) struct Loader {
    pub(super) path: PathBuf,
    pub(super) lines: LineIndex,
    pub(super) policy: ReadPolicy,
    pub(super) warnings: Vec<Warning>,
    pub(super) materials: Vec<SceneMaterial>,
    pub(super) material_ids: HashMap<String, u32>,
    pub(super) used: Vec<bool>,
    /// The textures decoded so far, and their index by source (a file's path, a glTF image).
    pub(super) textures: Vec<crate::texture::Texture>,
    pub(super) texture_ids: HashMap<String, u32>,
    /// The lamps read so far.
    pub(super) lamps: Vec<crate::lamp::Lamp>,
    /// The sky, when the file has one.
    pub(super) sky: Option<crate::sky::Sky>,
    /// The mesh files objects have read, by path: each group's part, so that another object
    /// naming the file places those parts again instead of reading and storing it again.
    pub(super) obj_parts: HashMap<PathBuf, Vec<super::objects::ObjModel>>,
}

/// For "unknown field `k`" inside a typed table (whose span covers the whole table), the offset
/// of the key `k` itself at or after `from`, so the error points at the offending line.
pub(super) fn unknown_key_offset(text: &str, from: usize, message: &str) -> Option<usize> {
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
pub(super) fn in_range(c: f32) -> bool {
    c.abs() <= MAX_COORDINATE
}

/// Refuses positions beyond [`MAX_COORDINATE`] (and non-finite ones), naming the object.
pub(super) fn check_range(
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

/// The camera of a scene that names none (a bare OBJ, a glTF without a camera): a 40 degree
/// vertical field of view, 512 x 512 pixels, looking down -z at the centre of the parts' world
/// bounds from far enough (1.1 times) that their bounding sphere fills the view.
pub(super) fn framing_camera(path: &Path, parts: &[PlacedPart]) -> Result<Camera, SceneError> {
    let bounds = parts
        .iter()
        .fold(Bounds::EMPTY, |b, p| match &p.part.geometry {
            Geometry::Mesh(m) => m
                .positions
                .iter()
                .fold(b, |b, q| b.grow(p.transform.point(*q))),
            Geometry::Copy { of } => match &parts[*of].part.geometry {
                Geometry::Mesh(m) => m
                    .positions
                    .iter()
                    .fold(b, |b, q| b.grow(p.transform.point(*q))),
                _ => b,
            },
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
    Camera::look_at(
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
    })
}

pub(super) fn rgb(t: Triple) -> Rgb {
    Rgb::from_array(t.get())
}

impl Loader {
    pub(super) fn line<T>(&self, s: &Spanned<T>) -> usize {
        self.lines.line_col(s.span().start).0
    }

    pub(super) fn add_material(&mut self, name: String, material: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.material_ids.insert(name.clone(), id);
        // Names reach terminals and output files: control characters are stored escaped.
        self.materials.push(SceneMaterial {
            name: printable(&name),
            material,
            albedo_texture: None,
        });
        self.used.push(false);
        id
    }

    pub(super) fn use_material(&mut self, id: u32) -> u32 {
        self.used[id as usize] = true;
        id
    }

    pub(super) fn default_material(&mut self) -> u32 {
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
}
