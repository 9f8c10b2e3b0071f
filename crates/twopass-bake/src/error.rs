//! The crate's errors: why bytes are not a usable bake ([`BakeProblem`]) and a failed read or
//! write naming its file ([`BakeError`]).

use std::fmt;
use std::path::{Path, PathBuf};

use twopass_composite::WriteError;
use twopass_radiosity::InvalidMesh;

use crate::fingerprint::Fingerprint;

/// Why bytes are not a usable bake file for a scene.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum BakeProblem {
    /// The bytes do not start with the bake file's magic number.
    NotABakeFile,
    /// The file was written in another layout version.
    UnsupportedVersion {
        /// The version in the file.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The file is shorter than its header says.
    Truncated {
        /// Bytes the header announces (header included).
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// The file is longer than its header says.
    TrailingBytes {
        /// Bytes after the payload.
        extra: u64,
    },
    /// The payload's CRC-32 differs from the stored one: the file was damaged.
    Checksum {
        /// CRC-32 in the header.
        stored: u32,
        /// CRC-32 of the payload as read.
        computed: u32,
    },
    /// The payload does not decode.
    Decode {
        /// The decoder's message.
        message: String,
    },
    /// The bake belongs to another scene (or a changed one).
    SceneMismatch {
        /// Which fingerprint differs.
        what: Fingerprint,
        /// The scene's fingerprint.
        scene: u64,
        /// The fingerprint stored in the bake.
        bake: u64,
    },
    /// The element mesh is inconsistent.
    Mesh(InvalidMesh),
    /// A per-vertex array has the wrong length or a non-finite value, or a vertex names an
    /// object the scene does not have.
    Values {
        /// Which array.
        what: &'static str,
        /// The offending index (or the length found, for a wrong length).
        index: usize,
        /// What is wrong.
        problem: &'static str,
    },
    /// A lightmap bake (`.lightmap.glb` and its EXR) that cannot serve the scene: what is
    /// wrong with it.
    Lightmap(String),
}

impl fmt::Display for BakeProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotABakeFile => write!(f, "not a twopass bake file (wrong magic number)"),
            Self::UnsupportedVersion { found, supported } => write!(
                f,
                "bake file version {found}, this build reads version {supported}: bake again"
            ),
            Self::Truncated { expected, found } => write!(
                f,
                "truncated bake file: {found} bytes, the header announces {expected}"
            ),
            Self::TrailingBytes { extra } => {
                write!(f, "bake file has {extra} bytes after its payload")
            }
            Self::Checksum { stored, computed } => write!(
                f,
                "damaged bake file: CRC-32 {computed:08x}, the header says {stored:08x}"
            ),
            Self::Decode { message } => write!(f, "bake payload does not decode: {message}"),
            Self::SceneMismatch { what, scene, bake } => {
                let what = match what {
                    Fingerprint::Geometry => "geometry",
                    Fingerprint::Lighting => "emission or diffuse reflectance",
                };
                write!(
                    f,
                    "bake was made for another scene: {what} fingerprint {bake:016x}, \
                     the scene's is {scene:016x}; bake the scene again"
                )
            }
            Self::Mesh(m) => write!(f, "{m}"),
            Self::Values {
                what,
                index,
                problem,
            } => write!(f, "bake {what} [{index}]: {problem}"),
            Self::Lightmap(message) => write!(f, "lightmap bake: {message}"),
        }
    }
}

impl std::error::Error for BakeProblem {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Mesh(m) => Some(m),
            _ => None,
        }
    }
}

/// A failed bake read or write, naming its file.
#[derive(Debug)]
#[non_exhaustive]
pub enum BakeError {
    /// Reading, writing or renaming the file failed.
    Io {
        /// The file (or folder) concerned.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not a usable bake for the scene.
    Invalid {
        /// The bake file.
        path: PathBuf,
        /// What is wrong with it.
        problem: BakeProblem,
    },
    /// An output could not be encoded.
    Encode {
        /// The file that was being written, or the format's name when encoding to memory.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

impl BakeError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            source,
        }
    }
}

impl From<WriteError> for BakeError {
    fn from(e: WriteError) -> Self {
        Self::Io {
            path: e.path,
            source: e.source,
        }
    }
}

impl fmt::Display for BakeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::Invalid { path, problem } => write!(f, "{}: {problem}", path.display()),
            Self::Encode { path, message } => {
                write!(f, "{}: cannot encode: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for BakeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Invalid { problem, .. } => Some(problem),
            Self::Encode { .. } => None,
        }
    }
}
