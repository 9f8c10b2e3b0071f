//! Atomic file output: write to a temporary file beside the target, then rename, so a failed
//! run never leaves a half-written file behind.

use std::fs;
use std::path::Path;

use crate::error::CliError;

/// Writes `bytes` to `path` atomically (the workspace's one atomic write,
/// [`twopass_composite::write::write_atomic`]), creating the parent directory if missing.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    fs::create_dir_all(dir).map_err(|e| CliError::io(dir, e))?;
    Ok(twopass_composite::write::write_atomic(path, bytes)?)
}

/// Encodes an 8-bit sRGB image (`rgb.len() == 3 * width * height`, rows top to bottom) as PNG
/// and writes it atomically to `path`.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), CliError> {
    let encode_err = |e: png::EncodingError| CliError::Encode {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut w = enc.write_header().map_err(encode_err)?;
        w.write_image_data(rgb).map_err(encode_err)?;
    }
    write_atomic(path, &bytes)
}

/// Writes `rows` as CSV (a header from the field names, one line per row) atomically to `path`.
pub fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<(), CliError> {
    let encode = |message: String| CliError::Encode {
        path: path.to_owned(),
        message,
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| encode(e.to_string()))?;
    }
    let bytes = w.into_inner().map_err(|e| encode(e.to_string()))?;
    write_atomic(path, &bytes)
}
