//! `twopass bench tradeoff SCENE`: the speed/accuracy trade of every method, measured.
//!
//! Sweeps each method's knobs one at a time around a base setting (and anti-aliasing against
//! shadow rays as a grid, since they trade against each other), renders every setting,
//! and measures its time (radiosity solve included) and its error against a converged
//! reference: the reference path tracer run long, cached on disk ([`mod@reference`]).
//!
//! - radiosity: element size, unshot fraction, visibility rays, adaptive subdivision on/off,
//!   each solve rendered as radiosity alone and by the hybrids, and element size crossed with
//!   samples per pixel (the two knobs that dominate their error), each element size at the
//!   base and at one shadow ray a pair, stopping at unshot 1e-3 and at 1e-2;
//! - Whitted and the hybrids: samples per pixel x shadow-ray grid, and recursion depth;
//! - the reference path tracer: samples per pixel.
//!
//! Writes, in `--output DIR` (default `tradeoff/`): `<stem>-tradeoff.csv` (one row per run:
//! method, settings, time per phase, rays, peak memory, error metrics, Pareto membership),
//! `<stem>-tradeoff.json` (the same plus the reference, the presets and the time each method
//! takes to reach each target), `<stem>-tradeoff.png` (error against time, log-log, one curve
//! per method, the Pareto front marked) and `<stem>.presets.toml` (the presets derived from the
//! front: the cheapest measured setting reaching each target error).

pub mod front;
mod plot;
pub mod reference;
mod sweep;

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;
use twopass_composite::metric::{Metrics, compare};
use twopass_composite::tonemap::ToneMap;
use twopass_radiosity::{Solution, Solver};
use twopass_trace::RenderStats;

use crate::bench::memory::{mib, peak_memory, reset_peak_memory};
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, integrator, load_lit, methods};
use crate::preset::{Preset, PresetFile, RenderKnobs};
use sweep::{RunSpec, SolveSpec, Sweep, plan_runs};

/// Arguments of `twopass bench tradeoff`.
#[derive(Debug, Args)]
pub struct TradeoffArgs {
    /// Scene file (.toml) or mesh (.obj).
    pub scene: PathBuf,
    /// A small sweep at 48 pixels wide for smoke tests (seconds, not minutes); its presets mean
    /// little.
    #[arg(long)]
    pub quick: bool,
    /// Samples per pixel of the converged reference [default: 8192; 256 with --quick].
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=10_000_000))]
    pub reference_spp: Option<u32>,
    /// Directory of the cached converged references [default: OUTPUT/cache].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Relative RMSE targets of the presets draft, preview and final, in that order, comma
    /// separated (`0.10,0.026,0.014`).
    #[arg(long, value_delimiter = ',', default_values_t = [0.10, 0.026, 0.014], value_parser = parse_target)]
    pub targets: Vec<f64>,
    /// Methods to sweep, comma separated [default: every method the scene calls for].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Vec<RenderMethod>,
    /// Also write the presets beside the scene (`<stem>.presets.toml`), where `--preset`
    /// looks for them.
    #[arg(long)]
    pub install_presets: bool,
}

fn parse_target(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|e| format!("`{s}`: {e}"))?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(format!(
            "{x}: a target relative RMSE must be finite and > 0"
        ))
    }
}

/// Names of the presets, in the order of `--targets`.
const PRESET_NAMES: [&str; 3] = ["draft", "preview", "final"];

/// A finished solve.
struct Solved {
    solution: Solution,
    seconds: f64,
    elements: usize,
    rays: u64,
    unshot_fraction: f64,
    peak_bytes: Option<u64>,
}

/// One measured run: a CSV row.
#[derive(Debug, Clone, Serialize)]
struct SweepRow {
    method: &'static str,
    /// The knob this run varies from the base setting.
    knob: &'static str,
    spp: u32,
    /// First-pass samples per pixel of adaptive anti-aliasing (empty: `spp` everywhere).
    adaptive_aa: Option<u32>,
    depth: u32,
    shadow_grid: u32,
    /// Radiosity settings (empty for Whitted and the path tracer).
    element_size: Option<f32>,
    unshot: Option<f64>,
    visibility_min: Option<u32>,
    visibility_max: Option<u32>,
    adaptive: Option<bool>,
    elements: Option<usize>,
    /// Unshot fraction the solve reached.
    unshot_reached: Option<f64>,
    /// Wall-clock seconds of the radiosity solve (0 without one).
    radiosity_seconds: f64,
    render_seconds: f64,
    /// Solve plus render, seconds.
    total_seconds: f64,
    /// Shadow rays of the solve.
    radiosity_rays: u64,
    /// Camera and secondary rays of the render.
    rays: u64,
    shadow_rays: u64,
    /// Largest resident memory of the solve and the render, MiB.
    peak_memory_mib: Option<f64>,
    mae: f64,
    rmse: f64,
    rel_rmse: f64,
    ssim: f64,
    /// On the Pareto front of all runs.
    pareto: bool,
    /// On the Pareto front of its own method.
    method_pareto: bool,
}

/// Time each method takes to reach a target error.
#[derive(Debug, Serialize)]
struct Reach {
    method: &'static str,
    target_rel_rmse: f64,
    /// Seconds, interpolated on log-log axes along the method's front; `None`: not reached.
    seconds: Option<f64>,
    /// `false` when even the cheapest run was below the target (the time is an upper bound).
    interpolated: bool,
    /// `seconds` over the reference path tracer's, when both reached it.
    ratio_to_path_tracer: Option<f64>,
}

#[derive(Debug, Serialize)]
struct ReferenceInfo {
    exr: PathBuf,
    settings: reference::ReferenceKey,
    render_seconds: f64,
    cached: bool,
    noise_rel_rmse: f64,
}

#[derive(Debug, Serialize)]
struct TradeoffReport {
    scene: PathBuf,
    width: u32,
    height: u32,
    threads: usize,
    seed: u64,
    reference: ReferenceInfo,
    skipped: Vec<String>,
    rows: Vec<SweepRow>,
    reach: Vec<Reach>,
    presets: Vec<Preset>,
    csv: PathBuf,
    plot: PathBuf,
    presets_file: PathBuf,
}

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

/// Runs every radiosity solve of the sweep once (each serves several runs), measuring its time
/// and peak memory.
fn solve_all(
    scene: &twopass_scene::Scene,
    solves: &[SolveSpec],
    args: &TradeoffArgs,
    ctx: &Context,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<Solved>, CliError> {
    let mut solved: Vec<Solved> = Vec::with_capacity(solves.len());
    for spec in solves {
        bar.set_message(format!("solve {}", spec.knob));
        reset_peak_memory();
        let started = Instant::now();
        let mut solver =
            Solver::new(scene, spec.knobs.solve_args().options(ctx.seed)).map_err(|source| {
                CliError::Solve {
                    path: args.scene.clone(),
                    source,
                }
            })?;
        solver.run(|_| std::ops::ControlFlow::Continue(()));
        let p = solver.progress();
        solved.push(Solved {
            solution: solver.solution(),
            seconds: started.elapsed().as_secs_f64(),
            elements: p.elements,
            rays: p.rays,
            unshot_fraction: p.unshot_fraction,
            peak_bytes: peak_memory(),
        });
        bar.inc(1);
    }
    Ok(solved)
}

/// Renders every run of the sweep and measures its time, rays, peak memory and error against
/// the converged reference (compared through the reference's display tone map).
fn measure_runs(
    scene: &twopass_scene::Scene,
    camera: &twopass_scene::Camera,
    runs: &[RunSpec],
    (solves, solved): (&[SolveSpec], &[Solved]),
    converged: &reference::Converged,
    ctx: &Context,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<SweepRow>, CliError> {
    let display = ToneMap::auto_default(&converged.image)?;
    let mut rows = Vec::with_capacity(runs.len());
    for run in runs {
        let solve = run.solve.map(|i| (&solves[i], &solved[i]));
        let integ = integrator(
            run.method,
            scene,
            solve.map(|s| &s.1.solution as &dyn twopass_scene::DiffuseRadiance),
            run.render.whitted(),
        );
        let settings = run.render.settings(ctx.seed);
        reset_peak_memory();
        bar.set_message(run.method.name());
        // One bar for the whole sweep: a second bar per render would fight it for the line.
        let out = twopass_trace::render(
            scene,
            camera,
            integ.as_ref(),
            &settings,
            &twopass_trace::RenderProgress::new(),
        );
        let render_peak = peak_memory();
        let image = out.layers.composite();
        image.check_finite(run.method.name())?;
        let metrics = compare(&image, &converged.image, &display)?;
        rows.push(row(run, solve, &out.stats, &metrics, render_peak));
        bar.inc(1);
    }
    Ok(rows)
}

/// Renders the path tracer past the sweep's last setting until it reaches the smallest
/// target, so that its time to reach every target is a measured crossing rather than a bound.
/// Each further run takes the samples per pixel the last one predicts, with 15 % to spare:
/// measured error^2 = reference noise^2 + c / spp (the reference's own noise is in every
/// measured error; the path tracer's falls as 1 / spp), at most the reference's. Stops when a
/// target at or below the reference's noise could not be reached at all. Nothing when the
/// path tracer is not swept.
fn extend_path_tracer(
    scene: &twopass_scene::Scene,
    camera: &twopass_scene::Camera,
    (runs, rows): (&mut Vec<RunSpec>, &mut Vec<SweepRow>),
    (sweep, targets): (&Sweep, &[f64]),
    converged: &reference::Converged,
    ctx: &Context,
    bar: &indicatif::ProgressBar,
) -> Result<(), CliError> {
    let smallest = targets.iter().copied().fold(f64::INFINITY, f64::min);
    loop {
        let path_tracer = || {
            runs.iter()
                .zip(rows.iter())
                .filter(|(r, _)| r.method == RenderMethod::Reference)
        };
        if path_tracer().any(|(_, row)| row.rel_rmse <= smallest) {
            return Ok(());
        }
        let Some((last, error)) = path_tracer()
            .max_by_key(|(r, _)| r.render.spp)
            .map(|(r, row)| (r.render, row.rel_rmse))
        else {
            return Ok(());
        };
        let Some(spp) = next_path_tracer_spp(
            (last.spp, error),
            converged.noise_rel_rmse,
            smallest,
            sweep.reference_spp,
        ) else {
            return Ok(());
        };
        let run = RunSpec {
            method: RenderMethod::Reference,
            knob: "spp-extended",
            render: RenderKnobs { spp, ..last },
            solve: None,
        };
        bar.inc_length(1);
        let row = measure_runs(
            scene,
            camera,
            std::slice::from_ref(&run),
            (&[], &[]),
            converged,
            ctx,
            bar,
        )?;
        rows.extend(row);
        runs.push(run);
    }
}

/// The path tracer's samples per pixel predicted to reach `target` relative RMSE from its last
/// run (`spp`, measured `error`) against a reference with noise `noise` (see
/// [`extend_path_tracer`]); `None` when it cannot be reached, or not within `max` samples.
fn next_path_tracer_spp(
    (spp, error): (u32, f64),
    noise: f64,
    target: f64,
    max: u32,
) -> Option<u32> {
    let own = error * error - noise * noise;
    let wanted = target * target - noise * noise;
    if own <= 0.0 || wanted <= 0.0 || spp >= max {
        return None;
    }
    let predicted = f64::from(spp) * own / wanted * 1.15;
    Some(predicted.ceil().min(f64::from(max)) as u32)
}

fn row(
    run: &RunSpec,
    solve: Option<(&SolveSpec, &Solved)>,
    stats: &RenderStats,
    m: &Metrics,
    render_peak: Option<u64>,
) -> SweepRow {
    let k = solve.map(|s| s.0.knobs);
    let s = solve.map(|s| s.1);
    let radiosity_seconds = s.map_or(0.0, |s| s.seconds);
    let render_seconds = stats.elapsed.as_secs_f64();
    let peak = match (render_peak, s.and_then(|s| s.peak_bytes)) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    };
    SweepRow {
        method: run.method.name(),
        knob: run.knob,
        spp: run.render.spp,
        adaptive_aa: run.render.adaptive,
        depth: run.render.depth,
        shadow_grid: run.render.shadow_grid,
        element_size: k.map(|k| k.element_size),
        unshot: k.map(|k| k.unshot),
        visibility_min: k.map(|k| k.visibility_min),
        visibility_max: k.map(|k| k.visibility_max),
        adaptive: k.map(|k| k.adaptive),
        elements: s.map(|s| s.elements),
        unshot_reached: s.map(|s| s.unshot_fraction),
        radiosity_seconds,
        render_seconds,
        total_seconds: radiosity_seconds + render_seconds,
        radiosity_rays: s.map_or(0, |s| s.rays),
        rays: stats.rays,
        shadow_rays: stats.shadow_rays,
        peak_memory_mib: mib(peak),
        mae: m.mae,
        rmse: m.rmse,
        rel_rmse: m.rel_rmse,
        ssim: m.ssim,
        pareto: false,
        method_pareto: false,
    }
}

fn points(rows: &[SweepRow]) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (r.total_seconds, r.rel_rmse)).collect()
}

/// Marks the global front and each method's own front.
fn mark_fronts(rows: &mut [SweepRow]) {
    for i in front::pareto_front(&points(rows)) {
        rows[i].pareto = true;
    }
    let names: Vec<&'static str> = rows.iter().map(|r| r.method).collect();
    for name in names
        .iter()
        .copied()
        .collect::<std::collections::BTreeSet<_>>()
    {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| names[i] == name).collect();
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (rows[i].total_seconds, rows[i].rel_rmse))
            .collect();
        for j in front::pareto_front(&pts) {
            rows[idx[j]].method_pareto = true;
        }
    }
}

/// The presets: for each target, the cheapest run reaching it.
fn derive_presets(
    rows: &[SweepRow],
    runs: &[RunSpec],
    solves: &[SolveSpec],
    targets: &[f64],
) -> Vec<Preset> {
    let pts = points(rows);
    PRESET_NAMES
        .iter()
        .zip(targets)
        .filter_map(|(name, &target)| {
            let (i, reached) = front::cheapest_reaching(&pts, target)?;
            Some(Preset {
                name: (*name).to_owned(),
                target_rel_rmse: target,
                reached,
                measured_rel_rmse: rows[i].rel_rmse,
                measured_seconds: rows[i].total_seconds,
                method: runs[i].method,
                render: runs[i].render,
                radiosity: runs[i].solve.map(|s| solves[s].knobs),
            })
        })
        .collect()
}

/// Time to reach each target, per method, with the ratio to the path tracer's.
fn reach_table(rows: &[SweepRow], methods: &[RenderMethod], targets: &[f64]) -> Vec<Reach> {
    let curve = |name: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.method == name)
            .map(|r| (r.total_seconds, r.rel_rmse))
            .collect()
    };
    let mut out = Vec::new();
    for &target in targets {
        let pt = front::time_to_reach(&curve(RenderMethod::Reference.name()), target);
        for m in methods {
            let reached = front::time_to_reach(&curve(m.name()), target);
            out.push(Reach {
                method: m.name(),
                target_rel_rmse: target,
                seconds: reached.map(|r| r.0),
                interpolated: reached.is_some_and(|r| r.1),
                ratio_to_path_tracer: match (reached, pt) {
                    (Some(a), Some(b)) => Some(a.0 / b.0),
                    _ => None,
                },
            });
        }
    }
    out
}

fn print_report(r: &TradeoffReport) -> Result<(), CliError> {
    for s in &r.skipped {
        outln!("skipped {s}");
    }
    outln!(
        "{}: {} x {}, {} threads; reference {} spp ({:.1} s{}), its noise {:.2} %",
        r.scene.display(),
        r.width,
        r.height,
        r.threads,
        r.reference.settings.spp,
        r.reference.render_seconds,
        if r.reference.cached { ", cached" } else { "" },
        100.0 * r.reference.noise_rel_rmse
    );
    outln!(
        "{:<14} {:<16} {:>5} {:>4} {:>4} {:>9} {:>8} {:>8} {:>9} {:>9} {:>9} {:>7}",
        "method",
        "knob",
        "spp",
        "grid",
        "dep",
        "elem size",
        "elements",
        "unshot",
        "solve s",
        "total s",
        "rel RMSE",
        "peak MiB"
    );
    for row in &r.rows {
        let opt = |x: Option<String>| x.unwrap_or_else(|| "-".to_owned());
        outln!(
            "{:<14} {:<16} {:>5} {:>4} {:>4} {:>9} {:>8} {:>8} {:>9.3} {:>9.3} {:>8.2}%{} {:>7}",
            row.method,
            row.knob,
            row.spp,
            row.shadow_grid,
            row.depth,
            opt(row.element_size.map(|e| format!("{e:.1}"))),
            opt(row.elements.map(|e| e.to_string())),
            opt(row.unshot.map(|u| format!("{u:.0e}"))),
            row.radiosity_seconds,
            row.total_seconds,
            100.0 * row.rel_rmse,
            if row.pareto { "*" } else { " " },
            opt(row.peak_memory_mib.map(|m| format!("{m:.0}"))),
        );
    }
    outln!("* on the Pareto front of all methods");
    for reach in &r.reach {
        outln!(
            "{:<14} reaches {:>5.2} % in {}{}",
            reach.method,
            100.0 * reach.target_rel_rmse,
            reach.seconds.map_or_else(
                || "(not reached)".to_owned(),
                |s| format!("{}{s:.3} s", if reach.interpolated { "" } else { "<= " })
            ),
            reach
                .ratio_to_path_tracer
                .map_or_else(String::new, |x| format!(
                    ", {x:.3} x the path tracer's time"
                ))
        );
    }
    for p in &r.presets {
        outln!(
            "preset {:<8} target {:>5.2} %{}: {} at {} spp{}, grid {}, depth {}{} -> {:.2} % in {:.3} s",
            p.name,
            100.0 * p.target_rel_rmse,
            if p.reached { "" } else { " (not reached)" },
            p.method.name(),
            p.render.spp,
            p.render
                .adaptive
                .map_or_else(String::new, |b| format!(" (adaptive from {b})")),
            p.render.shadow_grid,
            p.render.depth,
            p.radiosity.map_or_else(String::new, |k| format!(
                ", elements {:.1}, unshot {:.0e}, visibility {}-{}, adaptive {}",
                k.element_size, k.unshot, k.visibility_min, k.visibility_max, k.adaptive
            )),
            100.0 * p.measured_rel_rmse,
            p.measured_seconds
        );
    }
    outln!(
        "wrote {}, {}, {} and the JSON beside them",
        r.csv.display(),
        r.plot.display(),
        r.presets_file.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::next_path_tracer_spp;

    #[test]
    fn the_next_path_tracer_run_is_the_one_its_last_predicts() {
        // error^2 = 0.005^2 + 0.1 / spp: 1.118 % at 1000 spp; 1 % needs 1333.3 spp, and 15 %
        // more is 1533.3.
        let noise = 0.005_f64;
        let error = (noise * noise + 0.1 / 1000.0).sqrt();
        assert_eq!(
            next_path_tracer_spp((1000, error), noise, 0.01, 8192),
            Some(1534)
        );
        assert_eq!(
            next_path_tracer_spp((1000, error), noise, 0.01, 1200),
            Some(1200)
        );
        // At the cap, or a target under the reference's own noise: no further run.
        assert_eq!(next_path_tracer_spp((1200, error), noise, 0.01, 1200), None);
        assert_eq!(
            next_path_tracer_spp((1000, error), noise, 0.004, 8192),
            None
        );
    }
}
