//! The CLI's error type: everything a subcommand can fail with, each naming its file.

use std::path::PathBuf;

use twopass_scene::SceneError;

/// A failed subcommand. Every variant names the file or input it concerns; the process exits
/// with code 1 and prints the message on stderr.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CliError {
    /// Loading or validating a scene failed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// An output could not be encoded (PNG, JSON, ...).
    #[error("{}: cannot encode: {message}", path.display())]
    Encode {
        /// The file that was being written.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A radiosity solve cannot start for this scene (no emitter, an option out of range), or
    /// its result is refused (it created power).
    #[error("{}: {source}", path.display())]
    Solve {
        /// The scene file.
        path: PathBuf,
        /// Why the solver refused.
        source: twopass_radiosity::SolveError,
    },
    /// Encoding, writing or reading a bake output failed (the error names the file).
    #[error(transparent)]
    Bake(#[from] twopass_bake::BakeError),
    /// Writing or composing an image failed.
    #[error(transparent)]
    Composite(#[from] twopass_composite::error::CompositeError),
    /// The command's arguments are valid syntax but make no sense together or for this input.
    #[error("{0}")]
    Input(String),
    /// An option is out of the range this command can honour (exit code 2, like clap's
    /// own usage errors).
    #[error("{0}")]
    Usage(String),
}

/// An image check (a non-finite pixel, a region outside the image) as the compositor reports it.
impl From<twopass_image::ImageError> for CliError {
    fn from(e: twopass_image::ImageError) -> Self {
        Self::Composite(e.into())
    }
}

impl From<twopass_composite::WriteError> for CliError {
    fn from(e: twopass_composite::WriteError) -> Self {
        Self::Io {
            path: e.path,
            source: e.source,
        }
    }
}

impl CliError {
    /// The process exit code: 2 for a usage error (an option out of range, also when only
    /// the scene shows it, such as an element size too small for its area), 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Usage(_)
            | Self::Solve {
                source: twopass_radiosity::SolveError::Option { .. },
                ..
            } => 2,
            _ => 1,
        }
    }

    /// Whether this is a failed write to stdout because its reader went away (a closed pipe):
    /// the command stops quietly.
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, Self::Io { source, .. } if source.kind() == std::io::ErrorKind::BrokenPipe)
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
