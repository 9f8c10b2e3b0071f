//! `twopass`: the command line of the twopass engine.
//!
//! Every subcommand shares the options of [`context::Context`] (`--output`, `--width`,
//! `--height`, `--seed`, `--threads`, `--quiet`, `--json`). Exit codes: 0 on success, 1 on a user
//! error (bad input; the message on stderr names the file and the problem), 2 on a usage error.

#[macro_use]
mod macros;

mod allocation;
mod args;
mod bake;
mod bench;
mod brdf_check;
mod compare;
mod context;
mod error;
mod figure;
mod final_gather;
mod info;
mod output;
mod part;
mod pipeline;
mod plan;
mod preset;
mod render;
mod render_plan;
mod slurm;
mod solve;
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::context::Context;
use crate::error::CliError;

/// Hybrid global illumination: radiosity for the diffuse light, Whitted ray tracing for the rest.
#[derive(Debug, Parser)]
#[command(name = "twopass", version, about, propagate_version = true)]
struct Cli {
    #[command(flatten)]
    ctx: Context,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Describe a scene: triangles, materials, emitters, bounds, and the passes it requires.
    Info(info::InfoArgs),
    /// Render the scene with every method it calls for and compare them with the reference:
    /// a comparison sheet, one EXR per method, a JSON and CSV report.
    Compare(compare::CompareArgs),
    /// Render an image with one method: whitted, radiosity, hybrid (gathered
    /// per pixel), hybrid-classic, hybrid-direct, reference.
    Render(render::RenderArgs),
    /// Tabulate the plausibility of every reflection model and plot their lobes.
    BrdfCheck(brdf_check::BrdfCheckArgs),
    /// Solve the scene's radiosity and write the baked lighting: glTF binary (.glb, COLOR_0),
    /// PLY (float radiance), a bake file `render` can load, and a JSON manifest.
    Bake(bake::BakeArgs),
    /// Measure the engine: ray queries, radiosity solves, renders, and the speed/accuracy trade.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Write a static three.js page that shows a lightmap bake from the scene's camera.
    View(view::ViewArgs),
    /// Assemble the part files of `render --part` or `bake --from --part` into the outputs
    /// the single-process command writes, bit for bit.
    Merge(part::merge::MergeArgs),
    /// Run a render or a bake on a Slurm cluster: the solve as one job, the parts as a job
    /// array after it, the merge after the array; and how far a submitted job is.
    #[command(subcommand)]
    Slurm(slurm::SlurmCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = run(cli).and_then(|()| {
        use std::io::Write as _;
        std::io::stdout()
            .flush()
            .map_err(|e| CliError::io("(standard output)", e))
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`| head`): nothing more to say to anyone.
        Err(e) if e.is_broken_pipe() => ExitCode::SUCCESS,
        Err(e) => {
            errln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Stack of each worker thread, bytes: the command runs on one of them (see [`run`]), so it
/// gets what the main thread would (8 MiB) and more.
const WORKER_STACK_BYTES: usize = 16 << 20;

fn run(cli: Cli) -> Result<(), CliError> {
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(WORKER_STACK_BYTES);
    if let Some(n) = cli.ctx.threads {
        pool = pool.num_threads(n as usize);
    }
    pool.build_global().map_err(|e| {
        let n = cli
            .ctx
            .threads
            .map_or_else(|| "the".to_owned(), |n| n.to_string());
        CliError::Input(format!("cannot start {n} worker threads: {e}"))
    })?;
    // The command itself runs on a worker: its parallel loops (one per radiosity shot, one per
    // render) then start by splitting work with the other workers instead of waking the pool
    // from outside and sleeping until it is done, which cost tens of microseconds a loop.
    rayon::scope(|_| match &cli.command {
        Command::Info(args) => info::run(args, &cli.ctx),
        Command::BrdfCheck(args) => brdf_check::run(args, &cli.ctx),
        Command::Render(args) => render::run(args, &cli.ctx),
        Command::Compare(args) => compare::run(args, &cli.ctx),
        Command::Bake(args) => match (&args.from, args.part) {
            (Some(from), Some(part)) => part::bake::write_part(args, from, part, &cli.ctx),
            _ => bake::run(args, &cli.ctx),
        },
        Command::Bench(cmd) => bench::run(cmd, &cli.ctx),
        Command::View(args) => view::run(args, &cli.ctx),
        Command::Merge(args) => part::merge::run(args, &cli.ctx),
        Command::Slurm(cmd) => slurm::run(cmd, &cli.ctx),
    })
}
