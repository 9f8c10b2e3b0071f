//! Reading input files: only regular files of bounded size, optionally confined to the scene's
//! folder, and line lookup for messages.
//!
//! Every file the loader reads (the scene, its OBJ meshes, their MTL libraries) goes through
//! [`read_text`], so no input can make loading read without bound (`/dev/zero`, a FIFO, a
//! growing file) or reach outside the folder a caller confined it to.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::SceneError;

/// Largest scene file (TOML) read, bytes (64 MiB: a million objects fit in far less).
pub const MAX_SCENE_BYTES: u64 = 64 << 20;
/// Largest OBJ mesh file read, bytes (1 GiB: about 20 million triangles).
pub const MAX_OBJ_BYTES: u64 = 1 << 30;
/// Largest MTL material library read, bytes (16 MiB).
pub const MAX_MTL_BYTES: u64 = 16 << 20;
/// Largest glTF file (`.gltf` JSON or `.glb`) and largest external glTF buffer or image read,
/// bytes (1 GiB each, as an OBJ).
pub const MAX_GLTF_BYTES: u64 = 1 << 30;
/// Largest texture file read, bytes (256 MiB; its decoded size is bounded by
/// [`crate::MAX_TEXTURE_PIXELS`]).
pub const MAX_TEXTURE_BYTES: u64 = 256 << 20;

/// Which files a scene may make the loader read.
///
/// Scene files name meshes by path and OBJ files name material libraries by path; by default
/// any readable path is followed, as with any program that opens the files it is told to. A
/// scene from someone else can use that to make a render read (and, through error messages,
/// show parts of) files elsewhere on the machine, such as `file = "/etc/passwd"`. With
/// [`ReadPolicy::confined`], every path is resolved (symbolic links and `..` included) and must
/// lie inside the folder of the scene file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReadPolicy {
    /// The folder every read must stay inside, canonical; `None` allows any path.
    root: Option<PathBuf>,
}

impl ReadPolicy {
    /// Any path the process can read is allowed (the default).
    pub fn unconfined() -> Self {
        Self::default()
    }

    /// Reads are confined to the folder holding `scene` (resolved when loading starts).
    pub fn confined(scene: &Path) -> Result<Self, SceneError> {
        let dir = match scene.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let root = dir.canonicalize().map_err(|source| SceneError::Io {
            path: dir.to_owned(),
            source,
        })?;
        Ok(Self { root: Some(root) })
    }

    /// The folder reads are confined to, if any.
    pub fn root(&self) -> Option<&Path> {
        self.root.as_deref()
    }
}

/// Why a file that is not a regular file is refused (the message [`read_bounded`] gives).
const NOT_REGULAR: &str = "not a regular file (a device, pipe or directory is not read as one)";

/// Reads `path` whole if it is a regular file of at most `limit` bytes. Anything else (a
/// device such as `/dev/zero`, a pipe, a directory, a larger file, a file that grows past the
/// limit while it is read) is an error of kind [`std::io::ErrorKind::InvalidInput`] that says
/// why, so no input makes a reader run without bound. Every file reader of the workspace
/// (scenes, meshes, libraries, bakes, manifests, presets) goes through it.
pub fn read_bounded(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let refuse = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, m);
    let not_regular = || refuse(NOT_REGULAR.into());
    // The type is checked before opening: opening a FIFO for reading blocks until a writer
    // comes, which may be never. (`metadata` follows symbolic links, as `open` does.)
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path)?;
    // Checked again on what was opened, in case the path changed in between.
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > limit {
        return Err(refuse(format!(
            "{} bytes, more than the {limit} bytes read at most",
            meta.len()
        )));
    }
    // The file may grow while it is read: never take more than the limit.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(refuse(format!(
            "grew past the {limit} bytes read at most while being read"
        )));
    }
    Ok(bytes)
}

/// What kind of input a file is, for its size limit and messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum InputKind {
    Scene,
    Obj,
    Mtl,
    Gltf,
    GltfBuffer,
    GltfImage,
    Texture,
}

impl InputKind {
    fn limit(self) -> u64 {
        match self {
            Self::Scene => MAX_SCENE_BYTES,
            Self::Obj => MAX_OBJ_BYTES,
            Self::Mtl => MAX_MTL_BYTES,
            Self::Gltf | Self::GltfBuffer | Self::GltfImage => MAX_GLTF_BYTES,
            Self::Texture => MAX_TEXTURE_BYTES,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Self::Scene => "scene file",
            Self::Obj => "OBJ mesh",
            Self::Mtl => "MTL library",
            Self::Gltf => "glTF file",
            Self::GltfBuffer => "glTF buffer",
            Self::GltfImage => "glTF image",
            Self::Texture => "texture",
        }
    }
}

/// Reads `path` as UTF-8 text if it is a regular file no larger than its kind's limit and,
/// under a confining policy, inside the allowed folder.
pub(crate) fn read_text(
    path: &Path,
    kind: InputKind,
    policy: &ReadPolicy,
) -> Result<String, SceneError> {
    let bytes = read_bytes(path, kind, policy)?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        SceneError::Input {
            path: path.to_owned(),
            problem: format!("line {line}: not UTF-8 text"),
        }
    })
}

/// Reads `path` whole if it is a regular file no larger than its kind's limit and, under a
/// confining policy, inside the allowed folder.
pub(crate) fn read_bytes(
    path: &Path,
    kind: InputKind,
    policy: &ReadPolicy,
) -> Result<Vec<u8>, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_owned(),
        source,
    };
    let refuse = |problem: String| SceneError::Input {
        path: path.to_owned(),
        problem,
    };
    if let Some(root) = policy.root() {
        let real = path.canonicalize().map_err(io)?;
        if !real.starts_with(root) {
            return Err(refuse(format!(
                "{} lies outside the scene's folder {} and reads are confined to it",
                kind.name(),
                root.display()
            )));
        }
    }
    read_bounded(path, kind.limit()).map_err(|e| {
        if e.kind() == std::io::ErrorKind::InvalidInput {
            refuse(format!("{}: {e}", kind.name()))
        } else {
            io(e)
        }
    })
}

/// 1-based line and column of byte offsets in a text, in O(log lines) per lookup.
pub(crate) struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    pub(crate) fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Self { starts }
    }

    /// (line, column) of byte `offset`, both 1-based; the column counts bytes.
    pub(crate) fn line_col(&self, offset: usize) -> (usize, usize) {
        let line = self.starts.partition_point(|&s| s <= offset).max(1);
        (line, offset - self.starts[line - 1] + 1)
    }
}

/// `s` with control characters (and other characters a terminal would act on) escaped, for
/// names and values quoted in messages.
pub fn printable(s: &str) -> String {
    if !s.chars().any(|c| c.is_control()) {
        return s.to_owned();
    }
    s.chars()
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_columns() {
        let idx = LineIndex::new("ab\ncd\n\nx");
        assert_eq!(idx.line_col(0), (1, 1));
        assert_eq!(idx.line_col(1), (1, 2));
        assert_eq!(idx.line_col(3), (2, 1));
        assert_eq!(idx.line_col(6), (3, 1));
        assert_eq!(idx.line_col(7), (4, 1));
        assert_eq!(idx.line_col(100), (4, 94));
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("plain"), "plain");
        assert_eq!(printable("a\u{1b}[2Jb\n"), "a\\u{1b}[2Jb\\n");
    }

    #[test]
    fn special_files_are_refused() {
        let err = read_text(
            Path::new("/dev/zero"),
            InputKind::Obj,
            &ReadPolicy::default(),
        )
        .unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
    }
}
