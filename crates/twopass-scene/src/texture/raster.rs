//! The texture's data and the vocabulary its readers share: the decoded levels, the wrap
//! modes and filters, a material's reference to a texture.

use glam::Vec2;
use twopass_brdf::Rgb;

/// One level of a mip pyramid: linear RGB texels, row by row from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct MipLevel {
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// `width * height` linear reflectances, row-major from the top row.
    pub texels: Vec<Rgb>,
}

/// A decoded image with its mip pyramid, linear RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages: the file, or the glTF image by index and name.
    pub name: String,
    /// Level 0 is the image itself; each next level halves both sides (rounding down, at least
    /// 1), each texel the area-weighted mean of the texels of the level above it covers, so
    /// every level keeps the image's mean.
    pub levels: Vec<MipLevel>,
}

/// How texture coordinates outside [0, 1] are brought back (glTF's `wrapS` and `wrapT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    /// The image tiles (glTF's default, REPEAT).
    #[default]
    Repeat,
    /// The image tiles, every other copy mirrored (MIRRORED_REPEAT).
    MirroredRepeat,
    /// Coordinates are clamped to the edge texels (CLAMP_TO_EDGE; MTL's `-clamp on`).
    ClampToEdge,
}

/// How a point look-up reads the texels around it (glTF's `magFilter`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Filter {
    /// The nearest texel (NEAREST).
    Nearest,
    /// Bilinear interpolation of the four nearest texels (LINEAR, and the default).
    #[default]
    Linear,
}

/// A material's base colour texture: what it reads and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlbedoTexture {
    /// Index into [`crate::Scene::textures`].
    pub texture: u32,
    /// Wrap mode along u.
    pub wrap_u: Wrap,
    /// Wrap mode along v.
    pub wrap_v: Wrap,
    /// The point look-up's filter.
    pub filter: Filter,
    /// Texture coordinates are `uv * scale + offset` before the look-up (MTL's `-s` and `-o`;
    /// 1 and 0 for glTF).
    pub scale: Vec2,
    /// See [`AlbedoTexture::scale`].
    pub offset: Vec2,
}

/// The largest channel of a tint, at least 0 (scales an error estimate by its worst case).
pub(crate) fn max_channel(tint: Rgb) -> f32 {
    tint.max_element().max(0.0)
}

impl AlbedoTexture {
    /// A texture read with the default sampler (repeat, bilinear) and no transform.
    pub fn new(texture: u32) -> Self {
        Self {
            texture,
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            filter: Filter::Linear,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
        }
    }
}
