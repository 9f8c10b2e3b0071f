//! `twopass`: the command line of the twopass engine.
//!
//! Every subcommand shares the options of [`context::Context`] (`--output`, `--width`,
//! `--height`, `--seed`, `--threads`, `--quiet`, `--json`). Exit codes: 0 on success, 1 on a user
//! error (bad input; the message on stderr names the file and the problem), 2 on a usage error.

mod bake;
mod bench;
mod brdf_check;
mod compare;
mod context;
mod error;
mod figure;
mod info;
mod output;
mod plan;
mod preset;
mod render;
mod tradeoff;

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
    /// Render an image with one method: whitted, radiosity, hybrid, hybrid-direct, reference.
    Render(render::RenderArgs),
    /// Tabulate the plausibility of every reflection model and plot their lobes.
    BrdfCheck(brdf_check::BrdfCheckArgs),
    /// Solve the scene's radiosity and write the baked lighting: glTF binary (.glb, COLOR_0),
    /// PLY (float radiance), a bake file `render` can load, and a JSON manifest.
    Bake(bake::BakeArgs),
    /// Measure the engine: ray queries, radiosity solves, renders, and the speed/accuracy trade.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> Result<(), CliError> {
    if let Some(n) = cli.ctx.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| CliError::Input(format!("cannot start {n} threads: {e}")))?;
    }
    match &cli.command {
        Command::Info(args) => info::run(args, &cli.ctx),
        Command::BrdfCheck(args) => brdf_check::run(args, &cli.ctx),
        Command::Render(args) => render::run(args, &cli.ctx),
        Command::Compare(args) => compare::run(args, &cli.ctx),
        Command::Bake(args) => bake::run(args, &cli.ctx),
        Command::Bench(cmd) => bench::run(cmd, &cli.ctx),
    }
}
