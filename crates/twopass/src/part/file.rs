//! The part file: what one `--part I/N` run writes and `twopass merge` reads. Self-describing
//! and checked, so a truncated, corrupt or foreign part is an error naming it, never a wrong
//! merge.
//!
//! | bytes | field |
//! | --- | --- |
//! | 0..8 | magic `\x89TPPART\n` |
//! | 8..12 | format version, `u32` little endian ([`PART_FORMAT_VERSION`]) |
//! | 12..16 | header length `h` in bytes, `u32` little endian |
//! | 16..24 | payload length `p` in bytes, `u64` little endian |
//! | 24..24+h | the header, JSON ([`PartHeader`]): the job (scene fingerprint, every setting that shapes the result), which part of how many, and its cost |
//! | 24+h..24+h+p | the payload: the part's values as `f32` bit patterns, little endian ([`Payload`]) |
//! | last 4 | CRC-32 (IEEE) of every byte before it |

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::CliError;

/// The part file's magic bytes.
pub const PART_MAGIC: [u8; 8] = *b"\x89TPPART\n";

/// The part file's format version; a reader refuses any other.
pub const PART_FORMAT_VERSION: u32 = 1;

/// Bytes before the header: magic, version and the two lengths.
const FIXED: usize = 24;

/// Largest part file `merge` reads, bytes: a 16K x 16K render's six layers as `f32`.
pub const MAX_PART_BYTES: u64 = 16 << 30;

/// Which part of how many (`--part I/N`, 1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartIndex {
    /// This part, 1 to `of`.
    pub index: u32,
    /// How many parts the job has.
    pub of: u32,
}

impl std::fmt::Display for PartIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.of)
    }
}

/// Most parts a job may be split into (Slurm's default `MaxArraySize` is 1001).
pub const MAX_PARTS: u32 = 100_000;

/// Parses `--part I/N`: 1 <= I <= N <= [`MAX_PARTS`].
pub fn parse_part(s: &str) -> Result<PartIndex, String> {
    let needs = format!("must be I/N with 1 <= I <= N <= {MAX_PARTS}, such as 2/4");
    let (i, n) = s.split_once('/').ok_or_else(|| format!("{s} {needs}"))?;
    let (Ok(index), Ok(of)) = (i.trim().parse::<u32>(), n.trim().parse::<u32>()) else {
        return Err(format!("{s} {needs}"));
    };
    if index == 0 || index > of || of > MAX_PARTS {
        return Err(format!("{s} {needs}"));
    }
    Ok(PartIndex { index, of })
}

/// What a part cost, summed over the parts by `merge` into the whole job's cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Closest-hit rays traced.
    pub rays: u64,
    /// Shadow (occlusion) rays traced.
    pub shadow_rays: u64,
    /// Wall-clock seconds of the part's command, loading included.
    pub seconds: f64,
}

/// The header of a part file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartHeader {
    /// `render` or `bake`: the command that wrote it.
    pub kind: String,
    /// Which part of how many.
    pub part: PartIndex,
    /// The scene file as the command was given it.
    pub scene: std::path::PathBuf,
    /// The scene's fingerprint ([`twopass_bake::scene_fingerprint`]), hexadecimal.
    pub scene_fingerprint: String,
    /// Every setting that shapes the merged result, as named fields; parts merge only when
    /// these are equal.
    pub settings: serde_json::Map<String, serde_json::Value>,
    /// What this part holds besides its settings (a render part: the light pass's paths).
    pub extra: serde_json::Value,
    /// What the part cost.
    pub cost: Cost,
}

/// A part's values: `f32`s in the order its kind defines.
pub type Payload = Vec<f32>;

/// The bytes of a part file.
pub fn encode(header: &PartHeader, payload: &[f32]) -> Result<Vec<u8>, CliError> {
    let json = serde_json::to_vec(header).map_err(|e| CliError::Encode {
        path: "part header".into(),
        message: e.to_string(),
    })?;
    let mut bytes = Vec::with_capacity(FIXED + json.len() + 4 * payload.len() + 4);
    bytes.extend_from_slice(&PART_MAGIC);
    bytes.extend_from_slice(&PART_FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(json.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&(4 * payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&json);
    for v in payload {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32fast::hash(&bytes);
    bytes.extend_from_slice(&crc.to_le_bytes());
    Ok(bytes)
}

/// Reads and checks a part file: magic, version, lengths (a short file is "truncated"), the
/// CRC-32 and the header. Every error names `path` and what is wrong.
pub fn read(path: &Path) -> Result<(PartHeader, Payload), CliError> {
    let bytes =
        twopass_scene::read_bounded(path, MAX_PART_BYTES).map_err(|e| CliError::io(path, e))?;
    decode(&bytes).map_err(|why| CliError::Input(format!("{}: {why}", path.display())))
}

/// Reads only the header of a part file (for `slurm status`), checked like [`read`].
pub fn read_header(path: &Path) -> Result<PartHeader, CliError> {
    read(path).map(|(h, _)| h)
}

/// Decodes a part file's bytes; the error says what is wrong (without the file name).
pub fn decode(bytes: &[u8]) -> Result<(PartHeader, Payload), String> {
    if bytes.len() < 8 || bytes[..8] != PART_MAGIC {
        return Err("not a twopass part file (no part magic at its start)".into());
    }
    if bytes.len() < FIXED {
        return Err(format!(
            "truncated: {} bytes, shorter than the {FIXED}-byte part header",
            bytes.len()
        ));
    }
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != PART_FORMAT_VERSION {
        return Err(format!(
            "part format version {version}; this twopass reads version {PART_FORMAT_VERSION}"
        ));
    }
    let h = u64::from(u32_at(12));
    let p = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let want = (FIXED as u64)
        .checked_add(h)
        .and_then(|n| n.checked_add(p))
        .and_then(|n| n.checked_add(4));
    if want != Some(bytes.len() as u64) {
        let what = if want.is_none_or(|n| n > bytes.len() as u64) {
            "truncated"
        } else {
            "corrupt"
        };
        let want = want.map_or_else(|| "more than 2^64".to_owned(), |n| n.to_string());
        return Err(format!(
            "{what}: {} bytes, its header says {want}",
            bytes.len()
        ));
    }
    let body = bytes.len() - 4;
    let recorded = u32::from_le_bytes(bytes[body..].try_into().expect("4 bytes"));
    if crc32fast::hash(&bytes[..body]) != recorded {
        return Err("corrupt: its CRC-32 differs from the one recorded in it".into());
    }
    let (h, p) = (h as usize, p as usize);
    let header: PartHeader = serde_json::from_slice(&bytes[FIXED..FIXED + h])
        .map_err(|e| format!("corrupt header ({e})"))?;
    if p % 4 != 0 {
        return Err(format!(
            "corrupt: a payload of {p} bytes is not whole f32 values"
        ));
    }
    let payload = bytes[FIXED + h..FIXED + h + p]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    Ok((header, payload))
}

/// The scene file's stem, which names the outputs.
pub fn stem(scene: &Path) -> String {
    scene
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Where a part file goes: `output` itself when it ends in `.part`, else
/// `<name>.<I>-of-<N>.part` in the folder `output` names (default `parts`).
pub fn part_path(output: Option<&Path>, name: &str, part: PartIndex) -> PathBuf {
    match output {
        Some(p) if p.extension().is_some_and(|e| e == "part") => p.to_owned(),
        _ => output
            .unwrap_or(Path::new("parts"))
            .join(format!("{name}.{}-of-{}.part", part.index, part.of)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> PartHeader {
        PartHeader {
            kind: "render".into(),
            part: PartIndex { index: 2, of: 3 },
            scene: "s.toml".into(),
            scene_fingerprint: "00ff".into(),
            settings: serde_json::Map::new(),
            extra: serde_json::Value::Null,
            cost: Cost::default(),
        }
    }

    #[test]
    fn round_trip_and_every_damage_is_named() {
        let bytes = encode(&header(), &[1.0, -0.0, f32::MIN_POSITIVE]).unwrap();
        let (h, p) = decode(&bytes).unwrap();
        assert_eq!(h, header());
        assert_eq!(
            p.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            [1.0f32, -0.0, f32::MIN_POSITIVE].map(f32::to_bits)
        );
        let n = bytes.len();
        let cut = decode(&bytes[..n - 1]).unwrap_err();
        assert_eq!(
            cut,
            format!("truncated: {} bytes, its header says {n}", n - 1)
        );
        assert!(
            decode(&bytes[..10])
                .unwrap_err()
                .starts_with("truncated: 10 bytes")
        );
        let mut flipped = bytes.clone();
        flipped[n - 6] ^= 1;
        assert_eq!(
            decode(&flipped).unwrap_err(),
            "corrupt: its CRC-32 differs from the one recorded in it"
        );
        assert!(
            decode(b"P6 hello")
                .unwrap_err()
                .starts_with("not a twopass part file")
        );
    }

    #[test]
    fn part_index_parses_within_range() {
        assert_eq!(parse_part("2/4"), Ok(PartIndex { index: 2, of: 4 }));
        for bad in ["0/4", "5/4", "4", "a/b", "1/0", "-1/2"] {
            assert!(parse_part(bad).is_err(), "{bad}");
        }
    }
}
