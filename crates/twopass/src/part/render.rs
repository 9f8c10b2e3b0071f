//! `twopass render ... --part I/N`: the I-th of N shares of the render's tiles (row-major
//! tile order, contiguous ranges) and of its light tracing pass's paths, written as a part
//! file (`part::assemble` merges a set).
//!
//! Each pixel's random streams are keyed by (seed, pixel, sample), so a tile renders to the
//! same bits in any process. The light tracing pass (caustics through glass) splats anywhere
//! on the image: a part traces the I-th of N runs of its path chunks and keeps their splats,
//! which the merge adds in path order, the same sum the single render takes. Adaptive sampling
//! decides each pixel from its neighbours over the whole image, so `--part` refuses it (usage
//! error).

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use serde_json::{Map, Value, json};
use twopass_scene::{Camera, Scene};
use twopass_trace::{Integrator, RenderSettings, TileShare, tile_origins};

use super::file::{Cost, PartHeader, PartIndex, encode, part_path, stem};
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, check_dropped};
use crate::preset::RenderKnobs;

/// `f32` words per light splat in a part file: the pixel and the layer (as bit patterns), the
/// value's three channels.
pub const SPLAT_WORDS: usize = 5;

/// The tiles of part `part` among `count` tiles: a contiguous range, sizes differing by one
/// at most.
pub fn share_of(part: PartIndex, count: usize) -> std::ops::Range<usize> {
    let (i, n) = (part.index as usize - 1, part.of as usize);
    count * i / n..count * (i + 1) / n
}

/// Refuses `--part` with adaptive sampling (usage error, exit 2).
pub fn check(knobs: &RenderKnobs, preset: Option<&str>) -> Result<(), CliError> {
    if knobs.adaptive.is_some() {
        let from = preset.map_or_else(
            || "--adaptive".to_owned(),
            |p| format!("--preset {p} (adaptive)"),
        );
        return Err(CliError::Usage(format!(
            "--part with {from}: adaptive sampling refines a pixel by its neighbours' first \
             pass over the whole image, so it cannot be split; render parts without it"
        )));
    }
    Ok(())
}

/// What a render part is: everything the merge needs to write the single render's files.
pub struct RenderJob<'a> {
    /// The scene file as given.
    pub scene_path: &'a Path,
    /// The loaded scene.
    pub scene: &'a Scene,
    /// The camera at the render's resolution.
    pub camera: &'a Camera,
    /// The method.
    pub method: RenderMethod,
    /// The tracer's knobs (from the flags or the preset).
    pub knobs: RenderKnobs,
    /// Where the diffuse light comes from: the solve's settings or the bake file's checksum.
    pub radiosity: String,
    /// `--png`.
    pub png: bool,
    /// `--layers`.
    pub layers: bool,
    /// `--exposure`.
    pub exposure: Option<f32>,
    /// When the command started (the part's seconds count from here).
    pub started: Instant,
}

#[derive(Serialize)]
struct PartSummary<'a> {
    part: String,
    file: &'a Path,
    tiles: [usize; 2],
    light_splats: usize,
    rays: u64,
    shadow_rays: u64,
    seconds: f64,
}

/// Renders part `part` of `job` with `integrator` and writes its part file: `--output` when
/// it ends in `.part`, else `<stem>-<method>.<I>-of-<N>.part` in the folder `--output` names
/// (default `parts`).
pub fn write_part(
    job: &RenderJob<'_>,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    part: PartIndex,
    ctx: &Context,
) -> Result<(), CliError> {
    let camera = job.camera;
    let tiles = tile_origins(camera.width, camera.height, settings.tile_size);
    let share = TileShare {
        tiles: share_of(part, tiles.len()),
        light: (part.index - 1, part.of),
    };
    let out = twopass_trace::render_share(
        job.scene,
        camera,
        integrator,
        settings,
        &share,
        &twopass_trace::RenderProgress::new(),
    )
    .ok_or_else(|| CliError::Usage("--part: adaptive sampling cannot be split".into()))?;
    check_dropped(&out.stats, job.scene_path, ctx)?;
    let mut payload = Vec::new();
    for_each_share_pixel(
        (camera.width, camera.height),
        settings.tile_size,
        &tiles[share.tiles.clone()],
        |at| {
            for img in &out.layers.images {
                payload.extend_from_slice(&img.pixels()[at].to_array());
            }
        },
    );
    let splats = out.light.as_ref().map_or(&[][..], |l| l.splats.as_slice());
    for &(pixel, layer, value) in splats {
        payload.extend([
            f32::from_bits(pixel),
            f32::from_bits(layer.index() as u32),
            value.x,
            value.y,
            value.z,
        ]);
    }
    let stem = stem(job.scene_path);
    let path = part_path(
        ctx.output.as_deref(),
        &format!("{stem}-{}", job.method.name()),
        part,
    );
    let header = PartHeader {
        kind: "render".into(),
        part,
        scene: job.scene_path.to_owned(),
        scene_fingerprint: format!("{:016x}", twopass_bake::scene_fingerprint(job.scene)),
        settings: settings_of(job, settings),
        extra: json!({ "light_paths": out.light.as_ref().map(|l| l.paths) }),
        cost: Cost {
            rays: out.stats.rays,
            shadow_rays: out.stats.shadow_rays,
            seconds: job.started.elapsed().as_secs_f64(),
        },
    };
    crate::output::write_atomic(&path, &encode(&header, &payload)?)?;
    let summary = PartSummary {
        part: part.to_string(),
        file: &path,
        tiles: [share.tiles.start, share.tiles.end],
        light_splats: splats.len(),
        rays: header.cost.rays,
        shadow_rays: header.cost.shadow_rays,
        seconds: header.cost.seconds,
    };
    crate::output::report(&summary, ctx, || {
        outln!(
            "part {} of {}: tiles {}..{} of {}{} in {:.2} s ({} rays, {} shadow rays)",
            part.index,
            part.of,
            share.tiles.start,
            share.tiles.end,
            tiles.len(),
            match &out.light {
                Some(l) => format!(
                    " and its run of the light tracing pass ({} splats of {} paths in all)",
                    l.splats.len(),
                    l.paths
                ),
                None => String::new(),
            },
            summary.seconds,
            summary.rays,
            summary.shadow_rays
        );
        outln!("wrote {}", path.display());
        Ok(())
    })
}

/// Calls `f` with the row-major index of every pixel of `tiles`, tile by tile, rows within.
pub fn for_each_share_pixel(
    (width, height): (u32, u32),
    tile: u32,
    tiles: &[(u32, u32)],
    mut f: impl FnMut(usize),
) {
    let tile = tile.max(1);
    for &(x0, y0) in tiles {
        for y in y0..(y0 + tile).min(height) {
            for x in x0..(x0 + tile).min(width) {
                f(y as usize * width as usize + x as usize);
            }
        }
    }
}

/// The settings that shape the merged image, as the part header records them.
fn settings_of(job: &RenderJob<'_>, settings: &RenderSettings) -> Map<String, Value> {
    let value = json!({
        "method": job.method.name(),
        "width": job.camera.width,
        "height": job.camera.height,
        "spp": job.knobs.spp,
        "seed": settings.seed,
        "depth": job.knobs.depth,
        "shadow_grid": job.knobs.shadow_grid,
        "gather_rays": job.knobs.gather_rays,
        "tile_size": settings.tile_size,
        "jitter": settings.jitter,
        "radiosity": job.radiosity,
        "png": job.png,
        "layers": job.layers,
        "exposure": job.exposure,
    });
    match value {
        Value::Object(map) => map,
        _ => unreachable!("a JSON object literal"),
    }
}

/// Where a radiosity-based render's diffuse light comes from, as the part header records it:
/// the bake file's name and CRC-32, or the solver's flags (a solve with one seed gives the
/// same solution in every process; the flags, not the resolved options, which carry the
/// machine's memory limit, so that nodes of different sizes agree); `none` for the other
/// methods.
pub fn radiosity_source(
    method: RenderMethod,
    bake: Option<&Path>,
    solve: &crate::solve::SolveArgs,
) -> Result<String, CliError> {
    if !method.needs_radiosity() {
        return Ok("none".into());
    }
    Ok(match bake {
        Some(file) => {
            let bytes = twopass_scene::read_bounded(file, twopass_bake::MAX_BAKE_BYTES)
                .map_err(|e| CliError::io(file, e))?;
            format!("bake {} crc32 {:08x}", stem(file), crc32fast::hash(&bytes))
        }
        None => format!("solve {solve:?}"),
    })
}
