//! Base colour textures: the albedo of a surface varying over it.
//!
//! A [`Texture`] is an image decoded once at load (PNG or JPEG, `decode`), its 8- or 16-bit
//! sRGB values turned to linear reflectance by the sRGB transfer function, kept with a box-filtered
//! mip pyramid (`pyramid`). A material refers to one through an [`AlbedoTexture`]: which
//! texture, which texture coordinates, the sampler's wrap modes and filter, and a scale and
//! offset of the coordinates (MTL's `-s` and `-o`). The albedo where a surface is shaded is the
//! material's own diffuse reflectance (the factor: glTF's `baseColorFactor`, MTL's `Kd`) times
//! the texture's value there.
//!
//! Two look-ups serve every consumer (`lookup`): the value at a point (the sampler's filter on
//! the full-resolution level: the tracer's hits, a lightmap texel) and the area-weighted mean
//! over a triangle region of the surface, read from the mip level whose texels fit the region
//! (a radiosity element).
//!
//! Texture coordinates follow glTF: (0, 0) is the top left corner of the image, u to the right,
//! v down. An OBJ's `vt` (v up) is turned over at load.

mod decode;
mod lookup;
mod pyramid;
mod raster;

pub(crate) use decode::decode;
pub use decode::{MAX_TEXTURE_PIXELS, MAX_TEXTURE_SIDE, srgb_to_linear};
pub(crate) use raster::max_channel;
pub use raster::{AlbedoTexture, Filter, MipLevel, Texture, Wrap};
