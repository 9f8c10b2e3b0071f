//! The images the compositor works on: [`Image`] (linear RGB), [`Rgb8Image`] (display-referred
//! 8-bit) and [`Rect`], from `twopass-image`, the one home of the pixel raster that the tracer
//! fills too (ARCHITECTURE.md, "Where each idea lives"); here, the size check that answers with
//! this crate's error (the image crate's own errors convert into this crate's variants of the
//! same name).
//!
//! Conventions (ARCHITECTURE.md, "Conventions"): colour is linear RGB (Rec. 709 / sRGB
//! primaries), `f32` per channel, no alpha; pixels are stored row-major with pixel (0, 0) at the
//! top left; sizes and coordinates are in pixels.

use crate::error::{CompositeError, Result};

pub use twopass_brdf::colour::{LUMINANCE, luminance};
pub use twopass_image::{Image, Raster, Rect, Rgb8Image};

/// `Ok` when `image` has the size of `expected`; otherwise the error names `what`.
pub(crate) fn check_same_size(expected: &Image, image: &Image, what: &str) -> Result<()> {
    if expected.size() == image.size() {
        Ok(())
    } else {
        Err(CompositeError::SizeMismatch {
            what: what.to_owned(),
            expected: expected.size(),
            found: image.size(),
        })
    }
}
