//! `twopass render SCENE --method M`: one image with one method, written as a multi-layer EXR
//! (every layer of the tracer plus the final image) and, with `--png`, a tone-mapped PNG.
//!
//! The radiosity-based methods take their diffuse light from a fresh solve, or from a bake file
//! of `twopass bake` (`--bake FILE`), which renders any view without solving again.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::{Args, ValueEnum};
use serde::{Deserialize, Serialize};
use twopass_composite::image::Image;
use twopass_composite::layer::Layers;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::{write_exr_layers, write_png_tonemapped};
use twopass_radiosity::{Solution, Solver};
use twopass_scene::Scene;
use twopass_trace::hybrid::{hybrid, hybrid_direct, radiosity_only};
use twopass_trace::whitted::ambient_estimate;
use twopass_trace::{
    Integrator, Layer, LayerImages, Progress, Reference, ReferenceSettings, RenderOutput,
    RenderSettings, RenderStats, Whitted, WhittedSettings,
};

use crate::bake::SolveArgs;
use crate::context::Context;
use crate::error::CliError;
use crate::plan::plan;
use crate::preset::RenderKnobs;

/// A rendering method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Whitted ray tracing alone, with the Phong ambient term for interreflection.
    Whitted,
    /// Radiosity alone: camera rays shaded by the radiosity solution.
    Radiosity,
    /// Two-pass: radiosity for the diffuse light, the tracer for the non-diffuse terms.
    Hybrid,
    /// As hybrid, with direct diffuse light per pixel and radiosity's indirect part.
    HybridDirect,
    /// The reference path tracer.
    Reference,
}

impl Method {
    /// Whether the method reads a radiosity solution.
    pub fn needs_radiosity(self) -> bool {
        matches!(self, Self::Radiosity | Self::Hybrid | Self::HybridDirect)
    }

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Whitted => "whitted",
            Self::Radiosity => "radiosity",
            Self::Hybrid => "hybrid",
            Self::HybridDirect => "hybrid-direct",
            Self::Reference => "reference",
        }
    }
}

/// Arguments of `twopass render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (.toml) or mesh (.obj).
    pub scene: PathBuf,
    /// The method.
    #[arg(long, value_enum, default_value = "hybrid")]
    pub method: Method,
    /// Bake file from `twopass bake` for the radiosity-based methods (default: solve now).
    #[arg(long, value_name = "FILE")]
    pub bake: Option<PathBuf>,
    /// Samples per pixel (stratified).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: u32,
    /// Recursion depth of mirror and refraction paths (Whitted and the hybrids).
    /// At most 64: the recursion holds a stack frame per bounce, and a path trapped by total
    /// internal reflection keeps its full weight, so only the depth ends it.
    #[arg(long, default_value_t = WhittedSettings::default().max_depth, value_parser = clap::value_parser!(u32).range(0..=MAX_DEPTH as i64))]
    pub depth: u32,
    /// Shadow rays per emitter and hit, as an N x N stratified grid (Whitted and the hybrids).
    #[arg(long, default_value_t = WhittedSettings::default().shadow_grid, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub shadow_grid: u32,
    /// Also write a tone-mapped PNG beside the EXR.
    #[arg(long)]
    pub png: bool,
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
}

/// The arguments a preset sets, which conflict with `--preset`.
pub const PRESET_SETS: [&str; 11] = [
    "method",
    "spp",
    "depth",
    "shadow_grid",
    "unshot",
    "max_shots",
    "time_budget",
    "patch_size",
    "element_size",
    "no_adaptive",
    "visibility_rays",
];

#[derive(Debug, Serialize)]
struct Summary {
    scene: PathBuf,
    method: Method,
    preset: Option<String>,
    width: u32,
    height: u32,
    spp: u32,
    radiosity: Option<&'static str>,
    radiosity_seconds: f64,
    render_seconds: f64,
    rays: u64,
    shadow_rays: u64,
    mrays_per_s: f64,
    non_finite_samples: u64,
    /// Mean of the final image over pixels, per channel, W/(m^2 sr).
    mean: [f32; 3],
    exr: PathBuf,
    png: Option<PathBuf>,
    skipped: Vec<String>,
}

/// Loads a scene to render with several methods: prints its warnings unless quiet, and refuses
/// a scene where nothing emits (every image would be black).
pub fn load_lit(path: &Path, ctx: &Context) -> Result<Scene, CliError> {
    let (scene, warnings) = ctx.load_scene(path)?;
    if !ctx.quiet {
        for w in &warnings {
            errln!("warning: {w}");
        }
    }
    if scene.emitters.is_empty() {
        return Err(CliError::Input(format!(
            "{}: nothing emits light, every render would be black",
            path.display()
        )));
    }
    Ok(scene)
}

/// The radiosity for the radiosity-based methods: from a bake file, or solved now.
pub fn radiosity(
    scene: &Scene,
    path: &Path,
    bake: Option<&Path>,
    solve: &SolveArgs,
    ctx: &Context,
) -> Result<(Solution, &'static str), CliError> {
    match bake {
        Some(file) => {
            crate::bake::check_in_set(file)?;
            Ok((twopass_bake::read_bake(file, scene)?, "bake"))
        }
        None => {
            let mut solver =
                Solver::new(scene, solve.options(ctx.seed)).map_err(|source| CliError::Solve {
                    path: path.to_owned(),
                    source,
                })?;
            solve.run(&mut solver, ctx);
            Ok((solver.solution(), "solve"))
        }
    }
}

/// Renders with a progress bar drawn from the render loop's counters, then checks the
/// samples it had to drop (see [`check_dropped`]).
pub fn render_with_bar(
    scene: &Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    label: &str,
    ctx: &Context,
) -> Result<RenderOutput, CliError> {
    let progress = Progress::new();
    let bar = ctx.progress(1000, label);
    let done = std::sync::atomic::AtomicBool::new(false);
    let out = std::thread::scope(|s| {
        s.spawn(|| {
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                bar.set_position((progress.fraction() * 1000.0) as u64);
                std::thread::sleep(Duration::from_millis(100));
            }
        });
        let out = twopass_trace::render(scene, camera, integrator, settings, &progress);
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        out
    });
    bar.finish_and_clear();
    check_dropped(&out.stats, &scene.path, ctx)?;
    Ok(out)
}

/// Most of a render's samples that may be non-finite (and dropped) before the render is
/// refused: beyond this the image says more about the overflow than about the scene.
pub const MAX_DROPPED_FRACTION: f64 = 0.01;

/// Says loudly when a render dropped non-finite samples, and fails when it dropped more than
/// [`MAX_DROPPED_FRACTION`] of them: the image would be wrong (black where light overflowed).
pub fn check_dropped(stats: &RenderStats, scene: &Path, ctx: &Context) -> Result<(), CliError> {
    if stats.non_finite == 0 {
        return Ok(());
    }
    let fraction = stats.non_finite as f64 / stats.samples.max(1) as f64;
    let what = format!(
        "{}: the {} render dropped {} of {} samples ({:.3}%) as non-finite (NaN or infinite radiance)",
        scene.display(),
        stats.method,
        stats.non_finite,
        stats.samples,
        100.0 * fraction
    );
    if fraction > MAX_DROPPED_FRACTION {
        return Err(CliError::Input(format!(
            "{what}; the image would be wrong, so none is written (lower the emission or the scene's scale)"
        )));
    }
    if !ctx.quiet {
        errln!("warning: {what}; their pixels average the remaining samples");
    }
    Ok(())
}

/// The tracer's layers as named compositor layers, plus the final image as `image`.
pub fn to_layers(images: &LayerImages) -> Result<Layers, CliError> {
    let convert =
        |img: &twopass_trace::Image| Image::from_pixels(img.width, img.height, img.pixels.clone());
    let mut layers = Vec::with_capacity(Layer::ALL.len() + 1);
    layers.push(("image".to_owned(), convert(&images.composite())?));
    for layer in Layer::ALL {
        layers.push((layer.name().to_owned(), convert(images.layer(layer))?));
    }
    Ok(Layers::from_vec(layers)?)
}

/// The integrator of a method; `solution` must be given for the radiosity-based ones.
pub fn integrator<'a>(
    method: Method,
    scene: &'a Scene,
    solution: Option<&'a Solution>,
    whitted: WhittedSettings,
) -> Box<dyn Integrator + 'a> {
    let solution = || solution.expect("radiosity-based methods get a solution");
    match method {
        Method::Whitted => Box::new(Whitted::new(scene, ambient_estimate(scene), whitted)),
        Method::Radiosity => Box::new(radiosity_only(scene, solution())),
        Method::Hybrid => Box::new(hybrid(scene, solution(), whitted)),
        Method::HybridDirect => Box::new(hybrid_direct(scene, solution(), whitted)),
        Method::Reference => Box::new(Reference::new(scene, ReferenceSettings::default())),
    }
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
    let method = preset.as_ref().map_or(args.method, |p| p.method);
    let knobs = preset.as_ref().map_or(
        RenderKnobs {
            spp: args.spp,
            depth: args.depth,
            shadow_grid: args.shadow_grid,
        },
        |p| p.render,
    );
    let preset_solve = preset
        .as_ref()
        .and_then(|p| p.radiosity.as_ref())
        .map(SolveArgs::from_knobs);
    let solve = preset_solve.as_ref().unwrap_or(&args.solve);
    if args.bake.is_some() && !method.needs_radiosity() {
        return Err(CliError::Input(format!(
            "--bake is for the radiosity-based methods, not {}",
            method.name()
        )));
    }
    let camera = ctx.camera(&scene.camera)?;
    let decisions = plan(&scene);
    let mut skipped = Vec::new();
    if method.needs_radiosity() && !decisions.diffuse.required {
        return Err(CliError::Input(format!(
            "{}: no radiosity to compute: {}",
            args.scene.display(),
            decisions.diffuse.reason
        )));
    }
    if matches!(method, Method::Hybrid | Method::HybridDirect) && !decisions.specular.required {
        skipped.push(format!(
            "specular pass skipped: {}",
            decisions.specular.reason
        ));
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
    let integrator = integrator(
        method,
        &scene,
        solution.as_ref().map(|s| &s.0),
        knobs.whitted(),
    );
    let settings = RenderSettings {
        samples_per_pixel: knobs.spp,
        seed: ctx.seed,
        ..RenderSettings::default()
    };
    let out = render_with_bar(
        &scene,
        &camera,
        integrator.as_ref(),
        &settings,
        method.name(),
        ctx,
    )?;
    let layers = to_layers(&out.layers)?;
    let stem = args
        .scene
        .file_stem()
        .map_or_else(|| "render".to_owned(), |s| s.to_string_lossy().into_owned());
    let exr = match &ctx.output {
        Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) => p.clone(),
        Some(dir) => dir.join(format!("{stem}-{}.exr", method.name())),
        None => PathBuf::from(format!("{stem}-{}.exr", method.name())),
    };
    crate::output::create_dir(exr.parent().unwrap_or(Path::new("")))?;
    write_exr_layers(&exr, &layers)?;
    let png = if args.png {
        let image = layers.require("image")?;
        let map = match args.exposure {
            Some(stops) => ToneMap::from_stops(stops)?,
            None => ToneMap::auto(image, 0.99, 1.0)?,
        };
        let path = exr.with_extension("png");
        write_png_tonemapped(&path, image, &map)?;
        Some(path)
    } else {
        None
    };
    let s = &out.stats;
    let mean = out.layers.composite().mean();
    let summary = Summary {
        scene: args.scene.clone(),
        method,
        preset: args.preset.clone(),
        width: camera.width,
        height: camera.height,
        spp: knobs.spp,
        radiosity: solution.as_ref().map(|s| s.1),
        radiosity_seconds,
        render_seconds: s.elapsed.as_secs_f64(),
        rays: s.rays,
        shadow_rays: s.shadow_rays,
        mrays_per_s: s.rays_per_second() / 1e6,
        non_finite_samples: s.non_finite,
        mean: mean.to_array(),
        exr,
        png,
        skipped,
    };
    if ctx.json {
        crate::output::print_json(&summary)?;
    } else if !ctx.quiet {
        for s in &summary.skipped {
            outln!("{s}");
        }
        if let Some(source) = summary.radiosity {
            outln!(
                "radiosity from {source} in {:.2} s",
                summary.radiosity_seconds
            );
        }
        outln!(
            "{} {} x {} at {} spp in {:.2} s ({:.2} Mrays/s, {} non-finite samples dropped)",
            summary.method.name(),
            summary.width,
            summary.height,
            summary.spp,
            summary.render_seconds,
            summary.mrays_per_s,
            summary.non_finite_samples
        );
        outln!("wrote {}", summary.exr.display());
        if let Some(p) = &summary.png {
            outln!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// Deepest recursion of mirror and refraction paths (`--depth`, presets).
pub const MAX_DEPTH: u32 = 64;

/// Most stops of exposure either way: 2^64 spans far more than any radiance a scene can emit.
const MAX_STOPS: f32 = 64.0;

/// An exposure in stops: finite and within +-[`MAX_STOPS`].
fn parse_stops(s: &str) -> Result<f32, String> {
    let x: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if x.abs() <= MAX_STOPS {
        Ok(x)
    } else {
        Err(format!(
            "{x} must be a finite number of stops from -{MAX_STOPS} to {MAX_STOPS}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(samples: u64, non_finite: u64) -> RenderStats {
        RenderStats {
            method: "reference",
            width: 10,
            height: 10,
            samples_per_pixel: 1,
            samples,
            non_finite,
            rays: 0,
            shadow_rays: 0,
            elapsed: Duration::ZERO,
        }
    }

    fn quiet() -> Context {
        Context {
            output: None,
            width: None,
            height: None,
            seed: 0,
            threads: None,
            quiet: true,
            json: false,
            confine: false,
        }
    }

    #[test]
    fn dropped_samples_warn_then_fail() {
        let scene = Path::new("s.toml");
        assert!(check_dropped(&stats(1000, 0), scene, &quiet()).is_ok());
        // 1 % dropped is still an image worth having (with a warning).
        assert!(check_dropped(&stats(1000, 10), scene, &quiet()).is_ok());
        match check_dropped(&stats(1000, 11), scene, &quiet()) {
            Err(CliError::Input(m)) => {
                assert!(m.contains("s.toml") && m.contains("11 of 1000"), "{m}");
            }
            other => panic!("more than 1 % dropped must fail: {other:?}"),
        }
        assert!(check_dropped(&stats(100, 100), scene, &quiet()).is_err());
    }
}
