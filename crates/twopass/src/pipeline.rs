//! The pipeline every rendering command shares (`render`, `compare`, `bench render`, `bench
//! tradeoff`): the methods and which a scene calls for, loading a lit scene, the radiosity from
//! a bake file or a fresh solve, the integrator of a method, rendering with a progress bar, and
//! the tracer's layers as the compositor's.

use std::path::Path;
use std::time::Duration;

use clap::ValueEnum;
use serde::{Deserialize, Serialize};
use twopass_bake::Manifest;
use twopass_composite::layer::Layers;
use twopass_radiosity::{Solution, Solver};
use twopass_scene::{DiffuseRadiance, Scene};
use twopass_trace::hybrid::{DirectLight, gathered, hybrid, radiosity_only};
use twopass_trace::whitted::ambient_estimate;
use twopass_trace::{
    Integrator, Layer, LayerImages, Reference, ReferenceSettings, RenderOutput, RenderProgress,
    RenderSettings, RenderStats, SampleBudget, Whitted, WhittedSettings,
};

use crate::context::Context;
use crate::error::CliError;
use crate::plan::plan;
use crate::solve::SolveArgs;

/// A rendering method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RenderMethod {
    /// Whitted ray tracing alone, with the Phong ambient term for interreflection.
    Whitted,
    /// Radiosity alone: camera rays shaded by the radiosity solution.
    Radiosity,
    /// Two-pass with a final gather per pixel: direct light by shadow rays, indirect light by
    /// gather rays reading the radiosity solution where they land, the tracer for the
    /// non-diffuse terms.
    Hybrid,
    /// The classic two-pass hybrid: the radiosity solution shown where the camera (or a mirror
    /// or glass) sees a diffuse surface, the tracer for the non-diffuse terms.
    HybridClassic,
    /// As hybrid-classic, with direct diffuse light per pixel and radiosity's indirect part.
    HybridDirect,
    /// The reference path tracer.
    Reference,
}

impl RenderMethod {
    /// Whether the method reads a radiosity solution.
    pub fn needs_radiosity(self) -> bool {
        matches!(
            self,
            Self::Radiosity | Self::Hybrid | Self::HybridClassic | Self::HybridDirect
        )
    }

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Whitted => "whitted",
            Self::Radiosity => "radiosity",
            Self::Hybrid => "hybrid",
            Self::HybridClassic => "hybrid-classic",
            Self::HybridDirect => "hybrid-direct",
            Self::Reference => "reference",
        }
    }
}

/// Deepest recursion of mirror and refraction paths (`--depth`, presets).
pub const MAX_DEPTH: u32 = 64;

/// The methods a scene calls for, and what was skipped and why.
pub fn methods(scene: &Scene) -> (Vec<RenderMethod>, Vec<String>) {
    let p = plan(scene);
    let mut methods = vec![RenderMethod::Reference, RenderMethod::Whitted];
    let mut skipped = Vec::new();
    if p.diffuse.required {
        methods.push(RenderMethod::Radiosity);
        methods.push(RenderMethod::Hybrid);
        if p.specular.required {
            methods.push(RenderMethod::HybridClassic);
        } else {
            skipped.push(format!(
                "hybrid-classic: identical to radiosity alone, the specular pass is skipped ({})",
                p.specular.reason
            ));
        }
        methods.push(RenderMethod::HybridDirect);
    } else {
        skipped.push(format!(
            "radiosity, hybrid, hybrid-classic, hybrid-direct: {}",
            p.diffuse.reason
        ));
    }
    (methods, skipped)
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
    if !scene.has_light() {
        return Err(CliError::Input(format!(
            "{}: nothing emits light, every render would be black",
            path.display()
        )));
    }
    Ok(scene)
}

/// The diffuse light of the radiosity-based methods: a radiosity solution (solved now or read
/// from a `.bake` file), or a lightmap bake read back (`.lightmap.glb` and its HDR EXR).
pub enum Radiosity {
    /// A radiosity solution (boxed: it is much larger than the lightmap's handle).
    Solution(Box<Solution>),
    /// A lightmap bake: the lightmap sampled at each hit's `TEXCOORD_1`.
    Lightmap(twopass_bake::LightmapRadiance),
}

impl Radiosity {
    /// The diffuse light as the tracer takes it.
    pub fn as_dyn(&self) -> &dyn DiffuseRadiance {
        match self {
            Self::Solution(s) => s.as_ref(),
            Self::Lightmap(l) => l,
        }
    }
}

/// Whether `--bake FILE` names a lightmap `.glb` rather than a `.bake` file.
pub fn is_glb(file: &Path) -> bool {
    file.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
}

/// The radiosity for the radiosity-based methods: from a bake file, a lightmap `.glb` (with
/// its HDR EXR beside it), or solved now.
pub fn radiosity(
    scene: &Scene,
    path: &Path,
    bake: Option<&Path>,
    solve: &SolveArgs,
    ctx: &Context,
) -> Result<(Radiosity, &'static str), CliError> {
    match bake {
        Some(file) if is_glb(file) => {
            check_in_set(file)?;
            check_in_set(&twopass_bake::lightmap_exr_path(file))?;
            let lightmap = twopass_bake::read_lightmap_glb(file, scene)?;
            Ok((Radiosity::Lightmap(lightmap), "lightmap"))
        }
        Some(file) => {
            check_in_set(file)?;
            Ok((
                Radiosity::Solution(Box::new(twopass_bake::read_bake(file, scene)?)),
                "bake",
            ))
        }
        None => {
            let mut solver =
                Solver::new(scene, solve.options(ctx.seed)).map_err(|source| CliError::Solve {
                    path: path.to_owned(),
                    source,
                })?;
            solve
                .run(&mut solver, ctx)
                .map_err(|source| CliError::Solve {
                    path: path.to_owned(),
                    source,
                })?;
            if !ctx.quiet {
                crate::solve::warn_close_lights(path, scene, solver.mesh());
            }
            Ok((Radiosity::Solution(Box::new(solver.solution())), "solve"))
        }
    }
}

/// The render settings every command uses: `spp` stratified samples per pixel, the run's seed,
/// the rest at the tracer's defaults.
pub fn render_settings(spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: spp,
        seed,
        ..RenderSettings::default()
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
    render_maybe_budgeted(scene, camera, integrator, settings, None, label, ctx)
}

/// [`render_with_bar`] with each pixel's samples from `budget`
/// ([`twopass_trace::render_budgeted`]), whose size must be the camera's.
pub fn render_budgeted_with_bar(
    scene: &Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: &SampleBudget,
    label: &str,
    ctx: &Context,
) -> Result<RenderOutput, CliError> {
    if budget.size() != (camera.width, camera.height) {
        return Err(CliError::Input(format!(
            "{}: a sample budget of {:?} pixels for a {} x {} camera",
            scene.path.display(),
            budget.size(),
            camera.width,
            camera.height
        )));
    }
    render_maybe_budgeted(
        scene,
        camera,
        integrator,
        settings,
        Some(budget),
        label,
        ctx,
    )
}

fn render_maybe_budgeted(
    scene: &Scene,
    camera: &twopass_scene::Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: Option<&SampleBudget>,
    label: &str,
    ctx: &Context,
) -> Result<RenderOutput, CliError> {
    let progress = RenderProgress::new();
    let bar = ctx.progress(1000, label);
    // The bar is redrawn every 100 ms until the render ends, which drops `stop`: the drawing
    // thread wakes at once then, rather than finishing a sleep the render would wait out.
    let (stop, stopped) = std::sync::mpsc::channel::<()>();
    let out = std::thread::scope(|s| {
        let (bar, progress) = (&bar, &progress);
        s.spawn(move || {
            loop {
                bar.set_position((progress.fraction() * 1000.0) as u64);
                match stopped.recv_timeout(Duration::from_millis(100)) {
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                    _ => break,
                }
            }
        });
        let out = match budget {
            Some(b) => {
                twopass_trace::render_budgeted(scene, camera, integrator, settings, b, progress)
                    .expect("the budget's size was checked")
            }
            None => twopass_trace::render(scene, camera, integrator, settings, progress),
        };
        drop(stop);
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
    let mut layers = Vec::with_capacity(Layer::ALL.len() + 1);
    layers.push(("image".to_owned(), images.composite()));
    for layer in Layer::ALL {
        layers.push((layer.name().to_owned(), images.layer(layer).clone()));
    }
    Ok(Layers::from_vec(layers)?)
}

/// The integrator of a method; `solution` must be given for the radiosity-based ones.
pub fn integrator<'a>(
    method: RenderMethod,
    scene: &'a Scene,
    solution: Option<&'a dyn DiffuseRadiance>,
    whitted: WhittedSettings,
    reference: ReferenceSettings,
) -> Box<dyn Integrator + 'a> {
    let solution = || solution.expect("radiosity-based methods get a solution");
    match method {
        RenderMethod::Whitted => Box::new(Whitted::new(scene, ambient_estimate(scene), whitted)),
        RenderMethod::Radiosity => Box::new(radiosity_only(scene, solution())),
        RenderMethod::Hybrid => Box::new(gathered(scene, solution(), whitted)),
        RenderMethod::HybridClassic => Box::new(hybrid(
            scene,
            solution(),
            DirectLight::FromSolution,
            whitted,
        )),
        RenderMethod::HybridDirect => {
            Box::new(hybrid(scene, solution(), DirectLight::PerPixel, whitted))
        }
        RenderMethod::Reference => Box::new(Reference::new(scene, reference)),
    }
}

/// Checks a bake file's set against the manifest beside it (`<stem>.manifest.json`, for
/// `<stem>.lightmap.glb` and `.exr` too): every file the manifest seals, not only the one
/// asked for, must be there with the recorded size and CRC-32. A set with a file from another
/// bake (one interrupted between its files), a damaged file or a missing one is refused whole,
/// and so is a file without its manifest: `bake` writes the manifest last, so a set without
/// one is a bake that never finished (or one whose seal was removed), and its files cannot be
/// told from another bake's.
pub fn check_in_set(file: &Path) -> Result<(), CliError> {
    let (Some(dir), Some(stem), Some(name)) = (file.parent(), file.file_stem(), file.file_name())
    else {
        return Ok(());
    };
    // A lightmap's files (`x.lightmap.glb`, `x.lightmap.exr`) belong to `x.manifest.json`.
    let stem = stem.to_string_lossy();
    let stem = stem.strip_suffix(".lightmap").unwrap_or(&stem);
    let manifest_path = dir.join(format!("{stem}.manifest.json"));
    let text = match crate::output::read_small(&manifest_path) {
        Ok(text) => text,
        // A named file that is not there, or not a regular file (a FIFO, a device), is left
        // to its reader, which says so of the file itself.
        Err(e)
            if e.kind() == std::io::ErrorKind::NotFound
                && !std::fs::metadata(file).is_ok_and(|m| m.is_file()) =>
        {
            return Ok(());
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let folder = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            return Err(CliError::Input(format!(
                "{}: {} has no manifest beside it ({} is missing): a bake writes its manifest \
                 last, so this set is incomplete or its seal was removed; bake again into {}",
                folder.display(),
                name.to_string_lossy(),
                manifest_path.display(),
                folder.display()
            )));
        }
        Err(e) => return Err(CliError::io(&manifest_path, e)),
    };
    let manifest: Manifest = serde_json::from_slice(&text).map_err(|e| {
        CliError::Input(format!(
            "{}: not a bake manifest ({e}); remove it or bake again",
            manifest_path.display()
        ))
    })?;
    if !manifest
        .files
        .iter()
        .any(|f| f.path.file_name() == Some(name))
    {
        return Ok(());
    }
    for record in &manifest.files {
        if let Some(member) = record.path.file_name() {
            check_record(&dir.join(member), record, &manifest_path)?;
        }
    }
    Ok(())
}

/// Checks one file of a sealed set against its record: a regular file (opening a FIFO would
/// block), of the recorded size, with the recorded CRC-32 (read in pieces: a set's images may
/// be large).
fn check_record(
    path: &Path,
    record: &twopass_bake::FileRecord,
    manifest_path: &Path,
) -> Result<(), CliError> {
    use std::io::Read;
    let refuse = |what: String| {
        CliError::Input(format!(
            "{}: does not match its manifest {} ({what}): the bake set is mixed or damaged, \
             probably from a bake stopped between its files; bake again",
            path.display(),
            manifest_path.display()
        ))
    };
    let meta = match std::fs::metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(refuse("missing".into()));
        }
        Err(e) => return Err(CliError::io(path, e)),
    };
    if !meta.is_file() {
        return Err(refuse("not a regular file".into()));
    }
    if meta.len() != record.bytes {
        return Err(refuse(format!(
            "{} bytes, recorded {}",
            meta.len(),
            record.bytes
        )));
    }
    let Some(crc) = record.crc32 else {
        return Ok(());
    };
    let mut hasher = crc32fast::Hasher::new();
    let mut reader = std::fs::File::open(path).map_err(|e| CliError::io(path, e))?;
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let n = reader
            .read(&mut buffer)
            .map_err(|e| CliError::io(path, e))?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
    }
    if hasher.finalize() == crc {
        Ok(())
    } else {
        Err(refuse("its CRC-32 differs".into()))
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
            refined_pixels: 0,
            non_finite,
            rays: 0,
            shadow_rays: 0,
            light_paths: 0,
            light_plan: None,
            splits: 1,
            split_plan: None,
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
