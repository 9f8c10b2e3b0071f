//! `twopass merge PARTS... -o OUT`: a complete set of part files assembled into the outputs
//! the single-process command writes, bit for bit.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::set::read_set;
use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Part files of one job (`render --part`, `bake --from --part`), in any order: every part
    /// exactly once.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,
}

/// Checks the set and writes the merged outputs: a render's EXR (and PNG) where `render`
/// would write them for `--output`; a bake's files in the `--output` folder (default `bake`).
pub fn run(args: &MergeArgs, ctx: &Context) -> Result<(), CliError> {
    let started = Instant::now();
    let set = read_set(&args.parts)?;
    match set.header.kind.as_str() {
        "render" => super::assemble::merge(&set, ctx, started),
        "bake" => super::bake::merge(&set, ctx, started),
        other => Err(CliError::Input(format!(
            "{}: a part of kind `{other}`, which this twopass cannot merge",
            set.parts[0].path.display()
        ))),
    }
}
