//! `twopass bench ...`: end-to-end measurements, reported with ratios taken within one run.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::{Args, Subcommand};
use rayon::prelude::*;
use serde::Serialize;
use twopass_scene::workload::{self, QueryKind};
use twopass_scene::{Accel, Ray, Scene, SurfacePoint};

use crate::context::Context;
use crate::error::CliError;

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Ray queries per second (camera, incoherent, occlusion) on one and on all threads, and
    /// the BVH build time.
    Rays(RaysArgs),
    /// Radiosity solves at several element counts (progressive refinement): time, shots,
    /// rays, peak memory, and the error against the dense solve where it fits; or, with
    /// `--generate`, solves of generated scenes of growing size (by default with the
    /// hierarchical solver): time, links, rays, peak memory and their growth exponents.
    Radiosity(RadiosityArgs),
    /// Render time and rays per second of every method, and frames per second of new views
    /// rendered from a bake file (radiosity alone).
    Render(RenderArgs),
    /// The speed/accuracy trade: sweeps every method's knobs, measures time and error against
    /// a cached converged reference, plots the Pareto front and derives the presets.
    Tradeoff(crate::tradeoff::TradeoffArgs),
}

/// Arguments of `twopass bench render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
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
    pub solver: crate::bake::SolverChoice,
    /// With `--generate`: also draw time and peak memory against the triangle count on
    /// log-log axes into this PNG.
    #[arg(long, value_name = "FILE", requires = "generate")]
    pub plot: Option<PathBuf>,
    /// Element counts to aim at (the mesh reaches about these by bisection).
    #[arg(long, value_delimiter = ',', default_values_t = [1000u32, 10_000, 50_000, 200_000], value_parser = clap::value_parser!(u32).range(1..=twopass_radiosity::MAX_ELEMENTS as i64))]
    pub elements: Vec<u32>,
    /// Unshot fraction to solve to.
    #[arg(long, default_value_t = 1e-3, value_parser = crate::bake::parse_fraction)]
    pub unshot: f64,
    /// Compare with the dense solve when the mesh has at most this many vertices (its cost
    /// grows as the cube; at most 20000, where its matrix holds 3.2 GB).
    #[arg(long, default_value_t = 3000, value_parser = parse_dense_max)]
    pub dense_max_vertices: usize,
}

/// Arguments of `twopass bench rays`.
#[derive(Debug, Args)]
pub struct RaysArgs {
    /// Scene file (.toml or .obj); omit it with `--generate`.
    #[arg(required_unless_present = "generate")]
    pub scene: Option<PathBuf>,
    /// Instead of a file, generate a scene of about this many triangles (the Cornell room
    /// filled with icospheres).
    #[arg(long, conflicts_with = "scene", value_parser = clap::value_parser!(u64).range(1..=50_000_000))]
    pub generate: Option<u64>,
    /// Incoherent and occlusion rays per batch.
    #[arg(long, default_value_t = 1 << 18, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub rays: u64,
    /// Minimum measuring time per query and thread count, seconds.
    #[arg(long, default_value_t = 1.0, value_parser = parse_seconds)]
    pub seconds: f64,
}

/// One measured row.
#[derive(Debug, Serialize)]
struct Row {
    query: &'static str,
    rays: usize,
    /// Millions of rays per second on one thread.
    mrays_1: f64,
    /// Millions of rays per second on all threads.
    mrays_n: f64,
    /// mrays_n / mrays_1.
    speedup: f64,
    /// Fraction of rays that hit (closest hit) or are blocked (occlusion).
    hit_fraction: f64,
    /// Largest resident memory while measuring this query (scene, BVH and ray batch), MiB.
    peak_memory_mib: Option<f64>,
}

#[derive(Debug, Serialize)]
struct Report {
    scene: String,
    triangles: usize,
    threads: usize,
    /// Median of 5 builds, milliseconds.
    bvh_build_ms: f64,
    bvh_nodes: usize,
    rows: Vec<Row>,
}

/// Runs a benchmark.
pub fn run(cmd: &BenchCommand, ctx: &Context) -> Result<(), CliError> {
    match cmd {
        BenchCommand::Rays(args) => rays(args, ctx),
        BenchCommand::Radiosity(args) => radiosity(args, ctx),
        BenchCommand::Render(args) => render(args, ctx),
        BenchCommand::Tradeoff(args) => crate::tradeoff::run(args, ctx),
    }
}

/// Peak resident memory of this process since the last [`reset_peak_memory`], bytes (Linux:
/// VmHWM of /proc/self/status; `None` elsewhere).
pub(crate) fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Resets the peak resident memory to the current one (Linux `clear_refs` 5), so each bench
/// row reports its own peak.
pub(crate) fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Bytes as MiB.
pub(crate) fn mib(bytes: Option<u64>) -> Option<f64> {
    bytes.map(|b| b as f64 / (1024.0 * 1024.0))
}

/// A peak memory figure for a table: whole MiB, or n/a where the platform does not say.
fn fmt_mib(m: Option<f64>) -> String {
    m.map_or_else(|| "n/a".to_owned(), |m| format!("{m:.0}"))
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

fn radiosity_scale(args: &RadiosityArgs, ctx: &Context) -> Result<(), CliError> {
    use twopass_radiosity::{Options, Solver, Stop};
    let progress = ctx.progress(args.generate.len() as u64, "bench radiosity");
    let mut rows: Vec<ScaleRow> = Vec::new();
    for &n in &args.generate {
        reset_peak_memory();
        let started = Instant::now();
        let (scene, _) = workload::synthetic_scene(n as usize, ctx.seed)?;
        let load_seconds = started.elapsed().as_secs_f64();
        let options = Options {
            method: args.solver.method(),
            stop: Stop {
                unshot_fraction: args.unshot,
                ..Stop::default()
            },
            seed: ctx.seed,
            memory_limit: crate::context::memory_limit(),
            ..Options::default()
        };
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
            (now / before).ln() / (scene.mesh.triangles.len() as f64 / prev.triangles as f64).ln()
        };
        let time_growth = rows.last().map(|r| growth(seconds, r.seconds, r));
        let memory_growth = rows
            .last()
            .and_then(|r| Some(growth(peak?, r.peak_memory_mib?, r)));
        rows.push(ScaleRow {
            requested: n,
            triangles: scene.mesh.triangles.len(),
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
    if ctx.json {
        crate::output::print_json(&rows)?;
    } else if !ctx.quiet {
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
    }
    Ok(())
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

fn radiosity(args: &RadiosityArgs, ctx: &Context) -> Result<(), CliError> {
    use twopass_radiosity::{Options, Progressive, Stop, dense_solve};
    let Some(path) = &args.scene else {
        return radiosity_scale(args, ctx);
    };
    let (scene, _) = ctx.load_scene(path)?;
    let area = scene.total_area();
    let progress = ctx.progress(args.elements.len() as u64, "bench radiosity");
    let mut rows = Vec::new();
    for &target in &args.elements {
        // Bisection leaves are right triangles of area about L^2 / 4 for a longest edge L.
        let element_size = (4.0 * area / f64::from(target.max(1))).sqrt() as f32;
        let options = Options {
            element_size: Some(element_size),
            patch_size: Some((scene.bounds.diagonal() / 8.0).max(element_size)),
            adaptive: None,
            stop: Stop {
                unshot_fraction: args.unshot,
                ..Stop::default()
            },
            seed: ctx.seed,
            ..Options::default()
        };
        reset_peak_memory();
        let start = Instant::now();
        let mut solver = Progressive::new(&scene, options).map_err(|source| CliError::Solve {
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
    if ctx.json {
        crate::output::print_json(&rows)?;
    } else if !ctx.quiet {
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
    }
    Ok(())
}

enum Batch {
    Closest(Vec<Ray>),
    Occlusion(Vec<(SurfacePoint, SurfacePoint)>),
}

impl Batch {
    fn len(&self) -> usize {
        match self {
            Self::Closest(r) => r.len(),
            Self::Occlusion(p) => p.len(),
        }
    }

    /// Casts the whole batch once; returns how many rays hit.
    fn cast(&self, scene: &Scene, parallel: bool) -> usize {
        const CHUNK: usize = 1024;
        match (self, parallel) {
            (Self::Closest(r), false) => r.iter().filter(|r| scene.intersect(r).is_some()).count(),
            (Self::Closest(r), true) => r
                .par_chunks(CHUNK)
                .map(|c| c.iter().filter(|r| scene.intersect(r).is_some()).count())
                .sum(),
            (Self::Occlusion(p), false) => p
                .iter()
                .filter(|(a, b)| scene.occluded_between(a, b))
                .count(),
            (Self::Occlusion(p), true) => p
                .par_chunks(CHUNK)
                .map(|c| {
                    c.iter()
                        .filter(|(a, b)| scene.occluded_between(a, b))
                        .count()
                })
                .sum(),
        }
    }

    /// Rays per second (casting repeatedly for at least `min`) and the hit fraction.
    fn measure(&self, scene: &Scene, parallel: bool, min: Duration) -> (f64, f64) {
        let hits = self.cast(scene, parallel); // warm-up, also the hit count
        let start = Instant::now();
        let mut passes = 0usize;
        while passes == 0 || start.elapsed() < min {
            std::hint::black_box(self.cast(scene, parallel));
            passes += 1;
        }
        let rate = (passes * self.len()) as f64 / start.elapsed().as_secs_f64();
        (rate, hits as f64 / self.len().max(1) as f64)
    }
}

/// Most vertices of the dense comparison solve.
const MAX_DENSE_VERTICES: usize = 20_000;

fn parse_dense_max(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|e| format!("{e}"))?;
    if n <= MAX_DENSE_VERTICES {
        Ok(n)
    } else {
        Err(format!("{n} must be at most {MAX_DENSE_VERTICES}"))
    }
}

/// A measuring time: more than 0 and at most a day, seconds.
fn parse_seconds(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if x > 0.0 && x <= 86_400.0 {
        Ok(x)
    } else {
        Err(format!("{x} must be more than 0 and at most 86400 seconds"))
    }
}

fn rays(args: &RaysArgs, ctx: &Context) -> Result<(), CliError> {
    let (scene, name) = match (&args.scene, args.generate) {
        (_, Some(n)) => (
            workload::synthetic_scene(n as usize, ctx.seed)?.0,
            format!("generated ({n} triangles requested)"),
        ),
        (Some(path), None) => (ctx.load_scene(path)?.0, path.display().to_string()),
        (None, None) => unreachable!("clap requires a scene or --generate"),
    };
    let mut scene = scene;
    scene.camera = ctx.camera(&scene.camera)?;
    let n = args.rays as usize;
    let batches = [
        (
            QueryKind::Camera,
            "camera (coherent)",
            Batch::Closest(workload::camera_rays(&scene)),
        ),
        (
            QueryKind::Incoherent,
            "incoherent",
            Batch::Closest(workload::incoherent_rays(&scene, n, ctx.seed)),
        ),
        (
            QueryKind::Occlusion,
            "occlusion",
            Batch::Occlusion(workload::occlusion_pairs(&scene, n, ctx.seed ^ 0x5eed)),
        ),
    ];
    let progress = ctx.progress(7, "bench rays");
    let mut builds: Vec<f64> = (0..5)
        .map(|_| {
            let a = Accel::build(&scene.mesh.positions, &scene.mesh.triangles);
            a.build_time().as_secs_f64() * 1e3
        })
        .collect();
    builds.sort_by(f64::total_cmp);
    progress.inc(1);
    let min = Duration::from_secs_f64(args.seconds);
    let mut rows = Vec::new();
    for (_, label, batch) in &batches {
        reset_peak_memory();
        let (r1, hit) = batch.measure(&scene, false, min);
        progress.inc(1);
        let (rn, _) = batch.measure(&scene, true, min);
        progress.inc(1);
        rows.push(Row {
            query: label,
            rays: batch.len(),
            mrays_1: r1 / 1e6,
            mrays_n: rn / 1e6,
            speedup: rn / r1,
            hit_fraction: hit,
            peak_memory_mib: mib(peak_memory()),
        });
    }
    progress.finish_and_clear();
    let report = Report {
        scene: name,
        triangles: scene.mesh.triangles.len(),
        threads: rayon::current_num_threads(),
        bvh_build_ms: builds[2],
        bvh_nodes: scene.accel().node_count(),
        rows,
    };
    if ctx.json {
        crate::output::print_json(&report)?;
    } else if !ctx.quiet {
        outln!(
            "scene {}: {} triangles, BVH {} nodes built in {:.2} ms (median of 5), {} threads",
            report.scene,
            report.triangles,
            report.bvh_nodes,
            report.bvh_build_ms,
            report.threads
        );
        outln!(
            "{:<18} {:>9} {:>14} {:>14} {:>9} {:>7} {:>9}",
            "query",
            "rays",
            "1 thr Mrays/s",
            format!("{} thr Mrays/s", report.threads),
            "speed-up",
            "hit %",
            "peak MiB"
        );
        for r in &report.rows {
            outln!(
                "{:<18} {:>9} {:>14.2} {:>14.2} {:>8.2}x {:>6.1}% {:>9}",
                r.query,
                r.rays,
                r.mrays_1,
                r.mrays_n,
                r.speedup,
                100.0 * r.hit_fraction,
                fmt_mib(r.peak_memory_mib)
            );
        }
    }
    Ok(())
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

fn render(args: &RenderArgs, ctx: &Context) -> Result<(), CliError> {
    use crate::render::{Method, integrator};
    use twopass_trace::hybrid::radiosity_only;
    use twopass_trace::{Integrator, Progress, RenderSettings, WhittedSettings};

    let (scene, _) = ctx.load_scene(&args.scene)?;
    let camera = crate::context::resized(
        &scene.camera,
        Some(ctx.width.unwrap_or(512)),
        ctx.height.or(Some(ctx.width.unwrap_or(512))),
    )?;
    let started = Instant::now();
    let (solution, source) = match &args.bake {
        Some(path) => (
            twopass_bake::read_bake(path, &scene).map_err(|e| CliError::Input(e.to_string()))?,
            "bake",
        ),
        None => {
            let mut solver = twopass_radiosity::Solver::new(
                &scene,
                twopass_radiosity::Options {
                    seed: ctx.seed,
                    ..Default::default()
                },
            )
            .map_err(|e| CliError::Input(format!("{}: {e}", args.scene.display())))?;
            solver.run(|_| std::ops::ControlFlow::Continue(()));
            (solver.solution(), "solve")
        }
    };
    let radiosity_seconds = started.elapsed().as_secs_f64();
    let settings = RenderSettings {
        samples_per_pixel: args.spp,
        seed: ctx.seed,
        ..Default::default()
    };
    let w = WhittedSettings::default();
    let methods: Vec<Box<dyn Integrator + '_>> = [
        Method::Whitted,
        Method::Radiosity,
        Method::Hybrid,
        Method::HybridDirect,
        Method::Reference,
    ]
    .into_iter()
    .map(|m| integrator(m, &scene, Some(&solution), w))
    .collect();
    let bar = ctx.progress(methods.len() as u64 + 1, "bench render");
    let mut rows = Vec::new();
    for m in &methods {
        reset_peak_memory();
        let out = twopass_trace::render(&scene, &camera, m.as_ref(), &settings, &Progress::new());
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
    let one = RenderSettings {
        samples_per_pixel: 1,
        seed: ctx.seed,
        ..Default::default()
    };
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
            &Progress::new(),
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
    if ctx.json {
        crate::output::print_json(&report)?;
    } else if !ctx.quiet {
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
    }
    Ok(())
}
