//! Atomic file output: write to a temporary file beside the target, then rename, so a failed
//! run never leaves a half-written file behind.

use std::fs;
use std::path::Path;

use twopass_composite::Rgb8Image;

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

/// Writes an 8-bit sRGB image (`rgb.len() == 3 * width * height`, rows top to bottom) as PNG,
/// atomically, creating the parent directory if missing. The encoding is the workspace's one
/// PNG encoder ([`twopass_composite::write::encode_png`]).
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), CliError> {
    if rgb.len() as u64 != 3 * u64::from(width) * u64::from(height) {
        return Err(CliError::Encode {
            path: path.to_owned(),
            message: format!("{} bytes for a {width} x {height} RGB image", rgb.len()),
        });
    }
    let image = Rgb8Image::from_fn(width, height, |x, y| {
        let i = 3 * (y as usize * width as usize + x as usize);
        [rgb[i], rgb[i + 1], rgb[i + 2]]
    });
    let bytes = twopass_composite::write::encode_png(path, &image, None)?;
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
