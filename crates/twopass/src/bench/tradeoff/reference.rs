//! The converged reference of the tradeoff sweep: the reference path tracer run long, cached on
//! disk with its settings so it is rendered once per scene, size and sample count.
//!
//! Cache files, in the cache directory: `<stem>-reference-<key>.exr` (the image) and
//! `<stem>-reference-<key>.json` (the settings it was rendered with, its render time and its
//! own noise). `<key>` is the CRC-32 of the settings, which include a checksum of the loaded
//! scene (geometry, materials, objects, emitters, camera), so editing the scene invalidates
//! the cache. The JSON is written last: an interrupted render leaves no usable entry.
//!
//! The reference is rendered as two independent halves of `spp / 2` samples per pixel on
//! average each, with seeds no sweep run uses, and their mean is the reference. A half differs
//! from the mean by half the difference of the halves, whose variance is that of the mean: the
//! relative RMSE of a half against the mean is the noise of the reference itself, the floor
//! below which no measured error means anything.
//!
//! **Where the samples go.** Two pilot renders of `spp / 16` samples per pixel (at least 16),
//! with seeds of their own, measure where the path tracer is noisy; both halves then spend
//! their samples in proportion to that noise ([`SampleBudget::from_pilots`]): on the Cornell
//! spheres half of the squared error of a uniform render sits in 1 % of the pixels, those that
//! see a caustic through a sphere. Each pixel stays the unbiased mean of its own samples, the
//! pilots are independent of both halves, so the halves stay independent and the noise
//! measure above holds. The pilots are not part of the reference image; their time is part of
//! its render time.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use twopass_composite::image::Image;
use twopass_composite::metric::compare;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{read_exr, write_atomic, write_exr};
use twopass_scene::Scene;
use twopass_trace::{Reference, ReferenceSettings, RenderSettings, SampleBudget};

use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{render_budgeted_with_bar, render_with_bar};

/// Seeds of the two halves are the sweep's seed mixed with this, so no sweep run shares a
/// sample sequence with the reference (shared samples would hide part of the error).
const REFERENCE_SEED_MIX: u64 = 0x7265_6665_7265_6e63;
/// The pilots' seeds are the sweep's seed mixed with this (see [`REFERENCE_SEED_MIX`]).
const PILOT_SEED_MIX: u64 = 0x7069_6c6f_7473_0000;
/// Each pilot takes this fraction (1 / `PILOT_SHARE`) of the reference's samples per pixel.
const PILOT_SHARE: u32 = 16;
/// Fewest samples per pixel of a pilot.
const PILOT_MIN_SPP: u32 = 16;

/// Samples per pixel of each of the two pilot renders of a reference of `spp`.
fn pilot_spp(spp: u32) -> u32 {
    (spp / PILOT_SHARE).max(PILOT_MIN_SPP)
}

/// What the cached image was rendered with; an entry is used only when every field matches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceKey {
    /// The scene file as given.
    pub scene: PathBuf,
    /// [`twopass_bake::scene_fingerprint`] of the loaded scene (geometry, lighting, materials,
    /// camera), 16 hex digits.
    pub scene_checksum: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel of the mean of both halves, on average over the image.
    pub spp: u32,
    /// How the samples are spread over the pixels (`noise of 2 pilots of N spp`).
    pub allocation: String,
    /// The sweep's seed (the halves use seeds derived from it).
    pub seed: u64,
    /// Longest path, surface vertices.
    pub max_depth: u32,
    /// Path length from which Russian roulette may end a path.
    pub roulette_depth: u32,
    /// Who counts the caustic paths (`path tracing` or `light tracing`).
    pub caustics: String,
    /// Continuations per camera sample from its first diffuse or glossy vertex (`planned by a
    /// pilot`, or the count).
    pub splits: String,
    /// The sample values' sequence ([`twopass_trace::sampler::SAMPLE_SEQUENCE`]).
    pub sampler: String,
    /// Version of twopass that rendered it.
    pub version: String,
}

/// A cache entry's record.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Record {
    key: ReferenceKey,
    /// Wall-clock seconds of both halves.
    render_seconds: f64,
    /// Relative RMSE of the mean from its own noise, unitless.
    noise_rel_rmse: f64,
}

/// The converged reference image and what it cost.
#[derive(Debug)]
pub struct Converged {
    /// The image, W/(m^2 sr) per channel.
    pub image: Image,
    /// Its settings.
    pub key: ReferenceKey,
    /// Wall-clock seconds it took to render (when it was rendered, possibly in an earlier run).
    pub render_seconds: f64,
    /// Relative RMSE of the reference from its own noise: the floor of every measured error.
    pub noise_rel_rmse: f64,
    /// Whether it came from the cache.
    pub cached: bool,
    /// The cached EXR.
    pub exr: PathBuf,
}

/// The key of a reference for this scene, camera size and settings.
pub fn key(
    scene: &Scene,
    path: &Path,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> ReferenceKey {
    let settings = ReferenceSettings::default();
    ReferenceKey {
        scene: path.to_owned(),
        scene_checksum: format!("{:016x}", twopass_bake::scene_fingerprint(scene)),
        width,
        height,
        spp,
        allocation: format!("noise of 2 pilots of {} spp", pilot_spp(spp)),
        seed,
        max_depth: settings.max_depth,
        roulette_depth: settings.roulette_depth,
        caustics: match (settings.caustics, settings.light_paths) {
            (twopass_trace::Caustics::PathTracing, _) => "path tracing".to_owned(),
            (twopass_trace::Caustics::LightTracing, twopass_trace::LightPaths::Planned) => {
                "light tracing, light paths planned by a pilot".to_owned()
            }
            (twopass_trace::Caustics::LightTracing, twopass_trace::LightPaths::PerSample(r)) => {
                format!("light tracing, {r} light paths per camera sample")
            }
        },
        splits: match settings.splits {
            twopass_trace::PathSplits::Planned => "planned by a pilot".to_owned(),
            twopass_trace::PathSplits::Fixed(n) => n.to_string(),
        },
        sampler: twopass_trace::sampler::SAMPLE_SEQUENCE.to_owned(),
        version: env!("CARGO_PKG_VERSION").to_owned(),
    }
}

/// The cache's file names for `key` (EXR, JSON).
fn files(dir: &Path, key: &ReferenceKey) -> (PathBuf, PathBuf) {
    let json = serde_json::to_string(key).expect("key serializes");
    let stem = key
        .scene
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());
    let name = format!(
        "{stem}-reference-{:08x}-{}x{}-{}spp",
        crc32fast::hash(json.as_bytes()),
        key.width,
        key.height,
        key.spp
    );
    (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}.json")),
    )
}

/// The cached entry for `key`, when there is a complete one.
fn cached(dir: &Path, key: &ReferenceKey) -> Option<Converged> {
    let (exr, json) = files(dir, key);
    let record: Record = serde_json::from_slice(&crate::output::read_small(&json).ok()?).ok()?;
    if &record.key != key {
        return None;
    }
    let image = read_exr(&exr).ok()?;
    if image.size() != (key.width, key.height) || image.first_non_finite().is_some() {
        return None;
    }
    Some(Converged {
        image,
        key: record.key,
        render_seconds: record.render_seconds,
        noise_rel_rmse: record.noise_rel_rmse,
        cached: true,
        exr,
    })
}

/// The converged reference for `key`: from the cache in `dir`, or rendered now (two halves,
/// with a progress bar) and stored there.
pub fn converged(
    scene: &Scene,
    camera: &twopass_scene::Camera,
    dir: &Path,
    key: ReferenceKey,
    ctx: &Context,
) -> Result<Converged, CliError> {
    if let Some(hit) = cached(dir, &key) {
        return Ok(hit);
    }
    let integrator = Reference::new(scene, ReferenceSettings::default());
    let started = Instant::now();
    let mut pilots = Vec::with_capacity(2);
    for pilot in 0..2u64 {
        let settings = RenderSettings {
            samples_per_pixel: pilot_spp(key.spp),
            seed: (key.seed ^ PILOT_SEED_MIX).wrapping_add(pilot),
            ..RenderSettings::default()
        };
        let label = format!("reference pilot {}/2", pilot + 1);
        let out = render_with_bar(scene, camera, &integrator, &settings, &label, ctx)?;
        pilots.push(out.layers.composite());
    }
    let budget = SampleBudget::from_pilots(&pilots[0], &pilots[1], key.spp.div_ceil(2))
        .expect("pilots of the camera's size");
    let mut halves = Vec::with_capacity(2);
    for half in 0..2u64 {
        let settings = RenderSettings {
            samples_per_pixel: key.spp.div_ceil(2),
            seed: (key.seed ^ REFERENCE_SEED_MIX).wrapping_add(half),
            ..RenderSettings::default()
        };
        let label = format!("reference {}/2", half + 1);
        let out =
            render_budgeted_with_bar(scene, camera, &integrator, &settings, &budget, &label, ctx)?;
        halves.push(out.layers.composite());
    }
    let render_seconds = started.elapsed().as_secs_f64();
    let mean = Image::from_fn(key.width, key.height, |x, y| {
        0.5 * (halves[0].get(x, y) + halves[1].get(x, y))
    });
    mean.check_finite("reference")?;
    let display = ToneMap::auto_default(&mean)?;
    let noise_rel_rmse = compare(&halves[0], &mean, &display)?.rel_rmse;
    let (exr, json) = files(dir, &key);
    crate::output::create_dir(dir)?;
    write_exr(&exr, &mean)?;
    let record = Record {
        key: key.clone(),
        render_seconds,
        noise_rel_rmse,
    };
    let text = serde_json::to_string_pretty(&record).expect("record serializes");
    write_atomic(&json, text.as_bytes())?;
    Ok(Converged {
        image: mean,
        key,
        render_seconds,
        noise_rel_rmse,
        cached: false,
        exr,
    })
}
