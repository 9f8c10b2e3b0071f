//! The converged reference of a room: the CLI's own path tracer (`twopass render --method
//! reference`) run in a child process, cached beside the room as `reference-<S>spp.exr` with a
//! JSON sidecar `reference-<S>spp.json` holding its key: checksums of the scene and mesh
//! text, the samples per pixel and the seed (and the twopass version). A key that differs
//! renders it again; the sidecar is written last, so an interrupted render leaves no entry.
//!
//! It is the mean of two halves of `S / 2` samples per pixel with seeds of their own (the
//! bench's seed mixed with [`REFERENCE_SEED_MIX`], so no bake shares its sample sequence). A
//! half differs from the mean by half the halves' difference, whose variance is the mean's:
//! the relative RMSE of a half against the mean is the reference's own noise, the floor below
//! which no measured error means anything. The first half is kept beside the mean
//! (`reference-<S>spp-half0.exr`) so the bench can measure it as it measures a bake: what a
//! perfect image would score against this reference.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use twopass_composite::Image;
use twopass_composite::metric::compare;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{read_exr, write_exr};

use super::child::run_twopass;
use crate::error::CliError;

/// The halves' seeds are the bench's seed mixed with this, then + 0 and + 1.
const REFERENCE_SEED_MIX: u64 = 0x6261_6b65_7265_6600;

/// What a cached reference was rendered from; it is used only when every field matches.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceKey {
    /// CRC-32 of the scene file's text, 8 hex digits.
    pub scene_crc32: String,
    /// CRC-32 of the OBJ mesh's text, 8 hex digits.
    pub mesh_crc32: String,
    /// Samples per pixel of the mean of both halves.
    pub spp: u32,
    /// The bench's seed (the halves use seeds derived from it).
    pub seed: u64,
    /// Version of twopass that rendered it.
    pub version: String,
}

impl ReferenceKey {
    /// The key of a room's reference from its texts, `spp` and `seed`.
    pub fn new(scene: &str, mesh: &str, spp: u32, seed: u64) -> Self {
        Self {
            scene_crc32: format!("{:08x}", crc32fast::hash(scene.as_bytes())),
            mesh_crc32: format!("{:08x}", crc32fast::hash(mesh.as_bytes())),
            spp,
            seed,
            version: env!("CARGO_PKG_VERSION").to_owned(),
        }
    }
}

/// The sidecar's content.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Record {
    key: ReferenceKey,
    /// Wall-clock seconds of both halves.
    render_seconds: f64,
    /// Relative RMSE of a half against the mean.
    noise_rel_rmse: f64,
}

/// A room's converged reference.
#[derive(Debug)]
pub struct Converged {
    /// The image, W/(m^2 sr).
    pub image: Image,
    /// Its first half (half the samples), which differs from it by its noise.
    pub half: Image,
    /// Wall-clock seconds of its render (when it was rendered, possibly in an earlier run).
    pub render_seconds: f64,
    /// Relative RMSE of the reference from its own noise.
    pub noise_rel_rmse: f64,
    /// Whether it came from the cache.
    pub cached: bool,
    /// The EXR.
    pub exr: PathBuf,
}

/// The cache files in `dir` for `spp`: (image, sidecar, first half).
fn files(dir: &Path, spp: u32) -> (PathBuf, PathBuf, PathBuf) {
    (
        dir.join(format!("reference-{spp}spp.exr")),
        dir.join(format!("reference-{spp}spp.json")),
        dir.join(format!("reference-{spp}spp-half0.exr")),
    )
}

/// The cached reference for `key` in `dir`, when there is a complete one of `size`.
fn cached(dir: &Path, key: &ReferenceKey, size: (u32, u32)) -> Option<Converged> {
    let (exr, json, half) = files(dir, key.spp);
    let record: Record = serde_json::from_slice(&crate::output::read_small(&json).ok()?).ok()?;
    if &record.key != key {
        return None;
    }
    let image = read_exr(&exr).ok()?;
    let half = read_exr(&half).ok()?;
    let sound = |i: &Image| i.size() == size && i.first_non_finite().is_none();
    if !(sound(&image) && sound(&half)) {
        return None;
    }
    Some(Converged {
        image,
        half,
        render_seconds: record.render_seconds,
        noise_rel_rmse: record.noise_rel_rmse,
        cached: true,
        exr,
    })
}

/// The reference of the scene at `scene` (of camera `size`) for `key`: from the cache in
/// `dir`, or rendered now by two child processes (with `threads` worker threads when given)
/// and stored there.
pub fn converged(
    dir: &Path,
    scene: &Path,
    key: &ReferenceKey,
    size: (u32, u32),
    threads: Option<u32>,
) -> Result<Converged, CliError> {
    if let Some(hit) = cached(dir, key, size) {
        return Ok(hit);
    }
    let (exr, json, first) = files(dir, key.spp);
    let mut halves = Vec::with_capacity(2);
    let mut render_seconds = 0.0;
    for half in 0..2u64 {
        let path = dir.join(format!("reference-{}spp-half{half}.exr", key.spp));
        let mut args: Vec<OsString> = vec!["render".into(), scene.into()];
        let seed = (key.seed ^ REFERENCE_SEED_MIX).wrapping_add(half);
        let words = format!(
            "--method reference --spp {} --seed {seed} --quiet",
            key.spp.div_ceil(2)
        );
        args.extend(words.split_whitespace().map(OsString::from));
        if let Some(t) = threads {
            args.extend(["--threads".into(), t.to_string().into()]);
        }
        args.extend(["--output".into(), path.clone().into()]);
        render_seconds += run_twopass(&args)?.seconds;
        let image = read_exr(&path)?;
        if image.size() != size {
            return Err(CliError::Input(format!(
                "{}: the reference is {:?} pixels, the room's camera {size:?}",
                path.display(),
                image.size()
            )));
        }
        halves.push(image);
        if path != first {
            let _ = std::fs::remove_file(&path);
        }
    }
    let mean = Image::from_fn(size.0, size.1, |x, y| {
        0.5 * (halves[0].get(x, y) + halves[1].get(x, y))
    });
    mean.check_finite("reference")?;
    let noise_rel_rmse = compare(&halves[0], &mean, &ToneMap::auto_default(&mean)?)?.rel_rmse;
    write_exr(&exr, &mean)?;
    let record = Record {
        key: key.clone(),
        render_seconds,
        noise_rel_rmse,
    };
    let text = serde_json::to_string_pretty(&record).expect("record serializes");
    crate::output::write_atomic(&json, text.as_bytes())?;
    let half = halves.swap_remove(0);
    Ok(Converged {
        image: mean,
        half,
        render_seconds,
        noise_rel_rmse,
        cached: false,
        exr,
    })
}
