//! `twopass compare SCENE`: the Cornell-box comparison. Renders the scene with every method it
//! calls for (Whitted, radiosity alone, the hybrid gathered per pixel, the classic hybrid
//! where it differs from radiosity alone, the hybrid with per-pixel direct light, and the
//! reference path tracer) at one resolution and exposure, and writes, in `--output DIR`
//! (default `compare/`): `<stem>-compare.png` (a row of renders, a row of difference images
//! against the reference), `<stem>-<method>.exr` per method (every layer), and
//! `<stem>-compare.json` / `.csv` (method, settings, time per phase, rays, error metrics).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use serde::Serialize;
use twopass_composite::RenderMetadata;
use twopass_composite::image::Image;
use twopass_composite::metric::Metrics;
use twopass_composite::sheet::{ComparisonOptions, Entry, comparison};
use twopass_composite::write::{write_exr_render, write_png};
use twopass_radiosity::{Solution, Solver};
use twopass_scene::{Camera, Scene};
use twopass_trace::{RenderStats, WhittedSettings};

use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{
    RenderMethod, integrator, load_lit, methods, render_settings, render_with_bar, to_layers,
};

/// Arguments of `twopass compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Scene file (.toml), mesh (.obj) or glTF 2.0 (.gltf, .glb).
    pub scene: PathBuf,
    /// Draft quality: 256 pixels wide, few samples, a coarse radiosity mesh. Without it: 512
    /// wide, 16 samples per pixel, 4096 for the reference, the default radiosity mesh solved to
    /// 1e-4.
    #[arg(long)]
    pub quick: bool,
    /// Samples per pixel of the reference path tracer (overrides the preset).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub reference_spp: Option<u32>,
    /// Samples per pixel of the other methods (overrides the preset).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: Option<u32>,
}

/// What one method cost and how far it is from the reference.
#[derive(Debug, Serialize)]
struct MethodRow {
    method: &'static str,
    width: u32,
    height: u32,
    spp: u32,
    /// Radiosity solve shared by the radiosity-based methods, seconds (0 for the others).
    radiosity_seconds: f64,
    render_seconds: f64,
    total_seconds: f64,
    rays: u64,
    shadow_rays: u64,
    non_finite_samples: u64,
    /// Error metrics against the reference (empty for the reference itself).
    mae: Option<f64>,
    rmse: Option<f64>,
    rel_mse: Option<f64>,
    rel_rmse: Option<f64>,
    ssim: Option<f64>,
    exr: PathBuf,
}

#[derive(Debug, Serialize)]
struct CompareReport {
    scene: PathBuf,
    quick: bool,
    seed: u64,
    threads: usize,
    /// Radiosity: elements, patches, shots, shadow rays, unshot fraction reached.
    radiosity: Option<RadiosityInfo>,
    skipped: Vec<String>,
    tone_map: String,
    sheet: PathBuf,
    rows: Vec<MethodRow>,
}

#[derive(Debug, Serialize)]
struct RadiosityInfo {
    solver: &'static str,
    elements: usize,
    patches: usize,
    shots: u64,
    rays: u64,
    unshot_fraction: f64,
    seconds: f64,
}

/// One method's render: its image, costs and EXR.
struct Rendered {
    method: RenderMethod,
    image: Image,
    /// The shared radiosity solve, seconds (0 for the methods without radiosity).
    radiosity_seconds: f64,
    stats: RenderStats,
    exr: PathBuf,
}

/// Renders, compares and writes everything.
pub fn run(args: &CompareArgs, ctx: &Context) -> Result<(), CliError> {
    let scene = load_lit(&args.scene, ctx)?;
    let default_width = if args.quick { 256 } else { 512 };
    let camera = match (ctx.width, ctx.height) {
        (None, None) => crate::context::resized(&scene.camera, Some(default_width), None)?,
        (w, h) => crate::context::resized(&scene.camera, w, h)?,
    };
    let spp = args.spp.unwrap_or(if args.quick { 4 } else { 16 });
    let reference_spp = args
        .reference_spp
        .unwrap_or(if args.quick { 64 } else { 4096 });
    let (methods, skipped) = methods(&scene);
    let dir = ctx
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("compare"));
    crate::output::create_dir(&dir)?;
    let stem = args
        .scene
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());

    // One radiosity solve serves every radiosity-based method.
    let needs_radiosity = methods.iter().any(|m| m.needs_radiosity());
    let solved = if needs_radiosity {
        Some(solve_shared(&scene, args, ctx)?)
    } else {
        None
    };

    let images = render_methods(
        &scene,
        &camera,
        &methods,
        solved.as_ref().map(|s| (&s.0, s.1.seconds)),
        (spp, reference_spp),
        (&dir, &stem),
        ctx,
    )?;

    let (reference, others) = images
        .split_first()
        .expect("the reference is always rendered");
    fn entry(r: &Rendered) -> Entry<'_> {
        Entry {
            method: r.method.name(),
            image: &r.image,
            seconds: Some(r.radiosity_seconds + r.stats.elapsed.as_secs_f64()),
        }
    }
    let options = ComparisonOptions {
        title: Some(format!(
            "{}: {} x {}, {} spp ({} for the reference)",
            args.scene.display(),
            camera.width,
            camera.height,
            spp,
            reference_spp
        )),
        ..ComparisonOptions::default()
    };
    let sheet = comparison(
        &entry(reference),
        &others.iter().map(entry).collect::<Vec<_>>(),
        &options,
    )?;
    let sheet_path = dir.join(format!("{stem}-compare.png"));
    write_png(&sheet_path, &sheet.image, Some(&sheet.describe))?;

    let rows = method_rows(&images, &sheet.metrics);
    let report = CompareReport {
        scene: args.scene.clone(),
        quick: args.quick,
        seed: ctx.seed,
        threads: rayon::current_num_threads(),
        radiosity: solved.map(|s| s.1),
        skipped,
        tone_map: sheet.tone_map.describe(),
        sheet: sheet_path,
        rows,
    };
    crate::output::write_csv(&dir.join(format!("{stem}-compare.csv")), &report.rows)?;
    let json = dir.join(format!("{stem}-compare.json"));
    crate::output::finish_report(&json, &report, ctx, print_report)
}

/// The one radiosity solve every radiosity-based method shares ([`SolveArgs::compare`]).
///
/// [`SolveArgs::compare`]: crate::solve::SolveArgs::compare
fn solve_shared(
    scene: &Scene,
    args: &CompareArgs,
    ctx: &Context,
) -> Result<(Solution, RadiosityInfo), CliError> {
    let started = Instant::now();
    let options = crate::solve::SolveArgs::compare(scene, args.quick).options(ctx.seed);
    let mut solver = Solver::new(scene, options).map_err(|source| CliError::Solve {
        path: args.scene.clone(),
        source,
    })?;
    let bar = ctx.progress(1, "radiosity");
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    bar.finish_and_clear();
    solver.check_energy().map_err(|source| CliError::Solve {
        path: args.scene.clone(),
        source,
    })?;
    let p = solver.progress();
    let info = RadiosityInfo {
        solver: p.method.name(),
        elements: p.elements,
        patches: p.patches,
        shots: p.shots,
        rays: p.rays,
        unshot_fraction: p.unshot_fraction,
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok((solver.solution(), info))
}

/// Renders every method at one resolution (the reference with its own sample count), writing
/// each method's layers as `<stem>-<method>.exr` in `dir`.
fn render_methods(
    scene: &Scene,
    camera: &Camera,
    methods: &[RenderMethod],
    solved: Option<(&Solution, f64)>,
    (spp, reference_spp): (u32, u32),
    (dir, stem): (&Path, &str),
    ctx: &Context,
) -> Result<Vec<Rendered>, CliError> {
    let mut images = Vec::with_capacity(methods.len());
    for &method in methods {
        let integ = integrator(
            method,
            scene,
            solved.map(|s| s.0 as &dyn twopass_scene::DiffuseRadiance),
            WhittedSettings::default(),
            twopass_trace::ReferenceSettings::default(),
        );
        let settings = render_settings(
            if method == RenderMethod::Reference {
                reference_spp
            } else {
                spp
            },
            ctx.seed,
        );
        let out = render_with_bar(scene, camera, integ.as_ref(), &settings, method.name(), ctx)?;
        let layers = to_layers(&out.layers)?;
        let exr = dir.join(format!("{stem}-{}.exr", method.name()));
        let image = layers.require("image")?.clone();
        let radiosity_seconds = if method.needs_radiosity() {
            solved.map_or(0.0, |s| s.1)
        } else {
            0.0
        };
        let metadata = RenderMetadata::new(
            method.name(),
            settings.samples_per_pixel,
            ctx.seed,
            radiosity_seconds + out.stats.elapsed.as_secs_f64(),
        );
        write_exr_render(&exr, &layers, &metadata)?;
        images.push(Rendered {
            method,
            image,
            radiosity_seconds,
            stats: out.stats,
            exr,
        });
    }
    Ok(images)
}

/// The report's rows: each method's cost and, after the reference, its error metrics.
fn method_rows(images: &[Rendered], metrics: &[Metrics]) -> Vec<MethodRow> {
    images
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let metrics = i.checked_sub(1).map(|k| metrics[k]);
            let stats = &r.stats;
            let render_seconds = stats.elapsed.as_secs_f64();
            MethodRow {
                method: r.method.name(),
                width: r.image.width(),
                height: r.image.height(),
                spp: stats.samples_per_pixel,
                radiosity_seconds: r.radiosity_seconds,
                render_seconds,
                total_seconds: r.radiosity_seconds + render_seconds,
                rays: stats.rays,
                shadow_rays: stats.shadow_rays,
                non_finite_samples: stats.non_finite,
                mae: metrics.map(|x| x.mae),
                rmse: metrics.map(|x| x.rmse),
                rel_mse: metrics.map(|x| x.rel_mse),
                rel_rmse: metrics.map(|x| x.rel_rmse),
                ssim: metrics.map(|x| x.ssim),
                exr: r.exr.clone(),
            }
        })
        .collect()
}

/// The report as a table on stdout.
fn print_report(report: &CompareReport) -> Result<(), CliError> {
    for s in &report.skipped {
        outln!("skipped {s}");
    }
    if let Some(r) = &report.radiosity {
        outln!(
            "radiosity: {} elements, {} patches, {} shots, unshot {:.1e}, {:.2} s",
            r.elements,
            r.patches,
            r.shots,
            r.unshot_fraction,
            r.seconds
        );
    }
    outln!(
        "{:<14} {:>9} {:>9} {:>10} {:>9} {:>7}",
        "method",
        "spp",
        "seconds",
        "rel RMSE",
        "RMSE",
        "SSIM"
    );
    for r in &report.rows {
        let pct =
            |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |v| format!("{:.2}%", 100.0 * v));
        let num = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |v| format!("{v:.4}"));
        outln!(
            "{:<14} {:>9} {:>9.2} {:>10} {:>9} {:>7}",
            r.method,
            r.spp,
            r.total_seconds,
            pct(r.rel_rmse),
            num(r.rmse),
            num(r.ssim)
        );
    }
    outln!(
        "wrote {} and the EXRs, JSON and CSV beside it",
        report.sheet.display()
    );
    Ok(())
}
