//! Atomic file output: write to a temporary file beside the target, then rename, so a failed
//! run never leaves a half-written file behind.

use std::fs;
use std::path::Path;

use twopass_composite::Rgb8Image;

use crate::error::CliError;

/// Largest small input the CLI reads (presets, manifests, cache records), bytes.
pub const MAX_SMALL_INPUT: u64 = 16 << 20;

/// Reads a small input file (at most [`MAX_SMALL_INPUT`] bytes, a regular file).
pub fn read_small(path: &Path) -> std::io::Result<Vec<u8>> {
    twopass_scene::read_bounded(path, MAX_SMALL_INPUT)
}

/// Reads a small input file as UTF-8 text (see [`read_small`]).
pub fn read_text(path: &Path) -> std::io::Result<String> {
    String::from_utf8(read_small(path)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// Temporary files of atomic writes (every crate's `.twopass-*.tmp`) older than this are
/// leftovers of a killed run: a live one is written from memory and renamed within seconds.
pub const STALE_TEMPORARY: std::time::Duration = std::time::Duration::from_secs(600);

/// Creates `dir` and its missing parents. When a part of the path exists but is not a folder
/// (`-o scene.toml/x.exr`), says so instead of the system's "File exists". Also removes stale
/// temporary files ([`STALE_TEMPORARY`]) that a killed run left in it.
pub fn create_dir(dir: &Path) -> Result<(), CliError> {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    make_dir(dir)?;
    remove_stale_temporaries(dir);
    Ok(())
}

/// Removes `.twopass-*.tmp` files older than [`STALE_TEMPORARY`] from `dir`; best effort (a
/// file that cannot be removed stays, and is no reason to fail a run).
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !(name.starts_with(".twopass-") && name.ends_with(".tmp")) {
            continue;
        }
        let stale = entry.metadata().is_ok_and(|m| {
            m.is_file()
                && m.modified()
                    .ok()
                    .and_then(|t| t.elapsed().ok())
                    .is_some_and(|age| age > STALE_TEMPORARY)
        });
        if stale {
            let _ = fs::remove_file(entry.path());
        }
    }
}

fn make_dir(dir: &Path) -> Result<(), CliError> {
    fs::create_dir_all(dir).map_err(|e| {
        let file = dir.ancestors().find(|a| a.is_file()).filter(|_| {
            e.kind() == std::io::ErrorKind::AlreadyExists || e.raw_os_error() == Some(20)
        });
        match file {
            Some(file) => CliError::Input(format!(
                "{}: cannot create the output folder {}: {} is a file, not a directory",
                file.display(),
                dir.display(),
                file.display()
            )),
            None => CliError::io(dir, e),
        }
    })
}

/// Writes `bytes` to `path` atomically (the workspace's one atomic write,
/// [`twopass_composite::write::write_atomic`]), creating the parent directory if missing.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    create_dir(dir)?;
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

/// Prints `value` as pretty JSON on standard output (the `--json` summary of every command);
/// a write error is the CLI's error, as with `outln!`.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| CliError::Encode {
        path: "(standard output)".into(),
        message: e.to_string(),
    })?;
    outln!("{text}");
    Ok(())
}

/// The ending of every command with a summary: `value` as pretty JSON on stdout with
/// `--json`, else the human summary `print` unless `--quiet`.
pub fn report<T: serde::Serialize>(
    value: &T,
    ctx: &crate::context::Context,
    print: impl FnOnce() -> Result<(), CliError>,
) -> Result<(), CliError> {
    if ctx.json {
        print_json(value)
    } else if !ctx.quiet {
        print()
    } else {
        Ok(())
    }
}

/// The ending of the commands that keep a JSON report beside their other files: writes
/// `value` as pretty JSON to `path` (atomically), then ends as [`report`] does.
pub fn finish_report<T: serde::Serialize>(
    path: &Path,
    value: &T,
    ctx: &crate::context::Context,
    print: impl FnOnce(&T) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let json = serde_json::to_string_pretty(value).map_err(|e| CliError::Encode {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    write_atomic(path, json.as_bytes())?;
    report(value, ctx, || print(value))
}
