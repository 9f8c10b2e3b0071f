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
//! - the reference path tracer: samples per pixel;
//! - the bake's final gather over the element mesh (rays per point, over coarse and base
//!   solves), rendered as radiosity alone: the curve `radiosity-gathered`, which the presets
//!   (settings of `twopass render`, which shows a solve as solved) leave out.
//!
//! Writes, in `--output DIR` (default `tradeoff/`): `<stem>-tradeoff.csv` (one row per run:
//! method, settings, time per phase, rays, peak memory, error metrics, Pareto membership),
//! `<stem>-tradeoff.json` (the same plus the reference, the presets and the time each method
//! takes to reach each target), `<stem>-tradeoff.png` (error against time, log-log, one curve
//! per method, the Pareto front marked) and `<stem>.presets.toml` (the presets derived from the
//! front: the cheapest measured setting reaching each target error).

mod args;
pub mod front;
mod measure;
mod plot;
pub mod reference;
mod report;
mod run;
mod sweep;

pub use args::TradeoffArgs;
pub use run::run;
