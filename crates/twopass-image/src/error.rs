//! The crate's one error type.

use crate::rect::Rect;

/// What can go wrong building or reading a [`crate::Raster`]. Variants carry context fields (the
/// sizes, the rectangle, the pixel), not preformatted strings. Not `#[non_exhaustive]`, unlike
/// the other crates' errors: the compositor maps each variant to its own of the same name, and
/// a new variant should make that mapping fail to compile.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// [`crate::Raster::from_pixels`] got a pixel vector whose length is not `width * height`.
    #[error("{width} x {height} image needs {} pixels, got {len}", (*width as u64) * (*height as u64))]
    PixelCount {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// Length of the vector given.
        len: usize,
    },
    /// A rectangle that must lie inside an image does not.
    #[error("region {rect:?} is not inside the {width} x {height} image")]
    Region {
        /// The rectangle given, in pixels.
        rect: Rect,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
    },
    /// A pixel is NaN or infinite ([`crate::Image::check_finite`]).
    #[error("layer '{what}' pixel ({x}, {y}) is not finite: {value:?}")]
    NonFinite {
        /// The layer or image role named by the caller (such as "reference").
        what: String,
        /// Pixel column.
        x: u32,
        /// Pixel row (0 at the top).
        y: u32,
        /// The offending linear RGB value.
        value: [f32; 3],
    },
}
