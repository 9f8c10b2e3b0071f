//! Options shared by every subcommand, and the progress bar they all use.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use clap::Args;
use twopass_scene::{Camera, ReadPolicy};

use crate::error::CliError;
use indicatif::{ProgressBar, ProgressStyle};

/// Options every subcommand accepts, so scripts can drive them the same way.
#[derive(Debug, Clone, Args)]
pub struct Context {
    /// Output file, or directory for commands that write several files (created if missing).
    /// `render`: `x.exr` or `x.png` is that file; a path without an image extension (or ending
    /// in `/`) is a directory.
    #[arg(long, short, global = true)]
    pub output: Option<PathBuf>,
    /// Image width in pixels, overriding the scene's (alone: keeps the aspect ratio).
    #[arg(long, global = true, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels, overriding the scene's (alone: keeps the aspect ratio).
    #[arg(long, global = true, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Seed of every random sequence; the same seed gives the same result on any thread count.
    #[arg(long, global = true, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Print nothing but errors (and the JSON summary with --json).
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Print a machine-readable JSON summary on stdout instead of the human report.
    #[arg(long, global = true)]
    pub json: bool,
    /// Read only files inside the scene's folder: refuse OBJ meshes and MTL libraries that a
    /// scene names elsewhere (absolute paths, `..`, symbolic links out). Use it for scenes
    /// from others, which could otherwise make twopass read any file you can.
    #[arg(long, global = true)]
    pub confine: bool,
}

impl Context {
    /// Loads a scene under the read policy the options ask for (see `--confine`).
    pub fn load_scene(
        &self,
        path: &Path,
    ) -> Result<(twopass_scene::Scene, Vec<twopass_scene::Warning>), CliError> {
        let policy = if self.confine {
            ReadPolicy::confined(path)?
        } else {
            ReadPolicy::unconfined()
        };
        Ok(twopass_scene::load_with(path, &policy)?)
    }

    /// `camera` at the resolution `--width`/`--height` ask for, refused (usage error) when
    /// that image would be larger than [`Camera::MAX_PIXELS`] or a side than
    /// [`Camera::MAX_SIDE`].
    pub fn camera(&self, camera: &Camera) -> Result<Camera, CliError> {
        let camera = resized(camera, self.width, self.height)?;
        let pixels = u64::from(camera.width) * u64::from(camera.height);
        let need = pixels * RENDER_BYTES_PER_PIXEL;
        let limit = memory_limit();
        if need > limit {
            return Err(CliError::Usage(format!(
                "--width/--height: a {} x {} image needs about {:.1} GiB ({RENDER_BYTES_PER_PIXEL} \
                 bytes per pixel), more than the {:.1} GiB a command may take here; render a \
                 smaller image",
                camera.width,
                camera.height,
                need as f64 / f64::from(1u32 << 30),
                limit as f64 / f64::from(1u32 << 30)
            )));
        }
        Ok(camera)
    }

    /// The output path, or `default` when `--output` was not given.
    pub fn output_or<'a>(&'a self, default: &'a Path) -> &'a Path {
        self.output.as_deref().unwrap_or(default)
    }

    /// Whether human-readable progress and reports should be printed.
    pub fn chatty(&self) -> bool {
        !self.quiet && !self.json
    }

    /// A progress bar of `len` steps labelled `message`: drawn on a terminal, hidden when quiet,
    /// with `--json`, in CI (`CI` set) or when stderr is not a terminal.
    pub fn progress(&self, len: u64, message: &str) -> ProgressBar {
        let visible =
            self.chatty() && std::env::var_os("CI").is_none() && std::io::stderr().is_terminal();
        if !visible {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new(len).with_message(message.to_owned());
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:>12} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}",
            )
            .expect("static progress template is valid")
            .progress_chars("=> "),
        );
        bar
    }
}

/// Peak memory of a render per image pixel, bytes: the film's layers, the composite, the
/// encoded files and the adaptive pass's buffers. Every method measured about 317 bytes per
/// pixel at 2048 x 2048 (docs/benchmarks.md, "Render memory"); this keeps a margin over that.
pub const RENDER_BYTES_PER_PIXEL: u64 = 336;

/// Memory a command may take, bytes: `TWOPASS_MEMORY_LIMIT` (bytes) when set, else four
/// fifths of the machine's memory (`MemTotal` of /proc/meminfo), or 16 GiB where that cannot
/// be read.
pub fn memory_limit() -> u64 {
    if let Some(bytes) = std::env::var("TWOPASS_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
    {
        return bytes;
    }
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024 / 5 * 4)
        })
        .unwrap_or(16 << 30)
}

/// `camera` at `width` x `height` (either may be absent: see [`Camera::with_resolution`]),
/// refused as a usage error beyond [`Camera::check_resolution`].
pub fn resized(
    camera: &Camera,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<Camera, CliError> {
    camera
        .try_with_resolution(width, height)
        .map_err(|p| CliError::Usage(format!("--width/--height: {p}")))
}
