//! What a lightmap bake takes and gives: its settings (resolved for one scene before use), the
//! baked lightmap with its encodings, and where its texture coordinates came from.

use smart_default::SmartDefault;
use twopass_composite::Image;

/// Texels along the scene's bounding-box diagonal when no texel size is given: the texel edge
/// is then the diagonal over this.
pub const TEXELS_PER_DIAGONAL: f32 = 200.0;

/// How to lay out and fill a lightmap.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct LightmapSettings {
    /// Edge of one texel on the surface, scene units (finite, > 0); `None`: the scene's
    /// bounding-box diagonal over [`TEXELS_PER_DIAGONAL`].
    #[default(None)]
    pub texel_size: Option<f32>,
    /// Border around every chart, texels, filled by dilation (at least 1; 2 keeps bilinear
    /// filtering and the first mip level inside the chart).
    #[default(2)]
    pub padding: u32,
    /// What the texels hold; `None`: [`LightmapQuantity::for_scene`] (irradiance for a glTF
    /// scene, radiance otherwise).
    #[default(None)]
    pub quantity: Option<LightmapQuantity>,
    /// How the texture the `.glb` files reference for engines encodes the texels.
    #[default(LightmapEncoding::Rgbm)]
    pub encoding: LightmapEncoding,
}

/// How the lightmap texture that the `.glb` files reference for engines (the materials'
/// `extras.lightMap`) encodes the texels.
///
/// The default is [`Rgbm`](LightmapEncoding::Rgbm): a lightmap's point is its range (a sunlit
/// floor is many times brighter than the exposure's white), every consumer of
/// `extras.lightMap` already reads it with code of its own (glTF has no lightmap slot), and the
/// decode is one multiplication. The sRGB PNG is written either way (`<stem>.lightmap.png`,
/// and the lightmap `.glb`'s emissive texture that any glTF viewer shows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightmapEncoding {
    /// The exposure-scaled sRGB PNG: `round(255 srgb(min(1, exposure * value)))`, clipped.
    Srgb,
    /// RGBM ([`Rgbm`](super::Rgbm)): `value = multiplier * A * (R, G, B)`, linear, not clipped.
    Rgbm,
}

impl LightmapEncoding {
    /// Its name on the command line and in the `.glb`: `srgb` or `rgbm`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Srgb => "srgb",
            Self::Rgbm => "rgbm",
        }
    }
}

/// What a lightmap's texels hold, per RGB channel.
///
/// Engines multiply a lightmap by the surface's own base colour (and its texture):
/// Unity and Godot take the texel as the light a white diffuse surface would reflect (outgoing
/// = albedo x texel), three.js (r155 and later, physically based lights) as irradiance E in
/// W/m^2 (outgoing = albedo / pi x texel x `lightMapIntensity`). [`Irradiance`] holds E / pi,
/// so Unity and Godot use it as it is and three.js with `lightMapIntensity = pi`;
/// [`Radiance`] is the surface's own outgoing light with its albedo and emission baked in, for
/// viewers that show the lightmap alone (as emission).
///
/// [`Irradiance`]: LightmapQuantity::Irradiance
/// [`Radiance`]: LightmapQuantity::Radiance
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightmapQuantity {
    /// Outgoing radiance L = L_e + rho E / pi, W/(m^2 sr): emission and albedo included.
    Radiance,
    /// Incoming irradiance over pi, E / pi, W/(m^2 sr): the radiance a white Lambertian
    /// surface would reflect there, so that albedo x texel is the reflected radiance rho E /
    /// pi. No emission. It is the reflected light divided by the albedo per channel, so a
    /// channel whose albedo is 0 (black, or a mirror, glass or metal, which have no diffuse
    /// part) holds 0.
    Irradiance,
}

impl LightmapQuantity {
    /// The default for `scene`: irradiance for a glTF scene (its asset goes back to an engine
    /// that multiplies by its own base colour), radiance otherwise.
    pub fn for_scene(scene: &twopass_scene::Scene) -> Self {
        if scene.gltf.is_some() {
            Self::Irradiance
        } else {
            Self::Radiance
        }
    }

    /// Its name on the command line and in the manifest: `radiance` or `irradiance`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Radiance => "radiance",
            Self::Irradiance => "irradiance",
        }
    }

    /// How the lightmap PNG encodes it (recorded in the `.glb` and the manifest).
    pub fn png_formula(self) -> &'static str {
        match self {
            Self::Radiance => super::glb::PNG_FORMULA,
            Self::Irradiance => IRRADIANCE_PNG_FORMULA,
        }
    }
}

/// How the lightmap PNG encodes an irradiance lightmap.
pub const IRRADIANCE_PNG_FORMULA: &str = "sRGB-encoded 8-bit of min(1, exposure * E / pi), E \
     the irradiance reaching the surface in W/m^2 (E / pi in W/(m^2 sr): multiply by the \
     albedo for the reflected radiance); the HDR values are in the .exr beside the .glb";

/// [`LightmapSettings`] resolved for one scene: the texel size given or derived, the padding
/// at least 1.
#[derive(Debug, Clone, Copy)]
pub(super) struct Resolved {
    /// Edge of one texel on the surface, scene units.
    pub(super) texel_size: f32,
    /// Border around every chart, texels (at least 1).
    pub(super) padding: u32,
    /// What the texels hold.
    pub(super) quantity: LightmapQuantity,
    /// How the texture the `.glb` files reference encodes them.
    pub(super) encoding: LightmapEncoding,
}

/// A baked lightmap and the user-mesh glTF that shows it.
#[derive(Debug, Clone)]
pub struct Lightmap {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Edge of one texel on the surface, scene units: the settings' or the one derived from
    /// the scene's size.
    pub texel_size: f32,
    /// The [`quantity`](Lightmap::quantity) per texel, W/(m^2 sr) per RGB channel, linear,
    /// row-major, top row first (UV (0, 0) is the top-left corner, as glTF has it).
    pub radiance: Image,
    /// What the texels hold.
    pub quantity: LightmapQuantity,
    /// Charts in the atlas (1 when the scene's own texture coordinates are used).
    pub charts: usize,
    /// Objects whose charts got finer texels than `texel_size` for their curvature
    /// ([`curvature_scale`](super::curvature_scale)); 0 with the scene's own coordinates.
    pub curved_objects: usize,
    /// Texels a triangle touches, each lit at its own point (the rest are padding, dilated or
    /// empty).
    pub covered_texels: usize,
    /// Closest-hit rays a final gather traced (0 without one).
    pub rays: u64,
    /// Shadow rays a final gather traced (0 without one).
    pub shadow_rays: u64,
    /// Where the texture coordinates come from.
    pub atlas: AtlasSource,
    /// The scene's triangles with `TEXCOORD_1` into the atlas, as a `.glb` embedding the PNG.
    pub glb: Vec<u8>,
    /// For a glTF scene, the user's own document written back as `.glb` with the atlas on
    /// `TEXCOORD_1` and the PNG embedded and referenced (module `asset`); `None` otherwise.
    pub asset: Option<Vec<u8>>,
    /// The HDR lightmap as EXR bytes.
    pub exr: Vec<u8>,
    /// The LDR lightmap as PNG bytes (exposure-scaled sRGB).
    pub png: Vec<u8>,
    /// How the texture the `.glb` files reference encodes the texels.
    pub encoding: LightmapEncoding,
    /// With [`LightmapEncoding::Rgbm`], the HDR lightmap as an RGBA PNG (RGBM, module
    /// [`rgbm`](super::rgbm)) and its range multiplier; `None` otherwise.
    pub rgbm: Option<(Vec<u8>, f32)>,
}

/// Where a lightmap's texture coordinates come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AtlasSource {
    /// The scene's own texture coordinates (an OBJ's `vt`, a glTF's `TEXCOORD_1`): every
    /// triangle has them, they lie in [0, 1] and no two triangles overlap.
    Scene,
    /// Generated charts, because the scene's coordinates could not serve (the reason).
    Generated(String),
}

impl AtlasSource {
    /// In words, as the manifest records it.
    pub fn describe(&self) -> String {
        match self {
            Self::Scene => {
                "the scene's texture coordinates (an OBJ's vt, a glTF's TEXCOORD_1)".to_owned()
            }
            Self::Generated(why) => format!("generated charts ({why})"),
        }
    }
}
