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
}

/// [`LightmapSettings`] resolved for one scene: the texel size given or derived, the padding
/// at least 1.
#[derive(Debug, Clone, Copy)]
pub(super) struct Resolved {
    /// Edge of one texel on the surface, scene units.
    pub(super) texel_size: f32,
    /// Border around every chart, texels (at least 1).
    pub(super) padding: u32,
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
    /// Linear radiance per texel, W/(m^2 sr) per RGB channel, row-major, top row first (UV
    /// (0, 0) is the top-left corner, as glTF has it).
    pub radiance: Image,
    /// Charts in the atlas (1 when the scene's own texture coordinates are used).
    pub charts: usize,
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
    /// The HDR lightmap as EXR bytes.
    pub exr: Vec<u8>,
    /// The LDR lightmap as PNG bytes (exposure-scaled sRGB).
    pub png: Vec<u8>,
}

/// Where a lightmap's texture coordinates come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AtlasSource {
    /// The scene's own texture coordinates (an OBJ's `vt`): every triangle has them, they lie
    /// in [0, 1] and no two triangles overlap.
    Scene,
    /// Generated charts, because the scene's coordinates could not serve (the reason).
    Generated(String),
}

impl AtlasSource {
    /// In words, as the manifest records it.
    pub fn describe(&self) -> String {
        match self {
            Self::Scene => "the scene's texture coordinates (OBJ vt)".to_owned(),
            Self::Generated(why) => format!("generated charts ({why})"),
        }
    }
}
