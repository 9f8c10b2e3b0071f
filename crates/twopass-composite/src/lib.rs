//! twopass-composite: linear RGB images and named layers in; tone-mapped PNGs, multi-layer EXRs,
//! comparison sheets and error metrics out. Depends on no renderer crate (ARCHITECTURE.md,
//! "Architecture invariants"): its [`Image`] is `twopass-image`'s, the type a renderer's layers
//! already are, so nothing converts.
//!
//! Conventions: linear RGB (sRGB primaries), `f32`, pixel (0, 0) at the top left, sizes in
//! pixels. EXRs are written linear; PNGs are tone mapped (exposure, curve, sRGB transfer) and
//! say so in a text chunk. Non-finite pixels are an error for metrics and writers alike.
//!
//! ```
//! use twopass_composite::{Image, Layers, ToneMap, metric, write};
//!
//! let radiosity = Image::from_fn(4, 3, |x, _| [0.1 * x as f32, 0.2, 0.3]);
//! let specular = Image::filled(4, 3, glam::Vec3::splat(0.05));
//! let mut layers = Layers::new(4, 3).with("radiosity", radiosity)?.with("specular", specular)?;
//! let hybrid = layers.merge_into("final", &["radiosity", "specular"])?.clone();
//!
//! let reference = Image::filled(4, 3, glam::Vec3::new(0.2, 0.25, 0.35));
//! let display = ToneMap::auto_default(&reference)?; // one exposure for every panel
//! let m = metric::compare(&hybrid, &reference, &display)?;
//! assert!(m.rel_rmse > 0.0 && m.ssim <= 1.0);
//!
//! let dir = tempfile::tempdir()?;
//! write::write_exr_layers(&dir.path().join("hybrid.exr"), &layers)?;
//! write::write_png_tonemapped(&dir.path().join("hybrid.png"), &hybrid, &display)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod error;
pub mod false_colour;
pub mod image;
pub mod layer;
pub mod metadata;
pub mod metric;
pub mod sheet;
mod text;
pub mod tonemap;
pub mod write;

pub use error::{CompositeError, Result, WriteError};
pub use image::{Image, Rect, Rgb8Image};
pub use layer::Layers;
pub use metadata::RenderMetadata;
pub use metric::Metrics;
pub use tonemap::ToneMap;
