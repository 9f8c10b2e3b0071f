//! The crate's one error type.

use std::path::PathBuf;

use twopass_image::{ImageError, Rect};

/// Everything that can go wrong in this crate. Variants carry context fields (the file, the
/// layer, the pixel, the sizes), not preformatted strings.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CompositeError {
    /// `Image::from_pixels` got a pixel vector whose length is not `width * height`.
    #[error("{width} x {height} image needs {} pixels, got {len}", (*width as u64) * (*height as u64))]
    PixelCount {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// Length of the vector given.
        len: usize,
    },
    /// Two images (or a layer and its set) that must have one size do not.
    #[error("size mismatch in {what}: expected {expected:?}, found {found:?}")]
    SizeMismatch {
        /// What was being combined (a layer name, "reference", ...).
        what: String,
        /// The size required, (width, height).
        expected: (u32, u32),
        /// The size found, (width, height).
        found: (u32, u32),
    },
    /// An operation that needs at least one pixel got an empty image or region.
    #[error("{what} is empty (0 pixels)")]
    Empty {
        /// What was empty.
        what: String,
    },
    /// A pixel is NaN or infinite. Metrics refuse it (a NaN metric hides the problem) and
    /// writers refuse it (a file with NaN breaks every tool downstream).
    #[error("{}{}pixel ({x}, {y}) is not finite: {value:?}",
        path.as_ref().map(|p| format!("refusing to write {}: ", p.display())).unwrap_or_default(),
        layer.as_ref().map(|l| format!("layer '{l}' ")).unwrap_or_default())]
    NonFinite {
        /// The file that was to be written, if any.
        path: Option<PathBuf>,
        /// The layer (or image role, such as "reference") holding the pixel, if known.
        layer: Option<String>,
        /// Pixel column.
        x: u32,
        /// Pixel row (0 at the top).
        y: u32,
        /// The offending RGB value.
        value: [f32; 3],
    },
    /// A layer name is empty, repeated, or contains a character that would break EXR channel
    /// names (`.` separates layer and channel; control characters are refused).
    #[error("invalid layer name {name:?}: {reason}")]
    LayerName {
        /// The name given.
        name: String,
        /// Why it was refused.
        reason: &'static str,
    },
    /// A layer asked for by name is not in the set.
    #[error("no layer named {name:?}")]
    MissingLayer {
        /// The name asked for.
        name: String,
    },
    /// A region does not lie inside the image.
    #[error("region {rect:?} is not inside the {width} x {height} image")]
    Region {
        /// The region given.
        rect: Rect,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// A parameter is out of its range (percentile outside [0, 1], non-finite exposure, ...).
    #[error("invalid parameter {name} = {value}: {reason}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// The range or rule it breaks.
        reason: &'static str,
    },
    /// An EXR file read has no channel that the reader needs.
    #[error("{}: no channel {channel:?}", path.display())]
    MissingChannel {
        /// The file read.
        path: PathBuf,
        /// The channel name looked for.
        channel: String,
    },
    /// File system error (create, write, sync, rename, read).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The exr crate failed to encode or decode.
    #[error("{}: EXR: {source}", path.display())]
    Exr {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: exr::error::Error,
    },
    /// The png crate failed to encode.
    #[error("{}: PNG: {source}", path.display())]
    Png {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: png::EncodingError,
    },
    /// The embedded font could not be parsed (a build problem, not an input problem).
    #[error("embedded font: {0}")]
    Font(ab_glyph::InvalidFont),
}

/// The image crate's errors as this crate's variants of the same name (`NonFinite` without a
/// path: no file was involved).
impl From<ImageError> for CompositeError {
    fn from(e: ImageError) -> Self {
        match e {
            ImageError::PixelCount { width, height, len } => {
                CompositeError::PixelCount { width, height, len }
            }
            ImageError::Region {
                rect,
                width,
                height,
            } => CompositeError::Region {
                rect,
                width,
                height,
            },
            ImageError::NonFinite { what, x, y, value } => CompositeError::NonFinite {
                path: None,
                layer: Some(what),
                x,
                y,
                value,
            },
        }
    }
}

impl From<WriteError> for CompositeError {
    fn from(e: WriteError) -> Self {
        Self::Io {
            path: e.path,
            source: e.source,
        }
    }
}

/// A failed atomic write ([`crate::write::write_atomic`]): creating the temporary file, writing,
/// syncing or renaming it. Every crate that writes outputs converts it into its own error.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file (or, when the temporary file cannot be created, its folder).
    pub path: PathBuf,
    /// The operating system's error.
    #[source]
    pub source: std::io::Error,
}

/// The crate's result type.
pub type Result<T, E = CompositeError> = std::result::Result<T, E>;
