//! Measuring the sweep: every radiosity solve once, every run rendered and compared with the
//! converged reference, and the path tracer extended until it reaches the smallest target.

use std::time::Instant;

use twopass_composite::metric::{Metrics, compare};
use twopass_composite::tonemap::ToneMap;
use twopass_radiosity::{Solution, Solver};
use twopass_trace::RenderStats;

use super::args::TradeoffArgs;
use super::reference;
use super::report::SweepRow;
use super::sweep::{RunSpec, SolveSpec, Sweep};
use crate::bench::memory::{mib, peak_memory, reset_peak_memory};
use crate::context::Context;
use crate::error::CliError;
use crate::pipeline::{RenderMethod, integrator};
use crate::preset::RenderKnobs;

/// The method name of radiosity alone over a gathered element mesh, in the rows and the plot.
pub(super) const GATHERED_RADIOSITY: &str = "radiosity-gathered";

/// A finished solve (its final gather included, when it has one).
pub(super) struct Solved {
    pub(super) solution: Solution,
    pub(super) seconds: f64,
    pub(super) elements: usize,
    pub(super) rays: u64,
    pub(super) unshot_fraction: f64,
    pub(super) peak_bytes: Option<u64>,
}

/// Runs every radiosity solve of the sweep once (each serves several runs), measuring its time
/// and peak memory.
pub(super) fn solve_all(
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
        let mut solution = solver.solution();
        let mut rays = p.rays;
        if let Some(n) = spec.gather {
            // As `twopass bake --gather N` gathers its element mesh.
            let settings = crate::final_gather::Gather::Rays(n)
                .settings(ctx.seed)
                .expect("a ray count gathers");
            let gatherer = twopass_trace::gather::Gatherer::new(scene, &solution, settings);
            let (gathered, record) =
                crate::final_gather::gather_elements(&solution, scene, &gatherer.fixed(n), n);
            rays += record.rays + record.shadow_rays;
            solution = gathered;
        }
        solved.push(Solved {
            solution,
            seconds: started.elapsed().as_secs_f64(),
            elements: p.elements,
            rays,
            unshot_fraction: p.unshot_fraction,
            peak_bytes: peak_memory(),
        });
        bar.inc(1);
    }
    Ok(solved)
}

/// Renders every run of the sweep and measures its time, rays, peak memory and error against
/// the converged reference (compared through the reference's display tone map).
pub(super) fn measure_runs(
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
            twopass_trace::ReferenceSettings::default(),
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
pub(super) fn extend_path_tracer(
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

/// The CSV row of a measured run (its solve's figures included); not yet on any front.
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
    let gather = solve.and_then(|s| s.0.gather);
    SweepRow {
        // A gathered solve is radiosity with a bake's final gather: a curve of its own.
        method: match gather {
            Some(_) => GATHERED_RADIOSITY,
            None => run.method.name(),
        },
        final_gather: gather,
        knob: run.knob,
        spp: run.render.spp,
        adaptive_aa: run.render.adaptive,
        depth: run.render.depth,
        shadow_grid: run.render.shadow_grid,
        gather_rays: run.render.gather_rays,
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
