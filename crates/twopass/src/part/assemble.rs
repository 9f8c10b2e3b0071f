//! A set of render parts assembled into the images the single-process render writes: the
//! tiles copied into place, then the light tracing pass summed from every part's splats in
//! part (path) order and added, the same sums
//! `render` takes, and the EXR and PNG written where `render` writes them for `--output`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use serde_json::Value;
use twopass_composite::RenderMetadata;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{write_exr_render, write_exr_render_rgba, write_png_tonemapped};
use twopass_trace::{Layer, LayerImages, Splat, add_light, light_image, tile_origins};

use super::render::{SPLAT_WORDS, for_each_share_pixel, share_of};
use super::set::PartSet;
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, to_layers};

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
    // Parts written before `--layers` existed wrote every layer.
    let all_layers = s.get("layers").and_then(Value::as_bool).unwrap_or(true);
    let tiles = tile_origins(width, height, tile);
    let mut layers = LayerImages::new(width, height);
    let mut splats: Vec<Vec<Splat>> = Vec::new();
    let light_paths = set.header.extra.get("light_paths").and_then(Value::as_u64);
    for part in &set.parts {
        let range = share_of(part.header.part, tiles.len());
        let mut pixels = 0;
        for_each_share_pixel((width, height), tile, &tiles[range.clone()], |_| {
            pixels += 1
        });
        let (own, rest) = part
            .payload
            .split_at((6 * 3 * pixels).min(part.payload.len()));
        let paths = part.header.extra.get("light_paths").and_then(Value::as_u64);
        if own.len() != 6 * 3 * pixels || rest.len() % SPLAT_WORDS != 0 || paths != light_paths {
            return Err(CliError::Input(format!(
                "{}: part {} holds {} values, not its tiles' {} and whole light splats of a \
                 pass of {} paths; nothing merged",
                part.path.display(),
                part.header.part,
                part.payload.len(),
                6 * 3 * pixels,
                light_paths.map_or_else(|| "no".to_owned(), |p| p.to_string())
            )));
        }
        let mut values = own.chunks_exact(3);
        for_each_share_pixel((width, height), tile, &tiles[range], |at| {
            for img in &mut layers.images {
                if let Some(v) = values.next() {
                    img.pixels_mut()[at] = glam::Vec3::from_slice(v);
                }
            }
        });
        splats.push(decode_splats(rest, width * height).map_err(|why| {
            CliError::Input(format!(
                "{}: part {}: {why}; nothing merged",
                part.path.display(),
                part.header.part
            ))
        })?);
    }
    if let Some(paths) = light_paths {
        let light = light_image(width, height, paths, splats.iter().map(Vec::as_slice));
        add_light(&mut layers, &light);
    }
    let images = to_layers(&layers)?;
    let targets = crate::render::targets(ctx.output.as_deref(), &set.header.scene, method, png)?;
    if let Some(exr) = &targets.exr {
        crate::output::create_dir(exr.parent().unwrap_or(Path::new("")))?;
        let metadata = RenderMetadata::new(method.name(), spp, seed, set.cost.seconds);
        if all_layers {
            write_exr_render(exr, &images, &metadata)?;
        } else {
            write_exr_render_rgba(exr, &images, &metadata)?;
        }
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

/// A part's light splats (pixel, layer, value) from their `f32` words, each checked.
fn decode_splats(words: &[f32], pixels: u32) -> Result<Vec<Splat>, String> {
    words
        .chunks_exact(SPLAT_WORDS)
        .map(|w| {
            let (pixel, layer) = (w[0].to_bits(), w[1].to_bits() as usize);
            match Layer::ALL.get(layer) {
                Some(&l) if pixel < pixels => Ok((pixel, l, glam::Vec3::new(w[2], w[3], w[4]))),
                _ => Err(format!(
                    "a light splat on pixel {pixel}, layer {layer}: none such"
                )),
            }
        })
        .collect()
}
