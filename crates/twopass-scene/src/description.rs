//! The serde image of a scene file (TOML). Every key is documented in `scenes/README.md`;
//! unknown keys are errors. [`crate::load`] turns this into a validated [`crate::Scene`].

use serde::Deserialize;
use toml::Spanned;

/// The scene file version this build reads.
pub const VERSION: u32 = 1;

/// A whole scene file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Format version, must be [`VERSION`].
    pub version: u32,
    /// Length unit of every position in the file and its meshes (default metres). An
    /// unknown unit is a TOML error at its line naming the known ones.
    #[serde(default)]
    pub unit: crate::unit::Unit,
    /// The pinhole camera.
    pub camera: Spanned<CameraDesc>,
    /// Named materials, referenced by objects.
    #[serde(default, rename = "material")]
    pub materials: Vec<Spanned<MaterialDesc>>,
    /// The objects: built-in shapes or OBJ meshes.
    #[serde(default, rename = "object")]
    pub objects: Vec<Spanned<ObjectDesc>>,
    /// The lamps: point, spot and directional lights.
    #[serde(default, rename = "light")]
    pub lights: Vec<Spanned<LightDesc>>,
    /// The sky: light from every direction a ray escapes the scene by.
    pub sky: Option<Spanned<SkyDesc>>,
    /// Windows through which the sky lights an interior (sampling aims through them).
    #[serde(default, rename = "portal")]
    pub portals: Vec<Spanned<PortalDesc>>,
}

/// `[sky]`: a uniform environment or a clear daylight sky; `kind` selects which.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SkyDesc {
    /// The same radiance from every direction of the sphere.
    Uniform {
        /// Radiance, W/(m^2 sr) per channel (or one value for all three).
        radiance: Triple,
        /// Factor on the radiance (default 1).
        scale: Option<f32>,
    },
    /// Preetham et al.'s clear sky with a sun of finite size.
    Daylight {
        /// Atmospheric turbidity, in [2, 10] (default 3).
        turbidity: Option<f32>,
        /// The sun's elevation above the horizon, degrees in [-90, 90]; or give
        /// `sun_direction`.
        sun_elevation: Option<f32>,
        /// The sun's azimuth, degrees, from the horizontal part of +z toward +x (default 0).
        sun_azimuth: Option<f32>,
        /// Direction toward the sun (need not be unit); or give `sun_elevation`.
        sun_direction: Option<[f32; 3]>,
        /// The sun's angular diameter, degrees in (0, 45] (default 0.53).
        sun_diameter: Option<f32>,
        /// The zenith (need not be unit; default [0, 1, 0]).
        up: Option<[f32; 3]>,
        /// Factor on every radiance (default 1: luminance in cd/m^2 over 683 lm/W).
        scale: Option<f32>,
    },
}

/// `[[portal]]`: a parallelogram window through which the sky lights an interior, scene
/// units.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortalDesc {
    /// One corner.
    pub origin: [f32; 3],
    /// First edge from `origin`.
    pub edge_u: [f32; 3],
    /// Second edge from `origin`.
    pub edge_v: [f32; 3],
}

/// `[[light]]`: a lamp; `kind` selects point, spot or directional. A point or spot lamp gives
/// exactly one of `intensity` (W/sr) and `power` (W, as Blender states a lamp: intensity =
/// power / (4 pi), for a spot too); a directional lamp gives `irradiance`. `colour` multiplies
/// the value per channel (default 1).
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightDesc {
    /// Emits the same intensity in every direction.
    Point {
        /// Name in messages (default `light N`, N its 1-based index).
        name: Option<String>,
        /// Position, scene units.
        position: [f32; 3],
        /// Per-channel factor (default 1).
        colour: Option<Triple>,
        /// Radiant intensity, W/sr.
        intensity: Option<f32>,
        /// Emitted power, W (intensity = power / (4 pi)).
        power: Option<f32>,
    },
    /// A cone of light around `direction` (or toward `look_at`).
    Spot {
        /// Name in messages (default `light N`).
        name: Option<String>,
        /// Position, scene units.
        position: [f32; 3],
        /// Axis of the cone (need not be unit); or give `look_at`.
        direction: Option<[f32; 3]>,
        /// A point on the axis, scene units; or give `direction`.
        look_at: Option<[f32; 3]>,
        /// Per-channel factor (default 1).
        colour: Option<Triple>,
        /// Radiant intensity on the axis, W/sr.
        intensity: Option<f32>,
        /// Power of the point lamp the spot is cut from, W (intensity = power / (4 pi)).
        power: Option<f32>,
        /// Half angle of full intensity, degrees (default 0).
        inner_angle: Option<f32>,
        /// Half angle past which no light leaves, degrees in (0, 90] (default 45).
        outer_angle: Option<f32>,
    },
    /// Parallel light from infinitely far away, along `direction` (or from `position` toward
    /// `look_at`).
    Directional {
        /// Name in messages (default `light N`).
        name: Option<String>,
        /// Direction the light travels (need not be unit).
        direction: Option<[f32; 3]>,
        /// With `look_at`: the light travels from here toward `look_at`.
        position: Option<[f32; 3]>,
        /// With `position`.
        look_at: Option<[f32; 3]>,
        /// Per-channel factor (default 1).
        colour: Option<Triple>,
        /// Irradiance on a surface facing the light, W/m^2 (scene units squared).
        irradiance: f32,
    },
}

/// `[camera]`: a pinhole camera. Give either `fov_y` or `focal_length` (+ `film_size`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position, scene units.
    pub position: [f32; 3],
    /// Point looked at, scene units.
    pub look_at: [f32; 3],
    /// Up direction (default +y); need not be unit or orthogonal to the view.
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view, degrees in (0, 180).
    pub fov_y: Option<f32>,
    /// Focal length, mm (with `film_size`).
    pub focal_length: Option<f32>,
    /// Film width and height, mm (default 36 x 24); the height sets the field of view.
    pub film_size: Option<[f32; 2]>,
    /// Image width and height in pixels (default 512 x 512).
    #[serde(default = "default_resolution")]
    pub resolution: [u32; 2],
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn default_resolution() -> [u32; 2] {
    [512, 512]
}

/// Three numbers given as one value for all three or as a list: colours `[r, g, b]`, scales
/// `[x, y, z]`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Triple {
    /// The same value three times.
    Splat(f32),
    /// One value each.
    List([f32; 3]),
}

impl Triple {
    /// The three values.
    pub fn get(self) -> [f32; 3] {
        match self {
            Self::Splat(v) => [v; 3],
            Self::List(c) => c,
        }
    }
}

/// Which Fresnel a Cook-Torrance material evaluates.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum FresnelDesc {
    /// Exact unpolarized Fresnel.
    #[default]
    Exact,
    /// Schlick's approximation.
    Schlick,
}

/// `[[material]]`: a named material; `type` selects the model.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialDesc {
    /// Lambertian: `diffuse` reflectance in [0, 1).
    Lambert {
        /// Name objects refer to.
        name: String,
        /// Diffuse reflectance rho.
        diffuse: Triple,
    },
    /// Phong (1975) as published, or the normalized modified Phong with `normalized = true`.
    Phong {
        /// Name objects refer to.
        name: String,
        /// Diffuse reflectance rho (default 0).
        #[serde(default = "black")]
        diffuse: Triple,
        /// Specular coefficient k_s in [0, 1].
        specular: Triple,
        /// Exponent n in [0, 1e6].
        exponent: f32,
        /// Ambient coefficient k_a (default: the diffuse reflectance).
        ambient: Option<Triple>,
        /// Use the normalized (plausible) form.
        #[serde(default)]
        normalized: bool,
    },
    /// Blinn-Phong (1977), classic or `normalized = true`.
    BlinnPhong {
        /// Name objects refer to.
        name: String,
        /// Diffuse reflectance rho (default 0).
        #[serde(default = "black")]
        diffuse: Triple,
        /// Specular coefficient k_s in [0, 1].
        specular: Triple,
        /// Exponent n' in [0, 1e6].
        exponent: f32,
        /// Use the normalized (plausible) form.
        #[serde(default)]
        normalized: bool,
    },
    /// Cook-Torrance microfacet model (Beckmann D, V-cavity G, Fresnel).
    CookTorrance {
        /// Name objects refer to.
        name: String,
        /// Diffuse reflectance rho (default 0).
        #[serde(default = "black")]
        diffuse: Triple,
        /// Specular lobe weight s (default 1).
        #[serde(default = "white")]
        specular: Triple,
        /// Beckmann RMS slope m > 0.
        roughness: f32,
        /// A measured metal by name (`gold`, `silver`, `copper`, `aluminium`).
        conductor: Option<String>,
        /// Real part of the index of refraction (instead of `conductor`).
        ior: Option<Triple>,
        /// Extinction coefficient (default 0), with `ior`.
        k: Option<Triple>,
        /// `exact` (default) or `schlick`.
        #[serde(default)]
        fresnel: FresnelDesc,
    },
    /// Perfect mirror.
    Mirror {
        /// Name objects refer to.
        name: String,
        /// Reflectance in [0, 1] (default 1).
        #[serde(default = "white")]
        reflectance: Triple,
    },
    /// Smooth dielectric (glass, water).
    Dielectric {
        /// Name objects refer to.
        name: String,
        /// Index of refraction inside over outside, > 0.
        ior: f32,
    },
    /// Smooth conductor: a mirror with the exact Fresnel of a complex index.
    Conductor {
        /// Name objects refer to.
        name: String,
        /// A measured metal by name.
        conductor: Option<String>,
        /// Real part of the index of refraction (instead of `conductor`).
        ior: Option<Triple>,
        /// Extinction coefficient (default 0), with `ior`.
        k: Option<Triple>,
    },
}

fn black() -> Triple {
    Triple::Splat(0.0)
}

fn white() -> Triple {
    Triple::Splat(1.0)
}

impl MaterialDesc {
    /// The material's name.
    pub fn name(&self) -> &str {
        match self {
            Self::Lambert { name, .. }
            | Self::Phong { name, .. }
            | Self::BlinnPhong { name, .. }
            | Self::CookTorrance { name, .. }
            | Self::Mirror { name, .. }
            | Self::Dielectric { name, .. }
            | Self::Conductor { name, .. } => name,
        }
    }
}

/// `[[object]]`: a shape or mesh, its material, optional emission and transform.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Unique name, used in messages.
    pub name: String,
    /// The geometry.
    pub shape: ShapeDesc,
    /// Material name; required for built-in shapes, overrides every MTL material of an OBJ.
    pub material: Option<String>,
    /// For OBJ meshes: MTL material name -> scene material name.
    #[serde(default)]
    pub material_map: std::collections::BTreeMap<String, String>,
    /// Emitted radiance L_e per channel, W/(m^2 sr) in scene units, from the front side.
    pub emission: Option<Triple>,
    /// Object to world transform (scale, then rotations in order, then translation).
    #[serde(default)]
    pub transform: TransformDesc,
}

/// `shape = { type = ..., ... }`: the geometry of an object, in object space.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeDesc {
    /// Parallelogram `origin`, `origin + edge_u`, `origin + edge_u + edge_v`, `origin + edge_v`;
    /// the front side faces along edge_u x edge_v.
    Quad {
        /// A corner.
        origin: [f32; 3],
        /// First edge from `origin`.
        edge_u: [f32; 3],
        /// Second edge from `origin`.
        edge_v: [f32; 3],
    },
    /// Planar simple polygon (convex or not), counter-clockwise seen from its front side.
    Polygon {
        /// Three or more vertices in order.
        vertices: Vec<[f32; 3]>,
    },
    /// Axis-aligned box (before the transform), faces pointing out.
    Box {
        /// Minimum corner.
        min: [f32; 3],
        /// Maximum corner.
        max: [f32; 3],
    },
    /// Sphere with smooth shading normals, front side outside.
    Sphere {
        /// Centre.
        center: [f32; 3],
        /// Radius > 0.
        radius: f32,
        /// Icosphere subdivision level 0..=8 (default: from the sphere's size, see README).
        subdivisions: Option<u32>,
    },
    /// Wavefront OBJ mesh (with its MTL), path relative to the scene file.
    Obj {
        /// The OBJ file.
        file: String,
    },
}

/// `transform = { ... }`: applied as scale, then each rotation in order, then translation.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    /// Per-axis scale (or one value for all axes); default 1.
    pub scale: Option<Triple>,
    /// Rotations applied in order.
    #[serde(default)]
    pub rotate: Vec<RotationDesc>,
    /// Translation, scene units; default 0.
    pub translate: Option<[f32; 3]>,
}

/// One rotation about an axis through the origin (right-handed).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationDesc {
    /// Rotation axis (need not be unit).
    pub axis: [f32; 3],
    /// Angle in degrees.
    pub degrees: f32,
}
