//! The command: loads the scene, gets the converged reference, measures the sweep, marks the
//! fronts, derives the presets and writes the CSV, JSON, plot and presets file.

use std::path::PathBuf;

use super::args::{PRESET_NAMES, TradeoffArgs};
use super::front::{derive_presets, mark_fronts, reach_table};
use super::measure::{extend_path_tracer, measure_runs, solve_all};
use super::report::{ReferenceInfo, TradeoffReport, print_report};
use super::sweep::{Sweep, plan_runs};
use super::{plot, reference};
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, load_lit, methods};
use crate::preset::PresetFile;

/// Runs the sweep and writes the CSV, JSON, plot and presets.
pub fn run(args: &TradeoffArgs, ctx: &Context) -> Result<(), CliError> {
    if args.targets.len() != PRESET_NAMES.len() {
        return Err(CliError::Usage(format!(
            "--targets: {} values given; one per preset ({}) is needed",
            args.targets.len(),
            PRESET_NAMES.join(", ")
        )));
    }
    let scene = load_lit(&args.scene, ctx)?;
    let mut sweep = if args.quick {
        Sweep::quick()
    } else {
        Sweep::full()
    };
    if let Some(spp) = args.reference_spp {
        sweep.reference_spp = spp;
    }
    let camera = match (ctx.width, ctx.height) {
        (None, None) => crate::context::resized(&scene.camera, Some(sweep.width), None)?,
        (w, h) => crate::context::resized(&scene.camera, w, h)?,
    };
    let (chosen, skipped) = chosen_methods(args, &scene)?;
    let dir = ctx
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("tradeoff"));
    crate::output::create_dir(&dir)?;
    let cache = args.cache.clone().unwrap_or_else(|| dir.join("cache"));
    let stem = args
        .scene
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());

    let key = reference::key(
        &scene,
        &args.scene,
        camera.width,
        camera.height,
        sweep.reference_spp,
        ctx.seed,
    );
    let converged = reference::converged(&scene, &camera, &cache, key, ctx)?;
    if ctx.chatty() {
        errln!(
            "reference: {} spp, {} ({:.1} s), its own noise {:.2} % relative RMSE",
            sweep.reference_spp,
            if converged.cached {
                format!("from {}", converged.exr.display())
            } else {
                format!("rendered, cached as {}", converged.exr.display())
            },
            converged.render_seconds,
            100.0 * converged.noise_rel_rmse
        );
    }

    let (solves, runs) = plan_runs(&sweep, scene.bounds.diagonal(), &chosen);
    let bar = ctx.progress((solves.len() + runs.len()) as u64, "tradeoff");
    let solved = solve_all(&scene, &solves, args, ctx, &bar)?;

    let mut runs = runs;
    let mut rows = measure_runs(
        &scene,
        &camera,
        &runs,
        (&solves, &solved),
        &converged,
        ctx,
        &bar,
    )?;
    extend_path_tracer(
        &scene,
        &camera,
        (&mut runs, &mut rows),
        (&sweep, &args.targets),
        &converged,
        ctx,
        &bar,
    )?;
    bar.finish_and_clear();

    mark_fronts(&mut rows);
    let presets = derive_presets(&rows, &runs, &solves, &args.targets);
    let reach = reach_table(&rows, &chosen, &args.targets);

    let csv_path = dir.join(format!("{stem}-tradeoff.csv"));
    let plot_path = dir.join(format!("{stem}-tradeoff.png"));
    let presets_path = dir.join(format!("{stem}.presets.toml"));
    let measured_by = format!(
        "twopass bench tradeoff {}{}{}",
        args.scene.display(),
        if args.quick { " --quick" } else { "" },
        args.reference_spp
            .map_or_else(String::new, |s| format!(" --reference-spp {s}"))
    );
    let preset_file = PresetFile {
        measured_by,
        width: camera.width,
        height: camera.height,
        threads: rayon::current_num_threads(),
        presets: presets.clone(),
    };
    let report = TradeoffReport {
        scene: args.scene.clone(),
        width: camera.width,
        height: camera.height,
        threads: rayon::current_num_threads(),
        seed: ctx.seed,
        reference: ReferenceInfo {
            exr: converged.exr.clone(),
            settings: converged.key.clone(),
            render_seconds: converged.render_seconds,
            cached: converged.cached,
            noise_rel_rmse: converged.noise_rel_rmse,
        },
        skipped,
        rows,
        reach,
        presets,
        csv: csv_path.clone(),
        plot: plot_path.clone(),
        presets_file: presets_path.clone(),
    };
    crate::output::write_csv(&csv_path, &report.rows)?;
    plot::plot(
        &plot_path,
        &format!(
            "{}: {} x {}, {} threads",
            args.scene.display(),
            camera.width,
            camera.height,
            report.threads
        ),
        &report.rows,
        &report.presets,
        converged.noise_rel_rmse,
    )?;
    let toml = preset_file.to_toml();
    crate::output::write_atomic(&presets_path, toml.as_bytes())?;
    if args.install_presets {
        crate::output::write_atomic(&PresetFile::beside(&args.scene), toml.as_bytes())?;
    }
    let json = dir.join(format!("{stem}-tradeoff.json"));
    crate::output::finish_report(&json, &report, ctx, print_report)
}

/// The methods to sweep: those of `--methods` (in order, once each), or every method the scene
/// calls for; and what the scene skips and why. A radiosity-based method the scene does not
/// call for is refused.
fn chosen_methods(
    args: &TradeoffArgs,
    scene: &twopass_scene::Scene,
) -> Result<(Vec<RenderMethod>, Vec<String>), CliError> {
    let (called_for, skipped) = methods(scene);
    let chosen: Vec<RenderMethod> = if args.methods.is_empty() {
        called_for
    } else {
        let mut m: Vec<RenderMethod> = Vec::new();
        for &method in &args.methods {
            if !m.contains(&method) {
                m.push(method);
            }
        }
        if let Some(bad) = m
            .iter()
            .find(|m| m.needs_radiosity() && !called_for.contains(m))
        {
            return Err(CliError::Input(format!(
                "{}: --methods {}: the scene does not call for it ({})",
                args.scene.display(),
                bad.name(),
                skipped.join("; ")
            )));
        }
        m
    };
    Ok((chosen, skipped))
}
