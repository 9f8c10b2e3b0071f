//! `twopass bench ...`: end-to-end measurements, reported with ratios taken within one run.
//!
//! One module per benchmark: `rays` (ray queries and the BVH build), `radiosity` (solves by
//! element count or generated scene size), `render` (every method, and new views from a bake),
//! `tradeoff` (the speed/accuracy sweep and the presets), `bakes` (bake quality on generated
//! rooms against the path tracer); `memory` measures the peak resident memory they report.

pub mod bakes;
pub mod memory;
pub mod radiosity;
pub mod rays;
pub mod render;
pub mod tradeoff;

use clap::Subcommand;

use crate::context::Context;
use crate::error::CliError;

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Ray queries per second (camera, incoherent, occlusion) on one and on all threads, and
    /// the BVH build time.
    Rays(rays::RaysArgs),
    /// Radiosity solves at several element counts (progressive refinement): time, shots,
    /// rays, peak memory, and the error against the dense solve where it fits; or, with
    /// `--generate`, solves of generated scenes of growing size (by default with the
    /// hierarchical solver): time, links, rays, peak memory and their growth exponents.
    Radiosity(radiosity::RadiosityArgs),
    /// Render time and rays per second of every method, and frames per second of new views
    /// rendered from a bake file (radiosity alone).
    Render(render::RenderBenchArgs),
    /// The speed/accuracy trade: sweeps every method's knobs, measures time and error against
    /// a cached converged reference, plots the Pareto front and derives the presets.
    Tradeoff(tradeoff::TradeoffArgs),
    /// Bake quality on a family of generated rooms: for each, a cached converged reference
    /// (the path tracer), one `twopass bake --lightmap` (time, peak memory) and the renders
    /// from its lightmap and its `.bake`, measured against the reference per image and per
    /// object. Arguments after `--` go to every bake.
    Bakes(bakes::BakesArgs),
}

/// Runs a benchmark.
pub fn run(cmd: &BenchCommand, ctx: &Context) -> Result<(), CliError> {
    match cmd {
        BenchCommand::Rays(args) => rays::run(args, ctx),
        BenchCommand::Radiosity(args) => radiosity::run(args, ctx),
        BenchCommand::Render(args) => render::run(args, ctx),
        BenchCommand::Tradeoff(args) => tradeoff::run(args, ctx),
        BenchCommand::Bakes(args) => bakes::run(args, ctx),
    }
}
