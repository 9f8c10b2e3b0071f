//! `twopass render SCENE --method M`: one image with one method, written as a multi-layer EXR
//! (every layer of the tracer plus the final image) and, with `--png`, a tone-mapped PNG.
//! `--output x.exr` names the EXR, `--output x.png` asks for the PNG alone, and any other path
//! (no image extension, or a trailing `/`) is a directory for `<stem>-<method>.exr`.
//!
//! The radiosity-based methods take their diffuse light from a fresh solve, or from a bake file
//! of `twopass bake` (`--bake FILE`), which renders any view without solving again, or from a
//! lightmap bake (`--bake x.lightmap.glb`: the HDR lightmap `x.lightmap.exr` beside it, sampled
//! at each hit's `TEXCOORD_1`), which shows what an engine given the lightmap would show.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use twopass_composite::RenderMetadata;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{write_exr_render, write_exr_render_rgba, write_png_tonemapped};
use twopass_trace::{LightPaths, PathSplits, ReferenceSettings, WhittedSettings};

use crate::args::checked;
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{MAX_DEPTH, RenderMethod, integrator, is_glb, radiosity, to_layers};
use crate::plan::plan;
use crate::preset::{PRESET_SETS, RadiosityKnobs, RenderKnobs};
use crate::render_plan::Goal;
use crate::solve::SolveArgs;

mod summary;

use summary::{LightPlanSummary, SplitPlanSummary, Summary};

/// The gathered hybrid's default element edge is the scene's bounding-box diagonal over this
/// (radiosity alone and the bakes use diagonal / 24): its gather rays read the solution one
/// bounce away and average it, so a coarser solve costs the image little and halves the
/// solve's time on a progressive solve (docs/benchmarks.md, "The gathered hybrid").
pub const HYBRID_ELEMENTS_PER_DIAGONAL: f32 = 12.0;

/// The element edge `render` solves on for `method` when neither the user (`solve`'s
/// `--element-size`) nor a preset's solver knobs (`preset_sized`) size the mesh, scene units:
/// the gathered hybrid's diagonal / [`HYBRID_ELEMENTS_PER_DIAGONAL`]; `None` for every other
/// method and whenever the mesh is sized (the solver's own default holds). `slurm render`'s
/// solve job asks the same, so that its parts render what one `render` does.
pub(crate) fn hybrid_element_size(
    method: RenderMethod,
    preset_sized: bool,
    solve: &SolveArgs,
    scene: &twopass_scene::Scene,
) -> Option<f32> {
    (method == RenderMethod::Hybrid && !preset_sized && solve.element_size.is_none())
        .then(|| scene.bounds.diagonal() / HYBRID_ELEMENTS_PER_DIAGONAL)
}

/// Arguments of `twopass render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (.toml), mesh (.obj) or glTF 2.0 (.gltf, .glb).
    pub scene: PathBuf,
    /// The method [default: hybrid; with --target-error or --time-budget and no --method,
    /// the planner picks the hybrid or the path tracer, whichever it measures to get there
    /// first].
    #[arg(long, value_enum)]
    pub method: Option<RenderMethod>,
    /// The planner's noise target: the fewest samples per pixel whose image noise (relative
    /// RMSE), measured by two pilot renders, is at most this (0.02 is 2 %). With
    /// `--time-budget` (the whole process, seconds), at most the samples that fit it.
    #[arg(long, value_name = "FRACTION", value_parser = parse_target_error,
          conflicts_with_all = ["spp", "adaptive", "preset", "part"])]
    pub target_error: Option<f64>,
    /// Bake file from `twopass bake` for the radiosity-based methods (default: solve now): a
    /// `.bake` file, or a lightmap `<stem>.lightmap.glb` (its HDR `<stem>.lightmap.exr` beside
    /// it gives the light, sampled bilinearly at each hit's `TEXCOORD_1`; radiosity and hybrid
    /// only).
    #[arg(long, value_name = "FILE")]
    pub bake: Option<PathBuf>,
    /// Samples per pixel (stratified), the same in every pixel. Without it the default is a
    /// mean spread by noise: two pilot renders of a sixteenth of it each measure every pixel's
    /// noise, and the rest goes where the noise is (their samples count in the image)
    /// [default: 16; 64 for the gathered hybrid (`hybrid`); with --time-budget and no --spp, as
    /// many as the planner measures to fit the budget, in every pixel].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: Option<u32>,
    /// Adaptive anti-aliasing: BASE samples per pixel everywhere first, then `--spp` only in
    /// pixels whose samples, or whose neighbours, differ by a luminance contrast of more than
    /// 5 % (edges, shadow boundaries, noise); the others keep their BASE-sample mean.
    #[arg(long, value_name = "BASE", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub adaptive: Option<u32>,
    /// Recursion depth of mirror and refraction paths (Whitted and the hybrids).
    /// At most 64: the recursion holds a stack frame per bounce, and a path trapped by total
    /// internal reflection keeps its full weight, so only the depth ends it.
    #[arg(long, default_value_t = WhittedSettings::default().max_depth, value_parser = clap::value_parser!(u32).range(0..=MAX_DEPTH as i64))]
    pub depth: u32,
    /// Shadow rays per hit, as an N x N stratified grid over all the emitters, each ray's emitter
    /// chosen by its importance at the hit (Whitted and the hybrids; each lamp gets one more)
    /// [default: 4; 2 for the gathered hybrid (`hybrid`)].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub shadow_grid: Option<u32>,
    /// Gather rays per camera sample at every diffuse point the gathered hybrid (`hybrid`)
    /// shades: its indirect light, read from the solution where they land. Stratified over the
    /// pixel's samples, so a pixel gets `--spp` times this many [default: 4, at the hybrid's 64
    /// samples per pixel: 256 rays per pixel].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::preset::MAX_GATHER_RAYS)))]
    pub gather_rays: Option<u32>,
    /// Light paths per camera sample of the light tracing pass that finds the caustics (light
    /// through mirrors and glass onto what the camera sees): the path tracer's (`reference`)
    /// and the hybrids' per-pixel ones; more than 0, at most 16 [default: for the path tracer
    /// as many as a pilot of both passes measures to give the least error for the time, for
    /// the hybrids 1; the render's report says how many paths].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = parse_light_paths)]
    pub light_paths: Option<f32>,
    /// Continuations per camera sample of the path tracer (`reference`) from a camera path's
    /// first diffuse or glossy vertex (path splitting), 1 to 64; 1 is plain path tracing
    /// [default: as many as a pilot measures to give the least error for the time, at most
    /// 16; the render's report says how many].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub splits: Option<u32>,
    /// Also write a tone-mapped PNG beside the EXR.
    #[arg(long)]
    pub png: bool,
    /// Write every layer into the EXR (the final image as plain R, G, B and each pass as
    /// `<layer>.R/G/B`) instead of the plain RGBA image (R, G, B and A = 1) that any EXR
    /// reader opens as the image.
    #[arg(long)]
    pub layers: bool,
    /// PNG exposure in stops (EV) [default: auto, the 99th-percentile luminance maps to 1].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_stops)]
    pub exposure: Option<f32>,
    /// The radiosity solver's settings, for a fresh solve.
    #[command(flatten)]
    pub solve: SolveArgs,
    /// A measured preset (draft, preview, final) of `twopass bench tradeoff`: the cheapest
    /// setting measured to reach its error target. Sets the method and every setting above.
    #[arg(long, value_name = "NAME", conflicts_with_all = PRESET_SETS)]
    pub preset: Option<String>,
    /// The presets file (default: `<stem>.presets.toml` beside the scene).
    #[arg(long, value_name = "FILE", requires = "preset")]
    pub presets: Option<PathBuf>,
    /// Render only the I-th of N parts of the image (contiguous runs of its 16-pixel tiles)
    /// into a part file for `twopass merge` (`--output`: a `.part` file, or a folder for
    /// `<stem>-<method>.<I>-of-<N>.part`, default `parts`).
    #[arg(long, value_name = "I/N", value_parser = crate::part::parse_part)]
    pub part: Option<crate::part::PartIndex>,
}

/// Renders the scene and writes the EXR (and PNG).
pub fn run(args: &RenderArgs, ctx: &Context) -> Result<(), CliError> {
    let (scene, warnings) = ctx.load_scene(&args.scene)?;
    if !ctx.quiet {
        for w in &warnings {
            errln!("warning: {w}");
        }
    }
    let preset = args
        .preset
        .as_deref()
        .map(|name| crate::preset::load(&args.scene, args.presets.as_deref(), name))
        .transpose()?;
    let explicit = preset.as_ref().map(|p| p.method).or(args.method);
    let mut method = explicit.unwrap_or(RenderMethod::Hybrid);
    let budgeted = args.solve.time_budget.is_some()
        && args.spp.is_none()
        && args.adaptive.is_none()
        && args.preset.is_none()
        && args.part.is_none();
    let goal = (args.target_error.is_some() || budgeted).then(|| Goal {
        target_error: args.target_error,
        time_budget: args.solve.time_budget.map(|d| d.as_secs_f64()),
    });
    let defaults = RenderDefaults::of(method);
    let mut knobs = preset.as_ref().map_or(
        RenderKnobs {
            spp: args.spp.unwrap_or(defaults.spp),
            depth: args.depth,
            shadow_grid: args.shadow_grid.unwrap_or(defaults.shadow_grid),
            adaptive: args.adaptive,
            gather_rays: args.gather_rays.unwrap_or(defaults.gather_rays),
        },
        |p| p.render,
    );
    if args.part.is_some() {
        crate::part::render::check(&knobs, args.preset.as_deref())?;
    }
    let preset_solve = preset
        .as_ref()
        .and_then(|p| p.radiosity.as_ref())
        .map(RadiosityKnobs::solve_args);
    let solve = preset_solve.as_ref().unwrap_or(&args.solve);
    // The gathered hybrid reads the solution one bounce away, averaged over its gather rays,
    // and never shows it at the hit: a mesh twice as coarse serves it (ARCHITECTURE.md,
    // "The final gather"), unless the user or a preset sized it.
    let gather_solve;
    let solve = match hybrid_element_size(method, preset_solve.is_some(), solve, &scene) {
        Some(size) => {
            gather_solve = SolveArgs {
                element_size: Some(size),
                ..solve.clone()
            };
            &gather_solve
        }
        None => solve,
    };
    if args.bake.is_some() && !method.needs_radiosity() {
        return Err(CliError::Input(format!(
            "--bake is for the radiosity-based methods, not {}",
            method.name()
        )));
    }
    if args.bake.as_deref().is_some_and(is_glb) && method == RenderMethod::HybridDirect {
        return Err(CliError::Input(format!(
            "--bake {}: a lightmap holds the total diffuse light, not the indirect part \
             hybrid-direct adds to its direct light; use radiosity or hybrid, or a .bake file",
            args.bake.as_deref().unwrap_or(Path::new("")).display()
        )));
    }
    let decisions = plan(&scene);
    if goal.is_some() && explicit.is_none() && !decisions.diffuse.required {
        method = RenderMethod::Reference;
    }
    // Checked now with the method so far; named again once the planner has chosen.
    targets(ctx.output.as_deref(), &args.scene, method, args.png)?;
    let camera = ctx.camera(&scene.camera)?;
    let mut skipped = Vec::new();
    if method.needs_radiosity() && !decisions.diffuse.required {
        return Err(CliError::Input(format!(
            "{}: no radiosity to compute: {}",
            args.scene.display(),
            decisions.diffuse.reason
        )));
    }
    if matches!(
        method,
        RenderMethod::Hybrid | RenderMethod::HybridClassic | RenderMethod::HybridDirect
    ) && !decisions.specular.required
    {
        skipped.push(format!(
            "specular pass skipped: {}",
            decisions.specular.reason
        ));
    }
    if method.needs_radiosity() && args.bake.is_none() {
        let (needed, _) = twopass_radiosity::specular::decide(&scene);
        if needed && solve.specular_rays == 0 {
            skipped.push(
                "specular transfer skipped: --specular-rays 0 (mirrors and glass absorb in the \
                 radiosity pass)"
                    .into(),
            );
        }
    }
    let started = Instant::now();
    let solution = if method.needs_radiosity() {
        Some(radiosity(
            &scene,
            &args.scene,
            args.bake.as_deref(),
            solve,
            ctx,
        )?)
    } else {
        None
    };
    let radiosity_seconds = started.elapsed().as_secs_f64();
    let reference_settings = ReferenceSettings {
        light_paths: args
            .light_paths
            .map_or(LightPaths::Planned, LightPaths::PerSample),
        splits: args.splits.map_or(PathSplits::Planned, PathSplits::Fixed),
        ..ReferenceSettings::default()
    };
    let whitted = WhittedSettings {
        caustic_paths: args
            .light_paths
            .unwrap_or(WhittedSettings::default().caustic_paths),
        ..knobs.whitted()
    };
    let mut integrator = integrator(
        method,
        &scene,
        solution.as_ref().map(|s| s.0.as_dyn()),
        whitted,
        reference_settings,
    );
    let render_plan = match goal {
        Some(goal) => {
            let reference = (explicit.is_none() && method != RenderMethod::Reference).then(|| {
                crate::pipeline::integrator(
                    RenderMethod::Reference,
                    &scene,
                    None,
                    whitted,
                    reference_settings,
                )
            });
            let mut candidates = vec![(method, integrator.as_ref(), radiosity_seconds)];
            if let Some(r) = &reference {
                candidates.push((RenderMethod::Reference, r.as_ref(), 0.0));
            }
            let p = crate::render_plan::plan(
                &scene,
                &camera,
                &candidates,
                &knobs,
                goal,
                ctx.seed,
                started,
                ctx,
            )?;
            knobs.spp = p.choice().spp;
            if p.choice().method != method {
                method = p.choice().method;
                integrator = reference.expect("the path tracer was a candidate");
            }
            Some(p)
        }
        None => None,
    };
    let targets = targets(ctx.output.as_deref(), &args.scene, method, args.png)?;
    let settings = knobs.settings(ctx.seed);
    if let Some(part) = args.part {
        let job = crate::part::render::RenderJob {
            scene_path: &args.scene,
            scene: &scene,
            camera: &camera,
            method,
            knobs,
            radiosity: crate::part::render::radiosity_source(method, args.bake.as_deref(), solve)?,
            png: args.png,
            layers: args.layers,
            exposure: args.exposure,
            started,
        };
        return crate::part::render::write_part(&job, integrator.as_ref(), &settings, part, ctx);
    }
    // Without `--spp` (or anything else that fixes the samples) the default samples per pixel
    // are a mean, spent where the noise is.
    let by_noise = args.spp.is_none()
        && knobs.adaptive.is_none()
        && args.preset.is_none()
        && render_plan.is_none();
    let (out, allocation) = crate::allocation::render(
        &scene,
        &camera,
        integrator.as_ref(),
        &settings,
        by_noise,
        method.name(),
        ctx,
    )?;
    let layers = to_layers(&out.layers)?;
    if let Some(exr) = &targets.exr {
        crate::output::create_dir(exr.parent().unwrap_or(Path::new("")))?;
        // The header says how it was made: method, samples, seed, and the seconds of the
        // whole run (solve and render).
        let seconds = radiosity_seconds + out.stats.elapsed.as_secs_f64();
        let metadata = RenderMetadata::new(method.name(), knobs.spp, ctx.seed, seconds);
        if args.layers {
            write_exr_render(exr, &layers, &metadata)?;
        } else {
            write_exr_render_rgba(exr, &layers, &metadata)?;
        }
    }
    if let Some(png) = &targets.png {
        let image = layers.require("image")?;
        let map = match args.exposure {
            Some(stops) => ToneMap::from_stops(stops)?,
            None => ToneMap::auto(image, 0.99, 1.0)?,
        };
        crate::output::create_dir(png.parent().unwrap_or(Path::new("")))?;
        write_png_tonemapped(png, image, &map)?;
    }
    let Targets { exr, png } = targets;
    let s = &out.stats;
    let mean = out.layers.composite().mean();
    let summary = Summary {
        scene: args.scene.clone(),
        method,
        preset: args.preset.clone(),
        width: camera.width,
        height: camera.height,
        spp: knobs.spp,
        refined_pixels: s.refined_pixels,
        radiosity: solution.as_ref().map(|s| s.1),
        radiosity_seconds,
        render_seconds: s.elapsed.as_secs_f64(),
        rays: s.rays,
        shadow_rays: s.shadow_rays,
        mrays_per_s: s.rays_per_second() / 1e6,
        non_finite_samples: s.non_finite,
        light_paths: s.light_paths,
        light_plan: s.light_plan.as_ref().map(LightPlanSummary::from),
        splits: s.splits,
        split_plan: s.split_plan.as_ref().map(SplitPlanSummary::from),
        mean: mean.to_array(),
        exr,
        png,
        skipped,
        plan: render_plan,
        allocation,
    };
    crate::output::report(&summary, ctx, || summary.print(knobs.adaptive))
}

/// The files `render` writes: the multi-layer EXR and the tone-mapped PNG, each when asked for.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct Targets {
    /// The EXR (plain RGBA, or every layer with `--layers`).
    pub exr: Option<PathBuf>,
    /// The tone-mapped PNG.
    pub png: Option<PathBuf>,
}

/// Extensions that name an image file rather than a directory for `--output`.
const IMAGE_EXTENSIONS: [&str; 10] = [
    "exr", "png", "jpg", "jpeg", "tif", "tiff", "bmp", "hdr", "tga", "webp",
];

/// Where `render` writes, from `--output`: `x.exr` is the EXR (with `--png`, `x.png` beside
/// it), `x.png` is the PNG alone, and a path without an image extension (or ending in `/`) is
/// a directory for `<stem>-<method>.exr` (and `.png`); without `--output`, the current one. An
/// image format `render` cannot write is a usage error.
pub(crate) fn targets(
    output: Option<&Path>,
    scene: &Path,
    method: RenderMethod,
    png: bool,
) -> Result<Targets, CliError> {
    let stem = scene
        .file_stem()
        .map_or_else(|| "render".to_owned(), |s| s.to_string_lossy().into_owned());
    let in_dir = |dir: &Path| {
        let exr = dir.join(format!("{stem}-{}.exr", method.name()));
        let png = png.then(|| exr.with_extension("png"));
        Targets {
            exr: Some(exr),
            png,
        }
    };
    let Some(path) = output else {
        return Ok(in_dir(Path::new("")));
    };
    let names_dir = path
        .as_os_str()
        .to_string_lossy()
        .ends_with(['/', std::path::MAIN_SEPARATOR]);
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .filter(|e| !names_dir && IMAGE_EXTENSIONS.contains(&e.as_str()));
    match extension.as_deref() {
        None => Ok(in_dir(path)),
        Some("exr") => Ok(Targets {
            exr: Some(path.to_owned()),
            png: png.then(|| path.with_extension("png")),
        }),
        Some("png") => Ok(Targets {
            exr: None,
            png: Some(path.to_owned()),
        }),
        Some(other) => Err(CliError::Usage(format!(
            "--output {}: render writes .exr or .png, not .{other} (or name a directory)",
            path.display()
        ))),
    }
}

/// Samples per pixel of a render that names neither `--spp` nor a goal for the planner (the
/// gathered hybrid: [`RenderDefaults`]).
pub const DEFAULT_SPP: u32 = 16;

/// A method's samples and rays per sample when the command line names none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderDefaults {
    /// Samples per pixel.
    pub spp: u32,
    /// Shadow-ray grid side ([`WhittedSettings::shadow_grid`]).
    pub shadow_grid: u32,
    /// Gather rays per camera sample ([`WhittedSettings::gather_rays`]).
    pub gather_rays: u32,
}

impl RenderDefaults {
    /// The defaults of `method`. The gathered hybrid takes 64 camera samples of 4 gather rays
    /// and 2 x 2 shadow rays each. Its gather and shadow rays are stratified over the pixel's
    /// samples, so the camera's own noise (the edges, what mirrors and glass show of small
    /// bright emitters) needs the samples, and the gather's noise falls faster than one over
    /// its rays: 4 rays instead of 2 at each sample leave 1.7-2.2 times less squared noise for
    /// the time on six of eight scenes, 1.1 times on one and 0.92 times on the chrome room,
    /// whose noise is the camera's (docs/benchmarks.md, "The gathered hybrid").
    pub fn of(method: RenderMethod) -> Self {
        let w = WhittedSettings::default();
        match method {
            RenderMethod::Hybrid => Self {
                spp: 64,
                shadow_grid: 2,
                gather_rays: 4,
            },
            _ => Self {
                spp: DEFAULT_SPP,
                shadow_grid: w.shadow_grid,
                gather_rays: w.gather_rays,
            },
        }
    }
}

/// A noise target: a relative RMSE in (0, 1).
fn parse_target_error(s: &str) -> Result<f64, String> {
    checked(
        s,
        |x: &f64| *x > 0.0 && *x < 1.0,
        "must be a fraction in (0, 1), e.g. 0.02 for 2 %",
    )
}

/// Light paths per camera sample: more than 0 (no light paths would leave the caustics out),
/// at most the most a pilot picks.
fn parse_light_paths(s: &str) -> Result<f32, String> {
    let most = twopass_trace::light_plan::PLANNED_RANGE.1;
    checked(
        s,
        |x: &f32| *x > 0.0 && *x <= most,
        &format!("must be more than 0 and at most {most} light paths per camera sample"),
    )
}

/// Most stops of exposure either way: 2^64 spans far more than any radiance a scene can emit.
const MAX_STOPS: f32 = 64.0;

/// An exposure in stops: finite and within +-[`MAX_STOPS`].
fn parse_stops(s: &str) -> Result<f32, String> {
    let needs = format!("must be a finite number of stops from -{MAX_STOPS} to {MAX_STOPS}");
    checked(s, |x: &f32| x.abs() <= MAX_STOPS, &needs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(output: Option<&str>, png: bool) -> Result<Targets, CliError> {
        targets(
            output.map(Path::new),
            Path::new("scenes/box.toml"),
            RenderMethod::Hybrid,
            png,
        )
    }

    #[test]
    fn output_names_a_file_by_its_image_extension_and_a_directory_otherwise() {
        // (--output, --png, the EXR and the PNG written)
        let cases = [
            (None, false, Some("box-hybrid.exr"), None),
            (None, true, Some("box-hybrid.exr"), Some("box-hybrid.png")),
            (Some("a/out.exr"), false, Some("a/out.exr"), None),
            (Some("out.EXR"), true, Some("out.EXR"), Some("out.png")),
            (Some("out.png"), false, None, Some("out.png")),
            (Some("out.png"), true, None, Some("out.png")),
            (Some("renders"), false, Some("renders/box-hybrid.exr"), None),
            (
                Some("run.v2"),
                true,
                Some("run.v2/box-hybrid.exr"),
                Some("run.v2/box-hybrid.png"),
            ),
            (
                Some("out.png/"),
                false,
                Some("out.png/box-hybrid.exr"),
                None,
            ),
        ];
        for (output, png, exr_file, png_file) in cases {
            let want = Targets {
                exr: exr_file.map(PathBuf::from),
                png: png_file.map(PathBuf::from),
            };
            assert_eq!(t(output, png).unwrap(), want, "--output {output:?}");
        }
        match t(Some("out.jpg"), false) {
            Err(CliError::Usage(m)) => assert!(m.contains(".jpg"), "{m}"),
            other => panic!("a .jpg output must be a usage error: {other:?}"),
        }
    }
}
