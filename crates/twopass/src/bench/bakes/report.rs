//! The report of `twopass bench bakes`: what is measured per room and image (JSON fields),
//! and its tables.

use serde::Serialize;

use super::metric::{DEVIATION_FLOOR, ImageError, OFF_THRESHOLD};
use crate::bench::memory::fmt_mib;
use crate::error::CliError;

/// Regions listed per room in the table (the JSON has them all).
const REGIONS_SHOWN: usize = 8;

/// The whole run.
#[derive(Debug, Serialize)]
pub struct BakesReport {
    /// Where the rooms, references, bakes and renders are.
    pub out: String,
    /// Camera width and height of every room, pixels.
    pub size: u32,
    /// Samples per pixel of the references.
    pub reference_spp: u32,
    /// Samples per pixel of the renders from the bakes.
    pub render_spp: u32,
    /// Seed of the bakes and renders (`--seed`).
    pub seed: u64,
    /// Seed of the rooms' layouts.
    pub room_seed: u64,
    /// Triangles asked of the `spheres` room.
    pub spheres_triangles: u32,
    /// Arguments given to every bake after the bench's own.
    pub bake_args: Vec<String>,
    /// Fewest pixels of a region.
    pub min_region_pixels: u64,
    /// Floor of a per-pixel deviation's denominator, times the reference's mean luminance.
    pub deviation_floor: f64,
    /// Deviation above which a pixel counts as off.
    pub off_threshold: f64,
    /// Wall-clock seconds of the whole run.
    pub wall_seconds: f64,
    /// One entry per room, in the order measured.
    pub rooms: Vec<RoomReport>,
}

impl BakesReport {
    /// The settings of a run, before any room is measured.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        out: String,
        size: u32,
        reference_spp: u32,
        render_spp: u32,
        seed: u64,
        room_seed: u64,
        spheres_triangles: u32,
        bake_args: Vec<String>,
        min_region_pixels: u64,
    ) -> Self {
        Self {
            out,
            size,
            reference_spp,
            render_spp,
            seed,
            room_seed,
            spheres_triangles,
            bake_args,
            min_region_pixels,
            deviation_floor: DEVIATION_FLOOR,
            off_threshold: OFF_THRESHOLD,
            wall_seconds: 0.0,
            rooms: Vec::new(),
        }
    }
}

/// One room.
#[derive(Debug, Serialize)]
pub struct RoomReport {
    /// The room's name.
    pub room: String,
    /// Its scene file.
    pub scene: String,
    /// Triangles of the loaded scene.
    pub triangles: usize,
    /// Objects of the loaded scene.
    pub objects: usize,
    /// The converged reference.
    pub reference: ReferenceReport,
    /// The bakes under test: one, or one per `--gathers` setting.
    pub bakes: Vec<BakeReport>,
    /// The images rendered from the bakes, measured against the reference.
    pub images: Vec<ImageReport>,
}

/// A room's reference.
#[derive(Debug, Serialize)]
pub struct ReferenceReport {
    /// The EXR.
    pub exr: String,
    /// Whether this run found it in the cache.
    pub cached: bool,
    /// Wall-clock seconds of its render (in the run that rendered it).
    pub seconds: f64,
    /// Its own noise, relative RMSE of a half against the mean.
    pub noise_rel_rmse: f64,
    /// Its mean luminance, W/(m^2 sr).
    pub mean_luminance: f64,
    /// Its first half measured against it as the bakes' images are: what a perfect image
    /// would score against this reference (the floor of every figure).
    pub noise: ImageError,
}

/// A bake's cost, measured on the child process.
#[derive(Debug, Serialize)]
pub struct BakeReport {
    /// The `--gather` it was given by `--gathers` (`None`: the bake's default or the bake
    /// arguments').
    pub gather: Option<String>,
    /// Rays its final gather traced (closest-hit and shadow rays, from its manifest), if it
    /// gathered.
    pub gather_rays: Option<u64>,
    /// Folder of its outputs.
    pub dir: String,
    /// Wall-clock seconds of the whole `twopass bake` process.
    pub seconds: f64,
    /// Its peak resident memory, MiB.
    pub peak_memory_mib: Option<f64>,
}

/// One image rendered from a bake.
#[derive(Debug, Serialize)]
pub struct ImageReport {
    /// What it was rendered from: `lightmap` or `element bake`, with ` g=G` for a bake of
    /// `--gathers` setting G.
    pub source: String,
    /// Index of its bake in the room's `bakes`.
    pub bake: usize,
    /// The bake file given to `render --bake`.
    pub bake_file: String,
    /// The rendered EXR.
    pub exr: String,
    /// Wall-clock seconds of the render process.
    pub render_seconds: f64,
    /// Its error against the reference.
    #[serde(flatten)]
    pub error: ImageError,
}

/// A fraction as a signed or unsigned percentage.
fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// An object's name without the `room/` of the room's OBJ object.
fn short(object: &str) -> &str {
    object.strip_prefix("room/").unwrap_or(object)
}

/// The worst region of an image as `name +x.x %`.
fn worst(error: &ImageError) -> String {
    error.worst().map_or_else(
        || "-".to_owned(),
        |r| format!("{} {:+.1} %", short(&r.object), 100.0 * r.error),
    )
}

/// Prints one room's table: its images, then its worst regions.
pub fn print_room(r: &RoomReport, min_pixels: u64) -> Result<(), CliError> {
    outln!(
        "\n{}: {} triangles, {} objects; reference {} ({} s, noise {}); {}",
        r.room,
        r.triangles,
        r.objects,
        if r.reference.cached {
            "cached"
        } else {
            "rendered"
        },
        format_args!("{:.1}", r.reference.seconds),
        pct(r.reference.noise_rel_rmse),
        r.bakes
            .iter()
            .map(|b| format!(
                "bake{} {:.1} s, peak {} MiB",
                b.gather
                    .as_ref()
                    .map_or(String::new(), |g| format!(" g={g}")),
                b.seconds,
                fmt_mib(b.peak_memory_mib)
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    outln!(
        "{:<18} {:>9} {:>8} {:>8} {:>8}  worst region",
        "image",
        "rel RMSE",
        "mean",
        ">10 %",
        "p95"
    );
    for (source, e) in r
        .images
        .iter()
        .map(|i| (i.source.as_str(), &i.error))
        .chain([("(ref. noise)", &r.reference.noise)])
    {
        outln!(
            "{:<18} {:>9} {:>8} {:>8} {:>8}  {}",
            source,
            pct(e.rel_rmse),
            format!("{:+.1} %", 100.0 * e.mean_error),
            pct(e.share_off),
            pct(e.p95_deviation),
            worst(e)
        );
    }
    // Regions ordered by the largest |error| over the images.
    let mut names: Vec<(&str, u64, f64, f64)> = Vec::new();
    for i in &r.images {
        for g in &i.error.regions {
            match names.iter_mut().find(|n| n.0 == g.object) {
                Some(n) => n.3 = n.3.max(g.error.abs()),
                None => names.push((&g.object, g.pixels, g.reference_mean, g.error.abs())),
            }
        }
    }
    names.sort_by(|a, b| b.3.total_cmp(&a.3));
    if names.is_empty() {
        return Ok(());
    }
    out!(
        "{:<22} {:>7} {:>9}",
        format!("region (>= {min_pixels} px)"),
        "pixels",
        "ref mean"
    );
    for i in &r.images {
        out!(" {:>15}", i.source);
    }
    outln!();
    for (name, pixels, mean, _) in names.iter().take(REGIONS_SHOWN) {
        out!("{:<22} {:>7} {:>9.3}", short(name), pixels, mean);
        for i in &r.images {
            let e = i.error.regions.iter().find(|g| g.object == *name);
            out!(
                " {:>15}",
                e.map_or("-".to_owned(), |g| format!("{:+.1} %", 100.0 * g.error))
            );
        }
        outln!();
    }
    Ok(())
}

/// Prints the summary over the family: one row per room and image.
pub fn print_summary(report: &BakesReport) -> Result<(), CliError> {
    outln!(
        "\nsummary: rooms {} x {} (scene files at their own camera's size), reference {} spp, \
         renders {} spp, seed {}, bake args [{}]; {:.0} s",
        report.size,
        report.size,
        report.reference_spp,
        report.render_spp,
        report.seed,
        report.bake_args.join(" "),
        report.wall_seconds
    );
    outln!(
        "{:<11} {:<18} {:>9} {:>8} {:>8} {:>8} {:>7} {:>8} {:>9}  worst region",
        "room",
        "image",
        "rel RMSE",
        "mean",
        ">10 %",
        "p95",
        "bake s",
        "peak MiB",
        "gather Mrays"
    );
    for r in &report.rooms {
        for i in &r.images {
            let b = &r.bakes[i.bake];
            outln!(
                "{:<11} {:<18} {:>9} {:>8} {:>8} {:>8} {:>7.1} {:>8} {:>9}  {}",
                r.room,
                i.source,
                pct(i.error.rel_rmse),
                format!("{:+.1} %", 100.0 * i.error.mean_error),
                pct(i.error.share_off),
                pct(i.error.p95_deviation),
                b.seconds,
                fmt_mib(b.peak_memory_mib),
                b.gather_rays
                    .map_or("-".to_owned(), |n| format!("{:.1}", n as f64 / 1e6)),
                worst(&i.error)
            );
        }
        let e = &r.reference.noise;
        outln!(
            "{:<11} {:<18} {:>9} {:>8} {:>8} {:>8} {:>7} {:>8} {:>9}  {}",
            r.room,
            "(ref. noise)",
            pct(e.rel_rmse),
            format!("{:+.1} %", 100.0 * e.mean_error),
            pct(e.share_off),
            pct(e.p95_deviation),
            "",
            "",
            "",
            worst(e)
        );
    }
    outln!(
        "deviation = |Y - Y_ref| / max(Y_ref, {} x the reference's mean luminance); regions: objects of >= {} pixels;\n\
         (ref. noise): half the reference's samples against it, what a perfect image would score",
        report.deviation_floor,
        report.min_region_pixels
    );
    Ok(())
}
