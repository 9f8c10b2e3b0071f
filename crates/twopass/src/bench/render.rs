//! `twopass bench render`: render time and rays per second of every method, and frames per
//! second of new views rendered from a bake file (radiosity alone).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;

use super::memory::{fmt_mib, mib, peak_memory, reset_peak_memory};
use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass bench render`.
#[derive(Debug, Args)]
pub struct RenderBenchArgs {
    /// Scene file (.toml or .obj).
    pub scene: PathBuf,
    /// Bake file from `twopass bake` for the radiosity-based methods (default: solve now).
    #[arg(long)]
    pub bake: Option<PathBuf>,
    /// Samples per pixel of every method.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: u32,
    /// Views rendered from the bake for the frames-per-second figure.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
}

/// One method's render measurement.
#[derive(Debug, Serialize)]
struct RenderRow {
    method: &'static str,
    seconds: f64,
    /// Camera, secondary and shadow rays per second, millions.
    mrays_per_s: f64,
    /// Mean of the image over pixels and channels, W/(m^2 sr).
    mean: f64,
    non_finite: u64,
    /// Largest resident memory while rendering (scene, radiosity solution, film), MiB.
    peak_memory_mib: Option<f64>,
}

#[derive(Debug, Serialize)]
struct RenderReport {
    scene: String,
    width: u32,
    height: u32,
    spp: u32,
    threads: usize,
    /// Where the radiosity came from: "bake" or "solve", and how long that took.
    radiosity_source: &'static str,
    radiosity_seconds: f64,
    rows: Vec<RenderRow>,
    /// Radiosity alone from the bake, 1 sample per pixel, new views around the camera.
    frames: u32,
    frames_per_second: f64,
}

/// Renders with every method, then new views from the solution.
pub fn run(args: &RenderBenchArgs, ctx: &Context) -> Result<(), CliError> {
    use crate::pipeline::{RenderMethod, check_in_set, integrator, render_settings};
    use twopass_trace::hybrid::radiosity_only;
    use twopass_trace::{Integrator, RenderProgress, WhittedSettings};

    let (scene, _) = ctx.load_scene(&args.scene)?;
    let camera = crate::context::resized(
        &scene.camera,
        Some(ctx.width.unwrap_or(512)),
        ctx.height.or(Some(ctx.width.unwrap_or(512))),
    )?;
    let started = Instant::now();
    let (solution, source) = match &args.bake {
        Some(path) => {
            check_in_set(path)?;
            (twopass_bake::read_bake(path, &scene)?, "bake")
        }
        None => {
            let mut solver = twopass_radiosity::Solver::new(
                &scene,
                crate::solve::SolveArgs::default().options(ctx.seed),
            )
            .map_err(|source| CliError::Solve {
                path: args.scene.clone(),
                source,
            })?;
            solver.run(|_| std::ops::ControlFlow::Continue(()));
            (solver.solution(), "solve")
        }
    };
    let radiosity_seconds = started.elapsed().as_secs_f64();
    let settings = render_settings(args.spp, ctx.seed);
    let w = WhittedSettings::default();
    let methods: Vec<Box<dyn Integrator + '_>> = [
        RenderMethod::Whitted,
        RenderMethod::Radiosity,
        RenderMethod::Hybrid,
        RenderMethod::HybridClassic,
        RenderMethod::HybridDirect,
        RenderMethod::Reference,
    ]
    .into_iter()
    .map(|m| {
        integrator(
            m,
            &scene,
            Some(&solution as &dyn twopass_scene::DiffuseRadiance),
            w,
            twopass_trace::ReferenceSettings::default(),
        )
    })
    .collect();
    let bar = ctx.progress(methods.len() as u64 + 1, "bench render");
    let mut rows = Vec::new();
    for m in &methods {
        reset_peak_memory();
        let out = twopass_trace::render(
            &scene,
            &camera,
            m.as_ref(),
            &settings,
            &RenderProgress::new(),
        );
        let mean = out.layers.composite().mean();
        rows.push(RenderRow {
            method: out.stats.method,
            seconds: out.stats.elapsed.as_secs_f64(),
            mrays_per_s: out.stats.rays_per_second() / 1e6,
            mean: f64::from(mean.element_sum()) / 3.0,
            non_finite: out.stats.non_finite,
            peak_memory_mib: mib(peak_memory()),
        });
        bar.inc(1);
    }
    // New views: the camera turned about the vertical through its target, 1 spp each.
    let interactive = radiosity_only(&scene, &solution);
    let one = render_settings(1, ctx.seed);
    let target = camera.position
        + camera.forward * (scene.bounds.center() - camera.position).dot(camera.forward);
    let t = Instant::now();
    for f in 0..args.frames {
        let angle = (f as f32 / args.frames as f32 - 0.5) * 0.4;
        let offset = glam::Quat::from_axis_angle(camera.up, angle) * (camera.position - target);
        let view = twopass_scene::Camera::look_at(
            target + offset,
            target,
            camera.up,
            camera.fov_y,
            camera.width,
            camera.height,
        )
        .map_err(|p| CliError::Input(format!("bench view {f}: {p}")))?;
        std::hint::black_box(twopass_trace::render(
            &scene,
            &view,
            &interactive,
            &one,
            &RenderProgress::new(),
        ));
    }
    let frames_per_second = f64::from(args.frames) / t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let report = RenderReport {
        scene: args.scene.display().to_string(),
        width: camera.width,
        height: camera.height,
        spp: args.spp,
        threads: rayon::current_num_threads(),
        radiosity_source: source,
        radiosity_seconds,
        rows,
        frames: args.frames,
        frames_per_second,
    };
    crate::output::report(&report, ctx, || {
        outln!(
            "scene {}: {} x {}, {} spp, {} threads; radiosity from {} in {:.2} s",
            report.scene,
            report.width,
            report.height,
            report.spp,
            report.threads,
            report.radiosity_source,
            report.radiosity_seconds
        );
        outln!(
            "{:<14} {:>9} {:>9} {:>10} {:>10} {:>9}",
            "method",
            "seconds",
            "Mrays/s",
            "mean",
            "non-finite",
            "peak MiB"
        );
        for r in &report.rows {
            outln!(
                "{:<14} {:>9.3} {:>9.2} {:>10.4} {:>10} {:>9}",
                r.method,
                r.seconds,
                r.mrays_per_s,
                r.mean,
                r.non_finite,
                fmt_mib(r.peak_memory_mib)
            );
        }
        outln!(
            "new views from the radiosity solution (radiosity alone, 1 spp): {:.1} frames per second over {} frames",
            report.frames_per_second,
            report.frames
        );
        Ok(())
    })
}
