//! `twopass bench bakes`: bake quality on a family of generated rooms nobody tuned for
//! (`twopass_scene::workload::room`), per room and per object, against the project's own path
//! tracer.
//!
//! For each room, in `OUT/<room>/`: the room's scene and OBJ (`<room>.toml`, `<room>.obj`);
//! its converged reference (`reference`: the path tracer in a child process, cached); one
//! `twopass bake <room>.toml --lightmap --output OUT/<room>/bake ARGS` in a child process
//! (`ARGS` are the bench's arguments after `--`; with `--gathers`, one bake per setting, in
//! `bake-gather-<G>/`), timed and measured for peak memory; then two
//! renders from it (`render --bake ... --method radiosity`, children too; `hybrid-classic` in
//! a room with mirrors, metal or glass, which radiosity alone does not show): `lightmap.exr`
//! from `<room>.lightmap.glb` and `element-bake.exr` from `<room>.bake`, each measured against
//! the reference (`metric`). The report (`report`) goes to `OUT/bench-bakes.json` and stdout.

mod child;
mod metric;
mod reference;
mod report;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use twopass_brdf::colour::luminance;
use twopass_scene::workload::{RoomKind, RoomSettings, room};

use self::child::run_twopass;
use self::metric::{measure, object_map};
use self::reference::{ReferenceKey, converged};
use self::report::{BakeReport, BakesReport, ImageReport, ReferenceReport, RoomReport};
use crate::bench::memory::mib;
use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass bench bakes`.
#[derive(Debug, Args)]
pub struct BakesArgs {
    /// Rooms to measure, comma separated: spheres, grazing, near-light, two-lights,
    /// terminator, chrome [default: all].
    #[arg(long, value_delimiter = ',', value_parser = parse_room)]
    pub rooms: Vec<RoomKind>,
    /// Scene files (.toml or .obj) to measure as well, each at its own camera's resolution,
    /// its outputs in `DIR/<stem>/`; given alone (without `--rooms`), only these are measured.
    #[arg(long, value_name = "FILE")]
    pub scene: Vec<PathBuf>,
    /// Triangles of the `spheres` room (the others have a fixed size).
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u32).range(1_000..=10_000_000))]
    pub triangles: u32,
    /// Width and height of every room's camera, pixels.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(8..=4096))]
    pub size: u32,
    /// Samples per pixel of the converged references (two halves of half as many each).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(2..=1_000_000))]
    pub reference_spp: u32,
    /// Samples per pixel of the renders from the bakes (anti-aliasing only: a bake render
    /// has no noise).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub render_spp: u32,
    /// Fewest pixels an object covers to be measured as a region.
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u64).range(1..))]
    pub min_region_pixels: u64,
    /// Seed of the rooms' layouts (`--seed` seeds the reference, the bake and the renders).
    #[arg(long, default_value_t = 0)]
    pub room_seed: u64,
    /// The final gather's trade: bake every room once per setting given (`off`, `auto` or a
    /// ray count, comma separated: `--gathers off,16,64,auto`), each with `--gather` set
    /// to it, and measure the renders of each; without it, one bake with the bake's default.
    #[arg(long, value_delimiter = ',', value_name = "off|auto|N", value_parser = parse_gather)]
    pub gathers: Vec<String>,
    /// Folder of the rooms, references, bakes, renders and `bench-bakes.json`
    /// [default: --output, else bench-bakes].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Arguments given to every `twopass bake` after the bench's own, after `--`
    /// (`twopass bench bakes -- --texel-size 0.05`).
    #[arg(last = true, value_name = "BAKE ARGS")]
    pub bake_args: Vec<OsString>,
}

fn parse_room(s: &str) -> Result<RoomKind, String> {
    RoomKind::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = RoomKind::ALL.iter().map(|k| k.name()).collect();
        format!("no room `{s}`; the rooms are {}", names.join(", "))
    })
}

fn parse_gather(s: &str) -> Result<String, String> {
    match s {
        "off" | "auto" => Ok(s.to_owned()),
        _ => match s.parse::<u32>() {
            Ok(n) if n >= 1 => Ok(n.to_string()),
            _ => Err(format!("`{s}` is not off, auto or a ray count")),
        },
    }
}

/// `--threads N` for a child when the bench was given it.
fn threads_args(ctx: &Context) -> Vec<OsString> {
    ctx.threads
        .map(|t| vec!["--threads".into(), t.to_string().into()])
        .unwrap_or_default()
}

/// Measures every room asked for and reports.
pub fn run(args: &BakesArgs, ctx: &Context) -> Result<(), CliError> {
    let started = Instant::now();
    if ctx.width.is_some() || ctx.height.is_some() {
        return Err(CliError::Usage(
            "bench bakes: --width/--height do not apply; every room's camera is --size pixels square".into(),
        ));
    }
    let out = args
        .out
        .clone()
        .or_else(|| ctx.output.clone())
        .unwrap_or_else(|| PathBuf::from("bench-bakes"));
    // The scene files are loaded first, so that one that cannot be read is refused before
    // the rooms' minutes of work, not after them.
    for path in &args.scene {
        ctx.load_scene(path)?;
    }
    crate::output::create_dir(&out)?;
    let kinds = if args.rooms.is_empty() && args.scene.is_empty() {
        RoomKind::ALL.to_vec()
    } else {
        args.rooms.clone()
    };
    let mut report = BakesReport::new(
        out.display().to_string(),
        args.size,
        args.reference_spp,
        args.render_spp,
        ctx.seed,
        args.room_seed,
        args.triangles,
        args.bake_args
            .iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect(),
        args.min_region_pixels,
    );
    for kind in kinds {
        let r = measure_room(kind, &out, args, ctx)?;
        report.rooms.push(r);
    }
    for path in &args.scene {
        let r = measure_scene_file(path, &out, args, ctx)?;
        report.rooms.push(r);
    }
    report.wall_seconds = started.elapsed().as_secs_f64();
    crate::output::finish_report(&out.join("bench-bakes.json"), &report, ctx, |report| {
        for r in &report.rooms {
            report::print_room(r, report.min_region_pixels)?;
        }
        report::print_summary(report)
    })
}

/// A progress line on standard error, unless quiet or reporting JSON.
fn progress(ctx: &Context, line: std::fmt::Arguments) {
    if ctx.chatty() {
        errln!("{line}");
    }
}

/// Rays the final gather of the bake whose manifest is at `path` traced (closest-hit and
/// shadow rays), if the manifest says it gathered.
fn gather_rays(path: &Path) -> Option<u64> {
    let text = std::fs::read(path).ok()?;
    let manifest: serde_json::Value = serde_json::from_slice(&text).ok()?;
    let g = &manifest["lightmap"]["gather"];
    Some(g["rays"].as_u64()? + g["shadow_rays"].as_u64().unwrap_or(0))
}

/// Writes one room, renders or finds its reference, bakes it, renders the bake and measures.
fn measure_room(
    kind: RoomKind,
    out: &Path,
    args: &BakesArgs,
    ctx: &Context,
) -> Result<RoomReport, CliError> {
    let name = kind.name();
    let dir = out.join(name);
    let settings = RoomSettings {
        triangles: args.triangles as usize,
        seed: args.room_seed,
        resolution: args.size,
    };
    let room = room(kind, &settings);
    for (file, text) in room.mesh_files() {
        crate::output::write_atomic(&dir.join(file), text.as_bytes())?;
    }
    let scene_path = dir.join(room.scene_file());
    crate::output::write_atomic(&scene_path, room.scene.as_bytes())?;
    let meshes: String = room.mesh_files().iter().map(|m| m.1).collect();
    let key = ReferenceKey::new(&room.scene, &meshes, args.reference_spp, ctx.seed);
    measure_scene(name, &dir, &scene_path, key, args, ctx)
}

/// Measures a scene file the user gave: its outputs in `DIR/<stem>/`, its reference keyed by
/// the scene file's text (a changed mesh that the scene names is not noticed: delete the
/// cached reference then).
fn measure_scene_file(
    path: &Path,
    out: &Path,
    args: &BakesArgs,
    ctx: &Context,
) -> Result<RoomReport, CliError> {
    let name = path
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());
    let text = std::fs::read(path).map_err(|e| CliError::io(path, e))?;
    let dir = out.join(&name);
    crate::output::create_dir(&dir)?;
    let key = ReferenceKey::new(
        &String::from_utf8_lossy(&text),
        "",
        args.reference_spp,
        ctx.seed,
    );
    measure_scene(&name, &dir, path, key, args, ctx)
}

/// Renders or finds the reference of the scene at `scene_path` (keyed by `key`), bakes it into
/// `dir/bake`, renders the bake and measures, as `name`.
fn measure_scene(
    name: &str,
    dir: &Path,
    scene_path: &Path,
    key: ReferenceKey,
    args: &BakesArgs,
    ctx: &Context,
) -> Result<RoomReport, CliError> {
    let scene_path = scene_path.to_path_buf();
    let dir = dir.to_path_buf();
    let (scene, _) = ctx.load_scene(&scene_path)?;
    let size = (scene.camera.width, scene.camera.height);
    let objects = object_map(&scene);
    let names: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
    // Radiosity alone shows mirrors, metal and glass black; the classic hybrid shows the bake
    // at the diffuse points and traces the rest.
    let method = if twopass_scene::targets::specular_objects(&scene).is_empty() {
        "radiosity"
    } else {
        "hybrid-classic"
    };

    progress(ctx, format_args!("{name}: reference, {} spp", key.spp));
    let reference = converged(&dir, &scene_path, &key, size, ctx.threads)?;
    if reference.cached {
        progress(
            ctx,
            format_args!(
                "{name}: reference from the cache ({})",
                reference.exr.display()
            ),
        );
    }

    let gathers: Vec<Option<&str>> = if args.gathers.is_empty() {
        vec![None]
    } else {
        args.gathers.iter().map(|g| Some(g.as_str())).collect()
    };
    let mut bakes = Vec::new();
    let mut images = Vec::new();
    for gather in gathers {
        let (bake_dir, suffix) = match gather {
            None => (dir.join("bake"), String::new()),
            Some(g) => (dir.join(format!("bake-gather-{g}")), format!("-gather-{g}")),
        };
        match std::fs::remove_dir_all(&bake_dir) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(CliError::io(&bake_dir, e));
            }
            _ => {}
        }
        let mut bake: Vec<OsString> = vec![
            "bake".into(),
            scene_path.clone().into(),
            "--lightmap".into(),
        ];
        bake.extend(["--output".into(), bake_dir.clone().into()]);
        bake.extend([
            "--seed".into(),
            ctx.seed.to_string().into(),
            "--quiet".into(),
        ]);
        if let Some(g) = gather {
            bake.extend(["--gather".into(), g.into()]);
        }
        bake.extend(threads_args(ctx));
        bake.extend(args.bake_args.iter().cloned());
        progress(
            ctx,
            format_args!(
                "{name}: bake{}",
                gather.map_or(String::new(), |g| format!(" --gather {g}"))
            ),
        );
        let baked = run_twopass(&bake)?;
        let index = bakes.len();
        bakes.push(BakeReport {
            gather: gather.map(str::to_owned),
            gather_rays: gather_rays(&bake_dir.join(format!("{name}.manifest.json"))),
            dir: bake_dir.display().to_string(),
            seconds: baked.seconds,
            peak_memory_mib: mib(baked.peak_bytes),
        });
        for (source, file, exr) in [
            ("lightmap", format!("{name}.lightmap.glb"), "lightmap"),
            ("element bake", format!("{name}.bake"), "element-bake"),
        ] {
            let bake_file = bake_dir.join(file);
            if !bake_file.is_file() {
                progress(
                    ctx,
                    format_args!(
                        "{name}: the bake wrote no {}; not measured",
                        bake_file.display()
                    ),
                );
                continue;
            }
            let exr = dir.join(format!("{exr}{suffix}.exr"));
            let mut render: Vec<OsString> = vec!["render".into(), scene_path.clone().into()];
            render.extend(["--bake".into(), bake_file.clone().into()]);
            let words = format!(
                "--method {method} --spp {} --seed {} --quiet",
                args.render_spp, ctx.seed
            );
            render.extend(words.split_whitespace().map(OsString::from));
            render.extend(threads_args(ctx));
            render.extend(["--output".into(), exr.clone().into()]);
            progress(
                ctx,
                format_args!("{name}: render from the {source} ({method})"),
            );
            let rendered = run_twopass(&render)?;
            let image = twopass_composite::write::read_exr(&exr)?;
            let error = measure(
                &image,
                &reference.image,
                &objects,
                &names,
                args.min_region_pixels,
            )?;
            images.push(ImageReport {
                source: match gather {
                    None => source.to_owned(),
                    Some(g) => format!("{source} g={g}"),
                },
                bake: index,
                bake_file: bake_file.display().to_string(),
                exr: exr.display().to_string(),
                render_seconds: rendered.seconds,
                error,
            });
        }
    }
    let noise = measure(
        &reference.half,
        &reference.image,
        &objects,
        &names,
        args.min_region_pixels,
    )?;
    let pixels = reference.image.pixels();
    let mean_luminance =
        pixels.iter().map(|&p| f64::from(luminance(p))).sum::<f64>() / pixels.len() as f64;
    Ok(RoomReport {
        room: name.to_owned(),
        scene: scene_path.display().to_string(),
        triangles: scene.mesh.triangle_count(),
        objects: scene.objects.len(),
        reference: ReferenceReport {
            exr: reference.exr.display().to_string(),
            cached: reference.cached,
            seconds: reference.render_seconds,
            noise_rel_rmse: reference.noise_rel_rmse,
            mean_luminance,
            noise,
        },
        bakes,
        images,
    })
}
