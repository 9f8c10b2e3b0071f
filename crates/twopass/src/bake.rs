//! `twopass bake SCENE`: solve the scene's radiosity once and write the baked lighting for
//! engines and tools (glTF binary with `COLOR_0`, PLY with float radiance), a bake file that
//! `twopass render` loads to render any view without solving again, and a JSON manifest of
//! the settings, timings, rays, counts, unshot fraction and residuals.
//!
//! Files, in `--output DIR` (default `bake/`, created if missing), named after the scene file:
//! `<stem>.glb`, `<stem>.ply`, `<stem>.bake` and `<stem>.manifest.json`. Each is written
//! atomically (a temporary file in DIR, then a rename); the manifest comes last and lists the
//! others. Formats and units: `twopass_bake`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::{Args, ValueEnum};
use twopass_bake::{
    self as bake, ColorMapping, ColorRecord, FileRecord, GatherRecord, Manifest, TexelSource,
};
use twopass_radiosity::{Options, Solver, Stop};
use twopass_scene::RadianceEstimator;
use twopass_trace::gather::Gatherer;

use crate::args::{checked, positive_finite};
use crate::context::Context;
use crate::error::CliError;
use crate::final_gather::{Counted, Gather, gather_elements, parse_gather};
use crate::preset::PRESET_SETS;
use crate::solve::{SolveArgs, parse_length};

/// An output format of `twopass bake`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, ValueEnum)]
pub enum Format {
    /// glTF 2.0 binary in metres: per-vertex linear COLOR_0 = min(1, exposure * radiance),
    /// and the HDR radiance with its direct and indirect parts as _RADIANCE, _DIRECT, _INDIRECT.
    Glb,
    /// Binary PLY in scene units: per-vertex float radiance_*, direct_*, indirect_*
    /// (W/(m^2 sr)) and an 8-bit display colour red green blue.
    Ply,
    /// The bake file `twopass render` loads (the element mesh and radiosity, bit for bit).
    Bake,
    /// glTF 2.0 binary of the scene's own triangles and vertices (not the element mesh), in
    /// metres, with the solution sampled at those vertices: COLOR_0, _RADIANCE, _DIRECT,
    /// _INDIRECT (`<stem>.vertex.glb`).
    VertexGlb,
}

impl BakeArgs {
    /// Whether the bake gathers its element-mesh outputs (`.glb`, `.ply`, `.bake`): its
    /// gather is not off, and it writes one of them.
    pub(crate) fn gathers_elements(&self) -> bool {
        self.gather != Gather::Off
            && self
                .format
                .iter()
                .any(|f| matches!(f, Format::Glb | Format::Ply | Format::Bake))
    }

    /// Whether the bake runs a final gather at all: its gather is not off and some output
    /// takes it (the lightmap, the user's vertices or the element mesh).
    pub(crate) fn gathers(&self) -> bool {
        self.gather != Gather::Off
            && (self.lightmap
                || self.format.contains(&Format::VertexGlb)
                || self.gathers_elements())
    }
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Self::Glb => "glb",
            Self::Ply => "ply",
            Self::Bake => "bake",
            Self::VertexGlb => "vertex.glb",
        }
    }
}

/// Arguments of `twopass bake`.
#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Scene file (.toml), mesh (.obj) or glTF 2.0 (.gltf, .glb).
    pub scene: PathBuf,
    /// Outputs to write, comma separated (the manifest is always written).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "glb,ply,bake"
    )]
    pub format: Vec<Format>,
    /// The radiosity solver's settings.
    #[command(flatten)]
    pub solve: SolveArgs,
    /// The solver settings of a measured preset (draft, preview, final) of `twopass bench
    /// tradeoff`; the preset must use radiosity.
    #[arg(long, value_name = "NAME", conflicts_with_all = &PRESET_SETS[4..])]
    pub preset: Option<String>,
    /// The presets file (default: `<stem>.presets.toml` beside the scene).
    #[arg(long, value_name = "FILE", requires = "preset")]
    pub presets: Option<PathBuf>,
    /// Multiplier from radiance (W/(m^2 sr)) to the display colours (.glb COLOR_0, .ply red
    /// green blue), which are clipped at 1
    /// [default: auto, the 99th-percentile vertex luminance maps to 1].
    #[arg(long, value_name = "SR_M2_PER_W", value_parser = parse_exposure)]
    pub exposure: Option<f32>,
    /// Also bake a lightmap: `<stem>.lightmap.glb` (the scene's own triangles with a UV atlas
    /// on TEXCOORD_1, the OBJ's own texture coordinates when they fit, else generated, and the lightmap as an embedded PNG emissive texture),
    /// `<stem>.lightmap.exr` (HDR, W/(m^2 sr)) and `<stem>.lightmap.png` (the LDR
    /// texture, exposure-scaled sRGB); for a glTF scene also `<stem>.lightmapped.glb`, the
    /// scene's own glTF with the atlas on TEXCOORD_1 and the lightmap referenced by every
    /// baked material's `extras.lightMap`.
    #[arg(long)]
    pub lightmap: bool,
    /// What the lightmap's texels hold: `irradiance` (E / pi in W/(m^2 sr), the light a white
    /// diffuse surface would reflect, which engines multiply by the material's base colour:
    /// Unity and Godot as it is, three.js with lightMapIntensity = pi; no emission) or
    /// `radiance` (the surface's outgoing radiance, its albedo and emission included)
    /// [default: irradiance for a glTF scene, radiance otherwise].
    #[arg(long, value_enum, value_name = "QUANTITY", requires = "lightmap")]
    pub lightmap_quantity: Option<Quantity>,
    /// The lightmap texture the `.glb` files reference for engines (the materials'
    /// `extras.lightMap`): `rgbm` (HDR, nothing clipped: `<stem>.lightmap.rgbm.png`, an RGBA
    /// PNG whose value is multiplier x A x RGB, the 8-bit values over 255 read linearly, the
    /// multiplier in the `.glb` and the manifest) or `srgb` (the exposure-scaled sRGB PNG,
    /// clipped at 1). The sRGB PNG is written either way, and stays the lightmap `.glb`'s
    /// emissive texture.
    #[arg(
        long,
        value_enum,
        default_value = "rgbm",
        value_name = "ENCODING",
        requires = "lightmap"
    )]
    pub lightmap_encoding: Encoding,
    /// Lightmap texel edge on the surface, scene units [default: scene diagonal / 200].
    #[arg(long, value_name = "LENGTH", value_parser = parse_length, requires = "lightmap")]
    pub texel_size: Option<f32>,
    /// The final gather over the solution: `off` (every output shows the solution
    /// interpolated), `auto` (lightmap texels and the user's vertices: 64 to 256 gather rays,
    /// adaptive, plus 64 shadow rays; the element mesh's outputs: 16 to 64 at each of six
    /// points per element, about 8 million in all) or N (N gather rays per point of the
    /// element mesh, at most N elsewhere; 1 to 65536).
    #[arg(long, default_value = "auto", value_name = "off|auto|N", value_parser = parse_gather)]
    pub gather: Gather,
    /// Gather the I-th of N shards (`--part`) of the final gather's points (lightmap texels,
    /// vertices) over the solution of this `.bake` file (a solve's, written with `--format
    /// bake --gather off`), for the same scene, into a part file for `twopass merge`
    /// (`--output`: a `.part` file, or a folder, default `parts`).
    #[arg(long, value_name = "BAKE", requires = "part")]
    pub from: Option<PathBuf>,
    /// With `--from`: which shard, I/N (points whose key is I - 1 modulo N).
    #[arg(long, value_name = "I/N", value_parser = crate::part::parse_part, requires = "from")]
    pub part: Option<crate::part::PartIndex>,
    /// Vertices and patch pairs sampled for the residual report.
    #[arg(long, default_value_t = 200, value_name = "N", value_parser = parse_residual_samples)]
    pub residual_samples: usize,
}

/// What a lightmap holds (`--lightmap-quantity`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Quantity {
    /// Incoming irradiance over pi, E / pi, W/(m^2 sr): multiplied by the albedo in engines.
    Irradiance,
    /// Outgoing radiance, W/(m^2 sr), albedo and emission included.
    Radiance,
}

/// How the lightmap texture engines take is encoded (`--lightmap-encoding`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Encoding {
    /// RGBM: value = multiplier x A x RGB, linear, not clipped.
    Rgbm,
    /// The exposure-scaled sRGB PNG, clipped at 1.
    Srgb,
}

/// Peak memory of a lightmap bake per texel of surface, bytes: the atlas's layers, the
/// rasterized triangle of each texel, the dilation and the encoded images (measured on the
/// Cornell box at a texel size of 0.3, 21.5 million texels: 47 bytes each).
const LIGHTMAP_BYTES_PER_TEXEL: f64 = 46.0;

/// Most vertices and patch pairs the residual report samples.
const MAX_RESIDUAL_SAMPLES: usize = 100_000;

fn parse_residual_samples(s: &str) -> Result<usize, String> {
    let needs = format!("must be 1 to {MAX_RESIDUAL_SAMPLES}");
    checked(s, |n| (1..=MAX_RESIDUAL_SAMPLES).contains(n), &needs)
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    checked(s, positive_finite, "must be finite and > 0")
}

/// The lightmap settings the flags ask for (the library resolves the rest).
fn lightmap_settings(args: &BakeArgs) -> bake::LightmapSettings {
    bake::LightmapSettings {
        texel_size: args.texel_size,
        quantity: args.lightmap_quantity.map(|q| match q {
            Quantity::Irradiance => bake::LightmapQuantity::Irradiance,
            Quantity::Radiance => bake::LightmapQuantity::Radiance,
        }),
        encoding: match args.lightmap_encoding {
            Encoding::Rgbm => bake::LightmapEncoding::Rgbm,
            Encoding::Srgb => bake::LightmapEncoding::Srgb,
        },
        ..bake::LightmapSettings::default()
    }
}

/// Solves the scene and writes the selected outputs and the manifest.
pub fn run(args: &BakeArgs, ctx: &Context) -> Result<(), CliError> {
    let started = Instant::now();
    let (scene, warnings) = ctx.load_scene(&args.scene)?;
    if !ctx.quiet {
        for w in &warnings {
            errln!("warning: {w}");
        }
    }
    let load_time = started.elapsed();
    // A texel too small for any atlas is refused before the solve, leaving any earlier set in
    // the output folder as it was.
    if args.lightmap
        && let Some(size) = args.texel_size
    {
        let smallest = bake::lightmap::smallest_texel_size(&scene);
        // The charts cover the surface, so the atlas holds at least area / size^2 texels.
        let need = scene.total_area() / f64::from(size).powi(2) * LIGHTMAP_BYTES_PER_TEXEL;
        let limit = crate::context::memory_limit();
        if size >= smallest && need > limit as f64 {
            return Err(CliError::Usage(format!(
                "--texel-size {size}: {} has {:.6e} square units of surface, at least {:.3e} \
                 texels at that size, which need about {:.1} GiB ({LIGHTMAP_BYTES_PER_TEXEL} \
                 bytes per texel), more than the {:.1} GiB a command may take here; give a \
                 larger texel size",
                args.scene.display(),
                scene.total_area(),
                need / LIGHTMAP_BYTES_PER_TEXEL,
                need / f64::from(1u32 << 30),
                limit as f64 / f64::from(1u32 << 30),
            )));
        }
        if size < smallest {
            return Err(CliError::Usage(format!(
                "--texel-size {size}: {} has {:.6e} square units of surface, more than a \
                 {side} x {side} lightmap holds at that size; the smallest texel size that \
                 could fit is {smallest:.6e}",
                args.scene.display(),
                scene.total_area(),
                side = bake::lightmap::MAX_LIGHTMAP_SIDE,
            )));
        }
    }
    // The atlas depends on the geometry alone: a texel size whose charts cannot be packed is
    // refused before the solve too (the area bound above is only a floor).
    if args.lightmap
        && let Some(size) = args.texel_size
        && let Err(e) = bake::lightmap_atlas_size(&scene, &lightmap_settings(args))
    {
        return Err(CliError::Usage(format!(
            "--texel-size {size}: {}: {e}",
            args.scene.display()
        )));
    }
    let preset_solve = match &args.preset {
        Some(name) => {
            let preset = crate::preset::load(&args.scene, args.presets.as_deref(), name)?;
            let knobs = preset.radiosity.ok_or_else(|| {
                CliError::Input(format!(
                    "{}: preset `{name}` renders with {}, which bakes no radiosity",
                    args.scene.display(),
                    preset.method.name()
                ))
            })?;
            Some(knobs.solve_args())
        }
        None => None,
    };
    let solve = preset_solve.as_ref().unwrap_or(&args.solve);
    let options = solve.options(ctx.seed);
    // `--time-budget` bounds the whole process: what loading took is spent, and a tenth (at
    // most 2 s) is kept for the residual report and the files.
    let reserve = |total: Duration| (total / 10).min(Duration::from_secs(2));
    // A bake that gathers gives the solve half of what is left and the gather the rest.
    let gathers = args.gathers();
    let solve_share = if gathers { 2 } else { 1 };
    let solve_options = Options {
        stop: Stop {
            time_budget: options.stop.time_budget.map(|total| {
                total
                    .saturating_sub(started.elapsed())
                    .saturating_sub(reserve(total))
                    / solve_share
            }),
            ..options.stop
        },
        ..options.clone()
    };
    let mut solver = Solver::new(&scene, solve_options).map_err(|source| CliError::Solve {
        path: args.scene.clone(),
        source,
    })?;
    // The folder is created and held once the solve can start (nothing is written for a scene
    // the solver refuses).
    let dir = ctx.output_or(Path::new("bake"));
    crate::output::create_dir(dir)?;
    let _folder = lock_folder(dir, ctx)?;
    if ctx.chatty() {
        let (_, reason) = options.method.choose(&scene);
        errln!("radiosity: {} solver ({reason})", solver.method().name());
    }
    let finish = solve
        .run(&mut solver, ctx)
        .map_err(|source| CliError::Solve {
            path: args.scene.clone(),
            source,
        })?;
    let progress = solver.progress();
    let solution = solver.solution();
    let residuals_started = Instant::now();
    // Out of time: a token report rather than an overrun.
    let samples = match options.stop.time_budget {
        Some(total) if started.elapsed() + reserve(total) / 2 > total => {
            args.residual_samples.min(10)
        }
        _ => args.residual_samples,
    };
    let residuals = solver.residuals_of(samples, &solution);
    let residuals_time = residuals_started.elapsed();
    if !ctx.quiet {
        crate::solve::warn_energy(&args.scene, &residuals, solver.method());
        crate::solve::warn_close_lights(&args.scene, &scene, solution.mesh());
    }
    // The final gather over the solution, ending where the time budget (less the reserve for
    // the files) does.
    let gatherer = args.gather.settings(ctx.seed).filter(|_| gathers).map(|g| {
        let gatherer = Gatherer::new(&scene, &solution, g);
        match options.stop.time_budget {
            Some(total) => gatherer.with_deadline(started + total.saturating_sub(reserve(total))),
            None => gatherer,
        }
    });
    let estimator = gatherer.as_ref().map(|g| g as &dyn RadianceEstimator);
    // The element mesh with its own ray count (`auto`: fewer than a texel's).
    let elements = match (&gatherer, args.gather.element_rays(solution.mesh())) {
        (Some(g), Some(rays)) if args.gathers_elements() => {
            let fixed = g.fixed(rays);
            Some(gather_elements(&solution, &scene, &fixed, fixed.rays()))
        }
        _ => None,
    };
    let shown = elements.as_ref().map_or(&solution, |(s, _)| s);
    if ctx.chatty()
        && let Some((_, record)) = &elements
    {
        errln!(
            "final gather: element mesh at {} points, {} rays each ({:.2} s)",
            record.points,
            record.max_rays,
            record.seconds
        );
    }
    let mut manifest = Manifest::new(
        &scene,
        &options,
        finish,
        &progress,
        &residuals,
        samples,
        residuals_time,
    );
    manifest.timings.load_s = load_time.as_secs_f64();
    manifest.element_gather = elements.as_ref().map(|(_, record)| record.clone());
    let set = BakeSet {
        dir,
        scene: &scene,
        solution: &solution,
        shown,
        gatherer: gatherer.as_ref(),
        estimator,
        started,
    };
    write_set(args, ctx, &set, manifest)
}

/// What [`write_set`] writes from: the scene, the solution and the one the element outputs
/// show (gathered or not), the final gather (its settings for the manifest, and the estimates
/// themselves through `estimator`, which `twopass merge` replays from part files).
pub(crate) struct BakeSet<'a> {
    /// The output folder (created, and held by the caller).
    pub dir: &'a Path,
    /// The scene.
    pub scene: &'a twopass_scene::Scene,
    /// The radiosity solution.
    pub solution: &'a twopass_radiosity::Solution,
    /// The solution the element-mesh outputs show.
    pub shown: &'a twopass_radiosity::Solution,
    /// The final gather, when the bake gathers.
    pub gatherer: Option<&'a Gatherer<'a>>,
    /// Where the gathered points' estimates come from.
    pub estimator: Option<&'a dyn RadianceEstimator>,
    /// When the command started.
    pub started: Instant,
}

/// Writes the selected outputs of `set` and, last, the manifest (`manifest`, completed with
/// the files, the colour mapping, the lightmap and the timings).
pub(crate) fn write_set(
    args: &BakeArgs,
    ctx: &Context,
    set: &BakeSet<'_>,
    mut manifest: Manifest,
) -> Result<(), CliError> {
    let BakeSet {
        dir,
        scene,
        solution,
        shown,
        gatherer,
        estimator,
        started,
    } = *set;
    let stem = args
        .scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let writing_started = Instant::now();
    // The manifest is the set's seal: the old one goes before any file of the new set is
    // written and the new one comes last, with every file's size and CRC-32. A bake stopped
    // between its files leaves no manifest (visibly incomplete), never an old manifest beside
    // new files.
    let manifest_path = dir.join(format!("{stem}.manifest.json"));
    match std::fs::remove_file(&manifest_path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(CliError::io(&manifest_path, e)),
    }
    let formats: BTreeSet<Format> = args.format.iter().copied().collect();
    // One display mapping for every output's clipped colour (.glb COLOR_0, .ply red green blue).
    let (mapping, mode) = match args.exposure {
        Some(exposure) => (ColorMapping { exposure }, "fixed"),
        None => (ColorMapping::auto(shown), "auto"),
    };
    // What the manifest says of the mapping, with the vertices a .glb clipped.
    let color_record = |clamped_vertices| ColorRecord {
        mapping: ColorMapping::FORMULA.into(),
        exposure: mapping.exposure,
        exposure_mode: mode.into(),
        clamped_vertices,
    };
    for format in formats {
        let path = dir.join(format!("{stem}.{}", format.extension()));
        let bytes = match format {
            Format::Glb => {
                let glb = bake::encode_glb(shown, scene, mapping)?;
                manifest.color = Some(color_record(glb.clamped_vertices));
                glb.bytes
            }
            Format::Ply => bake::encode_ply(shown, scene, mapping)?,
            Format::Bake => bake::encode_bake(shown, scene)?,
            Format::VertexGlb => {
                let counted = estimator.map(|e| Counted::new(e, max_rays(gatherer)));
                let glb = bake::encode_vertex_glb(
                    solution,
                    scene,
                    mapping,
                    counted.as_ref().map(|c| c as &dyn RadianceEstimator),
                )?;
                manifest.vertex_gather = counted.map(|c| c.record());
                if manifest.color.is_none() {
                    manifest.color = Some(color_record(glb.clamped_vertices));
                }
                glb.bytes
            }
        };
        bake::write_atomic(&path, &bytes)?;
        manifest.files.push(FileRecord {
            format: format.extension().into(),
            path,
            bytes: bytes.len() as u64,
            crc32: Some(crc32fast::hash(&bytes)),
        });
    }
    if args.lightmap {
        let started = Instant::now();
        let settings = lightmap_settings(args);
        let source = match estimator {
            Some(g) => TexelSource::Gather(g),
            None => TexelSource::Solution(solution),
        };
        let lm = bake::bake_lightmap(source, scene, &settings, mapping)?;
        let seconds = started.elapsed().as_secs_f64();
        let files = [
            ("lightmap", "glb", Some(&lm.glb)),
            ("lightmap", "exr", Some(&lm.exr)),
            ("lightmap", "png", Some(&lm.png)),
            ("lightmap", "rgbm.png", lm.rgbm.as_ref().map(|(png, _)| png)),
            // A glTF scene's own asset back, with the lightmap on TEXCOORD_1.
            ("lightmapped", "glb", lm.asset.as_ref()),
        ];
        for (kind, ext, bytes) in files {
            let Some(bytes) = bytes else { continue };
            let path = dir.join(format!("{stem}.{kind}.{ext}"));
            bake::write_atomic(&path, bytes)?;
            manifest.files.push(FileRecord {
                format: format!("{kind}-{ext}"),
                path,
                bytes: bytes.len() as u64,
                crc32: Some(crc32fast::hash(bytes)),
            });
        }
        manifest.lightmap = Some(bake::LightmapRecord {
            texel_size: lm.texel_size,
            padding: settings.padding,
            width: lm.width,
            height: lm.height,
            charts: lm.charts,
            curved_objects: lm.curved_objects,
            atlas: lm.atlas.describe(),
            covered_texels: lm.covered_texels,
            quantity: lm.quantity.name().into(),
            png: lm.quantity.png_formula().into(),
            encoding: lm.encoding.name().into(),
            rgbm_multiplier: lm.rgbm.as_ref().map(|(_, m)| *m),
            seconds,
            gather: gatherer.as_ref().map(|gatherer| {
                let g = gatherer.settings();
                GatherRecord {
                    shadow_rays_per_point: g.shadow_rays,
                    min_rays: g.min_rays,
                    max_rays: g.max_rays,
                    target_error: g.target_error,
                    max_depth: g.max_depth,
                    seed: g.seed,
                    filter: bake::lightmap::FILTER.into(),
                    rays: lm.rays,
                    shadow_rays: lm.shadow_rays,
                    rays_per_second: (lm.rays + lm.shadow_rays) as f64 / seconds.max(1e-9),
                    late_points: gatherer.late_points(),
                    caustic_photons: gatherer.caustic_photons() as u64,
                }
            }),
        });
    }
    manifest.timings.writing_s = writing_started.elapsed().as_secs_f64();
    manifest.timings.total_s = started.elapsed().as_secs_f64();
    let json = manifest.to_json()?;
    bake::write_atomic(&manifest_path, &json)?;

    if ctx.json {
        out!("{}", String::from_utf8_lossy(&json));
    } else if ctx.chatty() {
        print_summary(&manifest, &manifest_path)?;
    }
    Ok(())
}

/// Most gather rays per point of `gatherer` (0 without one).
fn max_rays(gatherer: Option<&Gatherer<'_>>) -> u32 {
    gatherer.map_or(0, |g| g.settings().max_rays)
}

/// Holds `dir` for this bake (an advisory lock on the folder itself, released when the
/// returned handle drops, also when the process dies), so two bakes into one folder never mix
/// their files: the second waits for the first to finish, then writes its whole set.
pub(crate) fn lock_folder(dir: &Path, ctx: &Context) -> Result<std::fs::File, CliError> {
    let folder = std::fs::File::open(dir).map_err(|e| CliError::io(dir, e))?;
    match folder.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            if ctx.chatty() {
                errln!(
                    "{}: another bake is writing into this folder; waiting for it",
                    dir.display()
                );
            }
            folder.lock().map_err(|e| CliError::io(dir, e))?;
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(CliError::io(dir, e)),
    }
    Ok(folder)
}

fn print_summary(m: &Manifest, manifest_path: &Path) -> Result<(), CliError> {
    let t = &m.timings;
    let steps = if m.solver == "hierarchical" {
        format!("{} gather iterations", m.counts.iterations)
    } else {
        format!("{} shots", m.shots)
    };
    outln!(
        "{}: {} solver, {} after {steps} in {:.2} s (load {:.2}, meshing {:.2}, solving {:.2}, \
         refining {:.2}, residuals {:.2}, writing {:.2})",
        m.scene.display(),
        m.solver,
        m.finish.replace('_', " "),
        t.total_s,
        t.load_s,
        t.meshing_s,
        t.shooting_s,
        t.refining_s,
        t.residuals_s,
        t.writing_s
    );
    let c = &m.counts;
    outln!(
        "  {} patches, {} clusters, {} links, {} elements, {} vertices, {} refinement rounds; \
         {:.3e} shadow rays",
        c.patches,
        c.clusters,
        c.links,
        c.elements,
        c.vertices,
        c.refinement_rounds,
        m.rays as f64
    );
    let r = &m.residuals.residuals;
    outln!(
        "  residual {:.2e}; energy imbalance {:.1e}, excess {:.1e}; form-factor row sums \
         {:.3}..{:.3} (mean {:.3}); reciprocity spread {:.2e} (weighted {:.2e}, {} pairs)",
        m.unshot_fraction,
        r.energy_imbalance,
        r.energy_excess,
        r.row_sum_min,
        r.row_sum_max,
        r.row_sum_mean,
        r.reciprocity_spread,
        r.reciprocity_mean,
        r.reciprocity_pairs
    );
    if let Some(color) = &m.color {
        outln!(
            "  glb COLOR_0 = min(1, {:.4e} * L) ({} exposure), {} vertices clipped",
            color.exposure,
            color.exposure_mode,
            color.clamped_vertices
        );
    }
    if let Some(lm) = &m.lightmap {
        outln!(
            "  lightmap {} x {} texels of {} scene units, {} charts, {:.2} s",
            lm.width,
            lm.height,
            lm.texel_size,
            lm.charts,
            lm.seconds
        );
        if let Some(g) = &lm.gather {
            outln!(
                "  final gather: {} to {} rays and {} shadow rays per texel; {:.3e} rays, \
                 {:.3e} shadow rays, {:.3e} rays/s",
                g.min_rays,
                g.max_rays,
                g.shadow_rays_per_point,
                g.rays as f64,
                g.shadow_rays as f64,
                g.rays_per_second
            );
        }
    }
    for f in &m.files {
        outln!("  wrote {} ({} bytes)", f.path.display(), f.bytes);
    }
    outln!("  wrote {}", manifest_path.display());
    Ok(())
}
