//! Errors and warnings of scene loading. Every variant carries the file and, where one exists,
//! the line (TOML span or OBJ line), the object or material, and the offending value, as fields.

use std::fmt;
use std::path::PathBuf;

use twopass_brdf::ParamError;

use crate::camera::CameraProblem;

/// A scene that cannot be loaded. Loading stops at the first error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file is missing or unreadable.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is neither a `.toml` scene, an `.obj` mesh nor a glTF (`.gltf`, `.glb`).
    #[error("{}: not a scene: expected a .toml scene file, an .obj mesh or a glTF 2.0 file (.gltf, .glb)", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// TOML syntax error, unknown key, missing key or wrong type.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Toml {
        /// The scene file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message (what is wrong and where in the structure).
        message: String,
    },
    /// The scene's `version` is not one this build reads.
    #[error("{}:{line}: scene version {found} is not supported (this build reads version {supported})", path.display())]
    Version {
        /// The scene file.
        path: PathBuf,
        /// Line of the `version` key (1 when the key is not found as written).
        line: usize,
        /// The version the file declares.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// Two materials or two objects share a name.
    #[error("{}:{line}: duplicate {kind} name `{name}`", path.display())]
    DuplicateName {
        /// The scene file.
        path: PathBuf,
        /// Line of the second definition.
        line: usize,
        /// `"material"` or `"object"`.
        kind: &'static str,
        /// The repeated name.
        name: String,
    },
    /// An object refers to a material that no `[[material]]` defines.
    #[error("{}:{line}: object `{object}` refers to unknown material `{material}`", path.display())]
    UnknownMaterial {
        /// The scene file.
        path: PathBuf,
        /// Line of the object.
        line: usize,
        /// The object's name.
        object: String,
        /// The missing material name.
        material: String,
    },
    /// A material parameter is out of range (reflectance outside [0, 1), zero roughness, ...).
    #[error("{}{}: material `{material}`: {source}", path.display(), line_suffix(*line))]
    Material {
        /// The scene or MTL file.
        path: PathBuf,
        /// Line of the material, when known.
        line: Option<usize>,
        /// The material's name.
        material: String,
        /// Which parameter and why.
        source: ParamError,
    },
    /// A material is inconsistent as a whole (for example neither `conductor` nor `ior`).
    #[error("{}:{line}: material `{material}`: {problem}", path.display())]
    MaterialSpec {
        /// The scene file.
        path: PathBuf,
        /// Line of the material.
        line: usize,
        /// The material's name.
        material: String,
        /// What is wrong.
        problem: String,
    },
    /// The OBJ file could not be parsed.
    #[error("{}{}: cannot load OBJ: {source}", path.display(), line_suffix(*line))]
    Obj {
        /// The OBJ file.
        path: PathBuf,
        /// The first offending line, when it could be found.
        line: Option<usize>,
        /// tobj's error.
        source: tobj::LoadError,
    },
    /// The OBJ names an MTL library that is missing or broken, and the scene relies on it.
    #[error("{}: material library {} cannot be loaded ({source}); give the object a `material` in the scene file or fix the library", path.display(), mtl.as_ref().map_or_else(|| "(unnamed)".to_owned(), |m| m.display().to_string()))]
    MissingMtl {
        /// The OBJ file.
        path: PathBuf,
        /// The MTL library it names, if any.
        mtl: Option<PathBuf>,
        /// tobj's error.
        source: tobj::LoadError,
    },
    /// A NaN or infinite number in geometry, a transform or emission.
    #[error("{}{}: object `{object}`: {what} {index} is not finite ({value})", path.display(), line_suffix(*line))]
    NonFinite {
        /// The scene or OBJ file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The object.
        object: String,
        /// What holds the value (`"vertex"`, `"normal"`, `"emission channel"`, ...).
        what: &'static str,
        /// Index of the vertex, normal or channel.
        index: usize,
        /// The offending value.
        value: f32,
    },
    /// Negative emitted radiance.
    #[error("{}{}: object `{object}`: emission channel {channel} is negative ({value} W/(m^2 sr))", path.display(), line_suffix(*line))]
    NegativeEmission {
        /// The scene or MTL file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The object (or MTL material).
        object: String,
        /// 0, 1 or 2 for R, G, B.
        channel: usize,
        /// The offending value.
        value: f32,
    },
    /// Every triangle of an object is degenerate (zero area), so the object has no surface.
    #[error("{}{}: object `{object}`: all {triangles} triangles are degenerate (zero area)", path.display(), line_suffix(*line))]
    DegenerateObject {
        /// The scene or OBJ file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The object.
        object: String,
        /// How many triangles it had.
        triangles: usize,
    },
    /// A built-in shape or transform with impossible parameters.
    #[error("{}:{line}: object `{object}`: {problem}", path.display())]
    Shape {
        /// The scene file.
        path: PathBuf,
        /// Line of the object.
        line: usize,
        /// The object.
        object: String,
        /// What is wrong.
        problem: String,
    },
    /// The camera cannot form an image.
    #[error("{}{}: camera: {problem}", path.display(), line_suffix(*line))]
    Camera {
        /// The scene file.
        path: PathBuf,
        /// Line of `[camera]`, when known.
        line: Option<usize>,
        /// What is wrong.
        problem: CameraProblem,
    },
    /// The scene has no triangles at all.
    #[error("{}: the scene has no surfaces", path.display())]
    EmptyScene {
        /// The scene file.
        path: PathBuf,
    },
    /// A file was refused before parsing: not a regular file, too large, not UTF-8, or outside
    /// the folder reads are confined to.
    #[error("{}: {problem}", path.display())]
    Input {
        /// The file.
        path: PathBuf,
        /// Why it was refused.
        problem: String,
    },
    /// A malformed statement in an OBJ or MTL file (a face with too few corners, an index out
    /// of range, a colour with the wrong number of values, ...).
    #[error("{}:{line}: {problem}", path.display())]
    Statement {
        /// The OBJ or MTL file.
        path: PathBuf,
        /// 1-based line of the statement.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// An MTL material that cannot be used (negative or non-finite emission, ...).
    #[error("{}{}: MTL material `{material}`: {problem}", path.display(), line_suffix(*line))]
    MtlMaterial {
        /// The MTL library.
        path: PathBuf,
        /// Line of the offending statement (or of `newmtl`), when known.
        line: Option<usize>,
        /// The MTL material's name.
        material: String,
        /// What is wrong.
        problem: String,
    },
    /// A number outside the range the engine represents: coordinates beyond
    /// [`crate::MAX_COORDINATE`], or emission whose power overflows single precision.
    #[error("{}{}: object `{object}`: {problem}", path.display(), line_suffix(*line))]
    Range {
        /// The scene or OBJ file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The object.
        object: String,
        /// Which value and the range it must lie in.
        problem: String,
    },
    /// A glTF file that cannot be read as a scene: a malformed document, a buffer that is
    /// missing or too short, an accessor out of its buffer, an index out of range, a NaN
    /// position. `at` locates it in the document (`node 2 \`Chair\`, mesh 1 \`Seat\`,
    /// primitive 0`, `buffer 0`, `the document`).
    #[error("{}: {at}: {problem}", path.display())]
    Gltf {
        /// The glTF file.
        path: PathBuf,
        /// Where in the document: the node, mesh and primitive (index and name), the buffer,
        /// accessor or camera.
        at: String,
        /// What is wrong.
        problem: String,
    },
    /// A material's base colour texture cannot be used: its file is missing or unreadable,
    /// it is not a PNG or JPEG, it is corrupt, or its header declares more pixels than are
    /// read ([`crate::MAX_TEXTURE_PIXELS`]).
    #[error("{}{}: material `{material}`: texture {texture}: {problem}", path.display(), line_suffix(*line))]
    Texture {
        /// The file naming the texture (the MTL library, the glTF file).
        path: PathBuf,
        /// Line of the statement naming it (an MTL's `map_Kd`), when there is one.
        line: Option<usize>,
        /// The material.
        material: String,
        /// The texture: its file, or the glTF image by index and name.
        texture: String,
        /// What is wrong.
        problem: String,
    },
    /// A `[[light]]` table that cannot be a lamp (a negative intensity, a zero direction, an
    /// outer cone angle below the inner one, ...).
    #[error("{}:{line}: light {index}{}: {problem}", path.display(), name.as_ref().map_or_else(String::new, |n| format!(" `{n}`")))]
    Light {
        /// The scene file.
        path: PathBuf,
        /// Line of the `[[light]]` table.
        line: usize,
        /// 1-based index of the table among the file's `[[light]]` tables.
        index: usize,
        /// Its `name`, when given.
        name: Option<String>,
        /// What is wrong.
        problem: String,
    },
    /// A `[sky]` or `[[portal]]` table that cannot be used (a turbidity outside the model's
    /// range, a zero direction, a degenerate portal, ...).
    #[error("{}:{line}: {table}: {problem}", path.display())]
    Sky {
        /// The scene file.
        path: PathBuf,
        /// Line of the table.
        line: usize,
        /// Which table: `sky`, or `portal N` (1-based).
        table: String,
        /// What is wrong, naming the key.
        problem: String,
    },
    /// An error in a file an object of the scene refers to (its OBJ mesh or MTL library),
    /// located at that object.
    #[error("{}:{line}: object `{object}`: {source}", path.display())]
    InObject {
        /// The scene file.
        path: PathBuf,
        /// Line of the object.
        line: usize,
        /// The object.
        object: String,
        /// The error in the referenced file (it names that file).
        source: Box<SceneError>,
    },
}

fn line_suffix(line: Option<usize>) -> String {
    line.map_or_else(String::new, |l| format!(":{l}"))
}

/// A recoverable problem: the scene loads, and the caller decides how to show it.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Warning {
    /// Degenerate (zero-area) triangles were dropped from an object.
    DegenerateTriangles {
        /// The scene or OBJ file.
        path: PathBuf,
        /// The object.
        object: String,
        /// How many were dropped.
        dropped: usize,
        /// Index (within the object) of the first one dropped.
        first: usize,
    },
    /// Exact copies of another triangle of the same object (the same three corners in the
    /// same cyclic order) were dropped.
    DuplicateTriangles {
        /// The scene or OBJ file.
        path: PathBuf,
        /// The object.
        object: String,
        /// How many were dropped.
        dropped: usize,
        /// Index (within the object) of the first one dropped.
        first: usize,
        /// Index (within the object) of the triangle it copies.
        original: usize,
    },
    /// Exact copies of a triangle of an earlier object (the same three world corners in the
    /// same cyclic order) were dropped, across the whole scene; an object left with no
    /// triangle of its own was removed. One warning per scene, naming the first copy.
    CoincidentObjects {
        /// The scene or OBJ file.
        path: PathBuf,
        /// How many triangles were dropped.
        dropped: usize,
        /// In how many objects.
        objects: usize,
        /// How many objects were left without a triangle and removed.
        removed: usize,
        /// The first copy: its object, that object's line (when it has one) and its index
        /// within the object.
        copy: (String, Option<usize>, usize),
        /// The triangle it repeats: its object, line and index within that object.
        original: (String, Option<usize>, usize),
    },
    /// A bare OBJ's MTL library is missing or broken; its faces get the default grey.
    MissingMtl {
        /// The OBJ file.
        path: PathBuf,
        /// The MTL library it names, if any.
        mtl: Option<PathBuf>,
    },
    /// An MTL value outside what the engine accepts was clamped.
    MtlClamped {
        /// The OBJ file whose library holds the material.
        path: PathBuf,
        /// The MTL material.
        material: String,
        /// The MTL key (`Kd`, `Ks`, ...).
        key: &'static str,
        /// The value as written.
        from: f32,
        /// The value used.
        to: f32,
    },
    /// MTL keys this engine does not model (textures, transparency, ...) were ignored.
    MtlIgnored {
        /// The OBJ file whose library holds the material.
        path: PathBuf,
        /// The MTL material.
        material: String,
        /// The ignored keys.
        keys: Vec<String>,
    },
    /// A material is defined but no object uses it.
    UnusedMaterial {
        /// The scene file.
        path: PathBuf,
        /// Line of the material.
        line: usize,
        /// Its name.
        material: String,
    },
    /// The film's aspect ratio differs from the image's; the film height sets the field of view.
    FilmAspect {
        /// The scene file.
        path: PathBuf,
        /// Film width / height.
        film: f32,
        /// Image width / height.
        image: f32,
    },
    /// Nothing in the scene emits light (no emitting surface, no lamp), so every render is
    /// black.
    NoEmitters {
        /// The scene file.
        path: PathBuf,
    },
    /// A texture statement or slot read only in part, or not at all (an MTL `map_Kd` option,
    /// a texture on an object without texture coordinates), and what was done instead.
    Texture {
        /// The file naming the texture (MTL library, glTF file) or the object.
        path: PathBuf,
        /// Its line, when there is one.
        line: Option<usize>,
        /// The material or object.
        at: String,
        /// What is not used and what was done instead.
        problem: String,
    },
    /// Part of a glTF that twopass does not model (a texture, a lamp, a skin, a primitive of
    /// points or lines, ...), and what was done instead.
    Gltf {
        /// The glTF file.
        path: PathBuf,
        /// Where in the document (`material 3 \`Wood\``, `node 5 \`Lamp\``, ...).
        at: String,
        /// What is not modelled and what was done instead.
        problem: String,
    },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DegenerateTriangles {
                path,
                object,
                dropped,
                first,
            } => write!(
                f,
                "{}: object `{object}`: dropped {dropped} degenerate (zero-area) triangle(s), the first is triangle {first}",
                path.display()
            ),
            Self::DuplicateTriangles {
                path,
                object,
                dropped,
                first,
                original,
            } => write!(
                f,
                "{}: object `{object}`: dropped {dropped} triangle(s) that repeat another of the object exactly (same corners, same winding), the first is triangle {first}, a copy of triangle {original}",
                path.display()
            ),
            Self::CoincidentObjects {
                path,
                dropped,
                objects,
                removed,
                copy,
                original,
            } => {
                let at = |(object, line, triangle): &(String, Option<usize>, usize)| {
                    let line = line.map_or_else(String::new, |l| format!(" (line {l})"));
                    format!("triangle {triangle} of object `{object}`{line}")
                };
                write!(
                    f,
                    "{}: dropped {dropped} triangle(s) in {objects} object(s) that repeat a triangle of an earlier object exactly (same corners, same winding); {removed} object(s) left with no triangle were removed; the first is {}, a copy of {}",
                    path.display(),
                    at(copy),
                    at(original)
                )
            }
            Self::MissingMtl { path, mtl } => write!(
                f,
                "{}: material library {} cannot be loaded; using the default grey Lambert material",
                path.display(),
                mtl.as_ref()
                    .map_or_else(|| "(unnamed)".to_owned(), |m| m.display().to_string())
            ),
            Self::MtlClamped {
                path,
                material,
                key,
                from,
                to,
            } => write!(
                f,
                "{}: MTL material `{material}`: {key} = {from} clamped to {to}",
                path.display()
            ),
            Self::MtlIgnored {
                path,
                material,
                keys,
            } => write!(
                f,
                "{}: MTL material `{material}`: ignored keys not modelled here: {}",
                path.display(),
                keys.join(", ")
            ),
            Self::UnusedMaterial {
                path,
                line,
                material,
            } => write!(
                f,
                "{}:{line}: material `{material}` is not used by any object",
                path.display()
            ),
            Self::FilmAspect { path, film, image } => write!(
                f,
                "{}: film aspect {film:.3} differs from image aspect {image:.3}; the film height sets the field of view",
                path.display()
            ),
            Self::Gltf { path, at, problem } => write!(f, "{}: {at}: {problem}", path.display()),
            Self::Texture {
                path,
                line,
                at,
                problem,
            } => write!(
                f,
                "{}{}: {at}: {problem}",
                path.display(),
                line_suffix(*line)
            ),
            Self::NoEmitters { path } => write!(
                f,
                "{}: nothing in the scene emits light: every render will be black",
                path.display()
            ),
        }
    }
}
