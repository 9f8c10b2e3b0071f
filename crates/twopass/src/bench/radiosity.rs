//! `twopass bench radiosity`: progressive solves at several element counts (time, shots, rays,
//! peak memory, error against the dense solve), or solves of generated scenes of growing size
//! with their growth exponents and a log-log plot.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;
use twopass_scene::workload;

use super::memory::{fmt_mib, mib, peak_memory, reset_peak_memory};
use crate::args::checked;
use crate::context::Context;
use crate::error::CliError;
use crate::solve::SolveArgs;

/// Arguments of `twopass bench radiosity`.
#[derive(Debug, Args)]
pub struct RadiosityArgs {
    /// Scene file (.toml or .obj); omit it with `--generate`.
    #[arg(required_unless_present = "generate")]
    pub scene: Option<PathBuf>,
    /// Instead of a file, generate scenes of about these many triangles (the Cornell room
    /// filled with icospheres, as `bench rays --generate`) and solve each.
    #[arg(
        long,
        value_delimiter = ',',
        conflicts_with = "scene",
        value_parser = clap::value_parser!(u64).range(1..=20_000_000)
    )]
    pub generate: Vec<u64>,
    /// The solver of the `--generate` runs.
    #[arg(long, value_enum, default_value = "hierarchical")]
    pub solver: crate::solve::SolverChoice,
    /// With `--generate`: also draw time and peak memory against the triangle count on
    /// log-log axes into this PNG.
    #[arg(long, value_name = "FILE", requires = "generate")]
    pub plot: Option<PathBuf>,
    /// Element counts to aim at (the mesh reaches about these by bisection).
    #[arg(long, value_delimiter = ',', default_values_t = [1000u32, 10_000, 50_000, 200_000], value_parser = clap::value_parser!(u32).range(1..=twopass_radiosity::MAX_ELEMENTS as i64))]
    pub elements: Vec<u32>,
    /// Unshot fraction to solve to.
    #[arg(long, default_value_t = 1e-3, value_parser = crate::solve::parse_fraction)]
    pub unshot: f64,
    /// Compare with the dense solve when the mesh has at most this many vertices (its cost
    /// grows as the cube; at most 20000, where its matrix holds 3.2 GB).
    #[arg(long, default_value_t = 3000, value_parser = parse_dense_max)]
    pub dense_max_vertices: usize,
}

/// One measured radiosity solve.
#[derive(Debug, Serialize)]
struct SolveRow {
    target_elements: u32,
    element_size: f32,
    patches: usize,
    elements: usize,
    vertices: usize,
    shots: u64,
    rays: u64,
    seconds: f64,
    /// Shadow rays per second over the whole solve.
    mrays_per_s: f64,
    /// Seconds per element per shot, nanoseconds: flat when the solve grows as elements x
    /// shooters.
    ns_per_element_shot: f64,
    /// log(time ratio) / log(element ratio) against the previous row: 1 is linear growth.
    growth_exponent: Option<f64>,
    unshot_fraction: f64,
    peak_memory_mib: Option<f64>,
    /// Relative RMS difference of the vertex radiosities to the dense solve, when it fits.
    dense_relative_rms: Option<f64>,
    dense_seconds: Option<f64>,
}

/// One measured solve of a generated scene.
#[derive(Debug, Serialize)]
struct ScaleRow {
    /// Triangles asked for and made.
    requested: u64,
    triangles: usize,
    solver: &'static str,
    /// Why the solve stopped.
    finish: String,
    elements: usize,
    vertices: usize,
    links: usize,
    clusters: usize,
    shots: u64,
    iterations: u64,
    rays: u64,
    /// Scene generation and loading, seconds.
    load_seconds: f64,
    /// The whole solve, seconds (meshing and link refinement included).
    seconds: f64,
    refining_seconds: f64,
    /// The convergence measure at the end: residual power / emitted power.
    residual: f64,
    energy_imbalance: f64,
    peak_memory_mib: Option<f64>,
    /// log(time ratio) / log(triangle ratio) against the previous row.
    time_growth: Option<f64>,
    /// The same for peak memory.
    memory_growth: Option<f64>,
}

/// Solves generated scenes of growing size (`--generate`).
fn radiosity_scale(args: &RadiosityArgs, ctx: &Context) -> Result<(), CliError> {
    use twopass_radiosity::Solver;
    let progress = ctx.progress(args.generate.len() as u64, "bench radiosity");
    let mut rows: Vec<ScaleRow> = Vec::new();
    for &n in &args.generate {
        reset_peak_memory();
        let started = Instant::now();
        let (scene, _) = workload::synthetic_scene(n as usize, ctx.seed)?;
        let load_seconds = started.elapsed().as_secs_f64();
        let options = SolveArgs {
            solver: args.solver,
            unshot: args.unshot,
            ..SolveArgs::default()
        }
        .options(ctx.seed);
        let start = Instant::now();
        let mut solver = Solver::new(&scene, options).map_err(|source| CliError::Solve {
            path: PathBuf::from(format!("generated-{n}")),
            source,
        })?;
        let finish = solver.run(|_| std::ops::ControlFlow::Continue(()));
        let seconds = start.elapsed().as_secs_f64();
        let p = solver.progress();
        let peak = mib(peak_memory());
        let growth = |now: f64, before: f64, prev: &ScaleRow| {
            (now / before).ln() / (scene.mesh.triangle_count() as f64 / prev.triangles as f64).ln()
        };
        let time_growth = rows.last().map(|r| growth(seconds, r.seconds, r));
        let memory_growth = rows
            .last()
            .and_then(|r| Some(growth(peak?, r.peak_memory_mib?, r)));
        rows.push(ScaleRow {
            requested: n,
            triangles: scene.mesh.triangle_count(),
            solver: p.method.name(),
            finish: format!("{finish:?}"),
            elements: p.elements,
            vertices: p.vertices,
            links: p.links,
            clusters: p.clusters,
            shots: p.shots,
            iterations: p.iterations,
            rays: p.rays,
            load_seconds,
            seconds,
            refining_seconds: p.refining.as_secs_f64(),
            residual: p.unshot_fraction,
            energy_imbalance: p.worst_imbalance,
            peak_memory_mib: peak,
            time_growth,
            memory_growth,
        });
        progress.inc(1);
    }
    progress.finish_and_clear();
    if let Some(path) = &args.plot {
        plot_scale(path, &rows)?;
    }
    crate::output::report(&rows, ctx, || {
        outln!(
            "generated scenes: solve to residual {:.0e}, {} threads",
            args.unshot,
            rayon::current_num_threads()
        );
        outln!(
            "{:>9} {:>12} {:>9} {:>9} {:>10} {:>6} {:>10} {:>8} {:>8} {:>9} {:>9} {:>6} {:>6}",
            "triangles",
            "solver",
            "elements",
            "vertices",
            "links",
            "iters",
            "rays",
            "seconds",
            "refining",
            "residual",
            "peak MiB",
            "t-grow",
            "m-grow"
        );
        let g = |x: Option<f64>| x.map_or_else(|| "-".to_owned(), |g| format!("{g:.2}"));
        for r in &rows {
            outln!(
                "{:>9} {:>12} {:>9} {:>9} {:>10} {:>6} {:>10} {:>8.2} {:>8.2} {:>9.1e} {:>9} {:>6} {:>6}",
                r.triangles,
                r.solver,
                r.elements,
                r.vertices,
                r.links,
                r.iterations.max(r.shots),
                r.rays,
                r.seconds,
                r.refining_seconds,
                r.residual,
                fmt_mib(r.peak_memory_mib),
                g(r.time_growth),
                g(r.memory_growth)
            );
        }
        Ok(())
    })
}

/// Time and peak memory of the scale runs against the triangle count, log-log, each with a
/// line of slope 1 (linear growth) through its first point.
fn plot_scale(path: &std::path::Path, rows: &[ScaleRow]) -> Result<(), CliError> {
    use plotters::prelude::*;
    /// A panel: its name, the y unit and the (triangles, value) points.
    type Panel<'a> = (&'a str, &'a str, Vec<(f64, f64)>);
    let series: [Panel; 2] = [
        (
            "solve time",
            "seconds",
            rows.iter()
                .map(|r| (r.triangles as f64, r.seconds))
                .collect(),
        ),
        (
            "peak memory",
            "MiB",
            rows.iter()
                .filter_map(|r| Some((r.triangles as f64, r.peak_memory_mib?)))
                .collect(),
        ),
    ];
    crate::figure::png(path, 1100, 460, |root| {
        let panels = root.split_evenly((1, 2));
        for (area, (name, unit, points)) in panels.iter().zip(&series) {
            let Some(&(n0, y0)) = points.first() else {
                continue;
            };
            let (nmax, ymax) = points
                .iter()
                .fold((n0, y0), |(a, b), &(n, y)| (a.max(n), b.max(y)));
            let ymin = points.iter().fold(y0, |a, &(_, y)| a.min(y));
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("hierarchical radiosity: {name}"),
                    (crate::figure::FONT, 20),
                )
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(60)
                .build_cartesian_2d(
                    (n0 / 1.5..nmax * 1.5).log_scale(),
                    (ymin / 2.0..ymax * 2.0).log_scale(),
                )
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc("triangles")
                .y_desc(*unit)
                .label_style((crate::figure::FONT, 13))
                .axis_desc_style((crate::figure::FONT, 15))
                .light_line_style(RGBColor(236, 236, 236))
                .draw()
                .map_err(|e| e.to_string())?;
            let grey = RGBColor(150, 150, 150);
            chart
                .draw_series(LineSeries::new(
                    [(n0, y0), (nmax, y0 * nmax / n0)],
                    grey.stroke_width(1),
                ))
                .map_err(|e| e.to_string())?
                .label("linear growth")
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], grey));
            let blue = RGBColor(31, 119, 180);
            chart
                .draw_series(LineSeries::new(points.clone(), blue.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label("measured")
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], blue));
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, blue.filled())))
                .map_err(|e| e.to_string())?;
            crate::figure::legend(&mut chart, SeriesLabelPosition::UpperLeft, 13)?;
        }
        Ok(())
    })
}

/// Solves the scene at each element count, or the generated scenes of `--generate`.
pub fn run(args: &RadiosityArgs, ctx: &Context) -> Result<(), CliError> {
    use twopass_radiosity::{ProgressiveSolver, dense_solve};
    let Some(path) = &args.scene else {
        return radiosity_scale(args, ctx);
    };
    let (scene, _) = ctx.load_scene(path)?;
    let progress = ctx.progress(args.elements.len() as u64, "bench radiosity");
    let mut rows = Vec::new();
    for &target in &args.elements {
        let solve = SolveArgs::element_count(&scene, target, args.unshot);
        let element_size = solve.element_size.unwrap_or_default();
        let options = solve.options(ctx.seed);
        reset_peak_memory();
        let start = Instant::now();
        let mut solver =
            ProgressiveSolver::new(&scene, options).map_err(|source| CliError::Solve {
                path: path.clone(),
                source,
            })?;
        solver.run(|_| std::ops::ControlFlow::Continue(()));
        let seconds = start.elapsed().as_secs_f64();
        let p = solver.progress();
        let peak = peak_memory();
        let (dense_relative_rms, dense_seconds) = if p.vertices <= args.dense_max_vertices {
            let t = Instant::now();
            match dense_solve(&mut solver) {
                Some(dense) => {
                    let prog = solver.vertex_radiosity();
                    let (mut num, mut den) = (0.0, 0.0);
                    for (a, b) in prog.iter().zip(&dense) {
                        num += (*a - *b).length_squared();
                        den += b.length_squared();
                    }
                    (Some((num / den).sqrt()), Some(t.elapsed().as_secs_f64()))
                }
                None => (None, None),
            }
        } else {
            (None, None)
        };
        rows.push(SolveRow {
            target_elements: target,
            element_size,
            patches: p.patches,
            elements: p.elements,
            vertices: p.vertices,
            shots: p.shots,
            rays: p.rays,
            seconds,
            mrays_per_s: p.rays as f64 / seconds / 1e6,
            ns_per_element_shot: seconds * 1e9 / (p.elements as f64 * p.shots.max(1) as f64),
            growth_exponent: rows.last().map(|prev: &SolveRow| {
                (seconds / prev.seconds).ln() / (p.elements as f64 / prev.elements as f64).ln()
            }),
            unshot_fraction: p.unshot_fraction,
            peak_memory_mib: mib(peak),
            dense_relative_rms,
            dense_seconds,
        });
        progress.inc(1);
    }
    progress.finish_and_clear();
    crate::output::report(&rows, ctx, || {
        outln!(
            "scene {}: progressive refinement to unshot {:.0e}, fixed mesh, {} threads",
            path.display(),
            args.unshot,
            rayon::current_num_threads()
        );
        outln!(
            "{:>8} {:>8} {:>8} {:>8} {:>7} {:>11} {:>8} {:>8} {:>8} {:>6} {:>9} {:>11}",
            "elements",
            "vertices",
            "patches",
            "size",
            "shots",
            "rays",
            "seconds",
            "Mrays/s",
            "ns/el/sh",
            "growth",
            "peak MiB",
            "dense rRMS"
        );
        for r in &rows {
            outln!(
                "{:>8} {:>8} {:>8} {:>8.1} {:>7} {:>11} {:>8.2} {:>8.2} {:>8.1} {:>6} {:>9} {:>11}",
                r.elements,
                r.vertices,
                r.patches,
                r.element_size,
                r.shots,
                r.rays,
                r.seconds,
                r.mrays_per_s,
                r.ns_per_element_shot,
                r.growth_exponent
                    .map_or_else(|| "-".to_owned(), |g| format!("{g:.2}")),
                fmt_mib(r.peak_memory_mib),
                r.dense_relative_rms
                    .map_or_else(|| "-".to_owned(), |e| format!("{e:.2e}"))
            );
        }
        Ok(())
    })
}

/// Most vertices of the dense comparison solve.
const MAX_DENSE_VERTICES: usize = 20_000;

fn parse_dense_max(s: &str) -> Result<usize, String> {
    let needs = format!("must be at most {MAX_DENSE_VERTICES}");
    checked(s, |n| *n <= MAX_DENSE_VERTICES, &needs)
}
