//! twopass-image: the pixel rasters that the tracer fills and the compositor writes, as plain
//! data: [`Image`] (linear RGB, `f32` per channel, radiance in W/(m^2 sr) per channel when a
//! renderer made it), [`Rgb8Image`] (display-referred 8-bit sRGB, what PNGs and sheets hold),
//! both a [`Raster`] of one pixel type, and [`Rect`], a rectangle of pixels.
//!
//! It sits below both `twopass-trace` and `twopass-composite` (ARCHITECTURE.md, "Crates"), so a
//! render's layers are the compositor's images without a conversion. No file I/O here: the
//! compositor reads and writes EXR and PNG.
//!
//! Conventions (ARCHITECTURE.md, "Conventions"): colour is linear RGB (Rec. 709 / sRGB
//! primaries), no alpha; pixels are stored row-major with pixel (0, 0) at the top left; sizes
//! and coordinates are in pixels.
//!
//! ```
//! use twopass_image::{Image, Rect};
//!
//! let ramp = Image::from_fn(4, 3, |x, _| [0.25 * x as f32, 0.5, 1.0]);
//! assert_eq!(ramp.size(), (4, 3));
//! assert_eq!(ramp.get(2, 1), glam::Vec3::new(0.5, 0.5, 1.0));
//! let corner = ramp.crop(Rect::new(2, 1, 2, 2))?;
//! assert_eq!(corner.get(0, 0), ramp.get(2, 1));
//! # Ok::<(), twopass_image::ImageError>(())
//! ```

mod error;
mod raster;
mod rect;

pub use error::ImageError;
pub use raster::{Image, Raster, Rgb8Image};
pub use rect::Rect;
