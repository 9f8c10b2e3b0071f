//! `twopass render ... --part I/N`: the I-th of N shares of the render's tiles (row-major
//! tile order, contiguous ranges), written as a part file; and the assembly of a whole set
//! into the images the single-process render writes.
//!
//! Each pixel's random streams are keyed by (seed, pixel, sample), so a tile renders to the
//! same bits in any process. The light tracing pass (caustics through glass) is one pass over
//! the whole image whose splats land anywhere: part 1 carries it whole and the merge adds it
//! after assembling the tiles, the same sum the single render takes. Adaptive sampling decides
//! each pixel from its neighbours over the whole image, so `--part` refuses it (usage error).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use serde_json::{Map, Value, json};
use twopass_composite::RenderMetadata;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{write_exr_render, write_png_tonemapped};
use twopass_scene::{Camera, Scene};
use twopass_trace::{Integrator, LayerImages, RenderSettings, TileShare, tile_origins};

use super::file::{Cost, PartHeader, PartIndex, encode};
use super::set::PartSet;
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, check_dropped, to_layers};
use crate::preset::RenderKnobs;

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
    light_pass: bool,
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
        light: part.index == 1,
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
    if let Some(light) = &out.light {
        for img in &light.images {
            payload.extend(img.pixels().iter().flat_map(|p| p.to_array()));
        }
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
        extra: json!({ "light": out.light.is_some() }),
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
        light_pass: out.light.is_some(),
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
            if summary.light_pass {
                " and the light tracing pass"
            } else {
                ""
            },
            summary.seconds,
            summary.rays,
            summary.shadow_rays
        );
        outln!("wrote {}", path.display());
        Ok(())
    })
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

/// Calls `f` with the row-major index of every pixel of `tiles`, tile by tile, rows within.
fn for_each_share_pixel(
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
        "tile_size": settings.tile_size,
        "jitter": settings.jitter,
        "radiosity": job.radiosity,
        "png": job.png,
        "exposure": job.exposure,
    });
    match value {
        Value::Object(map) => map,
        _ => unreachable!("a JSON object literal"),
    }
}

#[derive(Serialize)]
struct MergeSummary {
    scene: PathBuf,
    method: String,
    width: u32,
    height: u32,
    parts: u32,
    rays: u64,
    shadow_rays: u64,
    /// Seconds of all parts together: the job's cost.
    part_seconds: f64,
    merge_seconds: f64,
    exr: Option<PathBuf>,
    png: Option<PathBuf>,
}

/// Assembles a checked set of render parts into the single render's EXR (and PNG), at
/// `--output` as `render` reads it.
pub fn merge(set: &PartSet, ctx: &Context, started: Instant) -> Result<(), CliError> {
    let s = &set.header.settings;
    let bad = |what: &str| {
        CliError::Input(format!(
            "{}: a render part without a valid {what} setting",
            set.parts[0].path.display()
        ))
    };
    let num = |k: &str| s.get(k).and_then(Value::as_u64).ok_or_else(|| bad(k));
    let (width, height) = (num("width")? as u32, num("height")? as u32);
    let tile = num("tile_size")? as u32;
    let spp = num("spp")? as u32;
    let seed = num("seed")?;
    let method: RenderMethod = s
        .get("method")
        .cloned()
        .and_then(|m| serde_json::from_value(m).ok())
        .ok_or_else(|| bad("method"))?;
    let png = s
        .get("png")
        .and_then(Value::as_bool)
        .ok_or_else(|| bad("png"))?;
    let exposure = s.get("exposure").and_then(Value::as_f64).map(|e| e as f32);
    let tiles = tile_origins(width, height, tile);
    let mut layers = LayerImages::new(width, height);
    let mut light = None;
    for part in &set.parts {
        let range = share_of(part.header.part, tiles.len());
        let mut values = part.payload.chunks_exact(3);
        let mut short = false;
        for_each_share_pixel((width, height), tile, &tiles[range], |at| {
            for img in &mut layers.images {
                match values.next() {
                    Some(v) => img.pixels_mut()[at] = glam::Vec3::from_slice(v),
                    None => short = true,
                }
            }
        });
        let carries = part.header.extra.get("light").and_then(Value::as_bool) == Some(true);
        let rest: Vec<f32> = values.flat_map(|v| v.iter().copied()).collect();
        let light_len = 6 * 3 * width as usize * height as usize;
        if short || rest.len() != if carries { light_len } else { 0 } {
            return Err(CliError::Input(format!(
                "{}: part {} holds {} values, not what its tiles{} need",
                part.path.display(),
                part.header.part,
                part.payload.len(),
                if carries { " and the light pass" } else { "" }
            )));
        }
        if carries {
            let mut l = LayerImages::new(width, height);
            for (img, chunk) in l
                .images
                .iter_mut()
                .zip(rest.chunks_exact(3 * width as usize * height as usize))
            {
                for (p, v) in img.pixels_mut().iter_mut().zip(chunk.chunks_exact(3)) {
                    *p = glam::Vec3::from_slice(v);
                }
            }
            light = Some(l);
        }
    }
    if let Some(l) = &light {
        twopass_trace::add_light(&mut layers, l);
    }
    let images = to_layers(&layers)?;
    let targets = crate::render::targets(ctx.output.as_deref(), &set.header.scene, method, png)?;
    if let Some(exr) = &targets.exr {
        crate::output::create_dir(exr.parent().unwrap_or(Path::new("")))?;
        let metadata = RenderMetadata::new(method.name(), spp, seed, set.cost.seconds);
        write_exr_render(exr, &images, &metadata)?;
    }
    if let Some(png) = &targets.png {
        let image = images.require("image")?;
        let map = match exposure {
            Some(stops) => ToneMap::from_stops(stops)?,
            None => ToneMap::auto(image, 0.99, 1.0)?,
        };
        crate::output::create_dir(png.parent().unwrap_or(Path::new("")))?;
        write_png_tonemapped(png, image, &map)?;
    }
    let summary = MergeSummary {
        scene: set.header.scene.clone(),
        method: method.name().into(),
        width,
        height,
        parts: set.header.part.of,
        rays: set.cost.rays,
        shadow_rays: set.cost.shadow_rays,
        part_seconds: set.cost.seconds,
        merge_seconds: started.elapsed().as_secs_f64(),
        exr: targets.exr,
        png: targets.png,
    };
    crate::output::report(&summary, ctx, || {
        outln!(
            "merged {} parts of {} ({} {} x {} at {spp} spp): {} rays, {} shadow rays, {:.2} s in all parts",
            summary.parts,
            summary.scene.display(),
            summary.method,
            width,
            height,
            summary.rays,
            summary.shadow_rays,
            summary.part_seconds
        );
        for p in summary.exr.iter().chain(&summary.png) {
            outln!("wrote {}", p.display());
        }
        Ok(())
    })
}

/// Where a radiosity-based render's diffuse light comes from, as the part header records it:
/// the bake file's name and CRC-32, or the solve's settings (a solve with one seed gives the
/// same solution in every process); `none` for the other methods.
pub fn radiosity_source(
    method: RenderMethod,
    bake: Option<&Path>,
    solve: &crate::solve::SolveArgs,
    ctx: &Context,
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
        None => format!("solve {:?}", solve.options(ctx.seed)),
    })
}
