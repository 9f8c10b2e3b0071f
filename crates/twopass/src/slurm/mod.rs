//! `twopass slurm render|bake|status`: a render or a bake run on a Slurm cluster as it is,
//! with Slurm's own tools (`sbatch`, job arrays, dependencies); twopass schedules nothing.
//!
//! Three jobs: the solve (`twopass bake --format bake --gather off`, when the work needs a
//! radiosity solution), the parts as a job array depending on it (`--dependency=afterok`:
//! no part starts over a failed solve), and the merge after the array
//! (`--dependency=afterany`: it runs when every task has ended, also after a failed one, and
//! then itself names any missing or damaged part; a task requeued before the array ends, by
//! `--requeue` on preemption or by `scontrol requeue`, is waited for). Each part is written
//! atomically, so a requeued task redoes its own part and nothing else. The scripts are
//! generated (not static files in the repository) because they carry the job's own command
//! lines, paths and part count; `--dry-run` prints them.
//!
//! Files in `--dir` (default `slurm-<stem>`): `scripts/` (the three scripts), `logs/` (Slurm's
//! output of each job; a part's `--json` summary with its rays and seconds), `solve/` (the
//! solution), `parts/` (the part files), `job.json` (the job ids and files, read by `slurm
//! status`), and the merged outputs in `--output` (default `<dir>/out`).

mod script;
mod status;
mod submit;

use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::context::Context;
use crate::error::CliError;

/// `twopass slurm` subcommands.
#[derive(Debug, Subcommand)]
pub enum SlurmCommand {
    /// Submit a render as a job array of `--parts` parts: `twopass slurm render --parts N --
    /// SCENE [render flags]`.
    Render(SubmitArgs),
    /// Submit a bake's final gather as a job array of `--parts` shards over one solve:
    /// `twopass slurm bake --parts N -- SCENE [bake flags]`.
    Bake(SubmitArgs),
    /// How many parts of a submitted job are done, their rays and seconds, and whether the
    /// merged outputs are there.
    Status(status::StatusArgs),
}

/// Arguments of `twopass slurm render` and `slurm bake`.
#[derive(Debug, Args)]
pub struct SubmitArgs {
    /// Parts of the job array (1 to 1000, Slurm's default `MaxArraySize` less one).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub parts: u32,
    /// Folder of the job's scripts, logs, solution and parts (default `slurm-<stem>`).
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// CPUs per task (`#SBATCH --cpus-per-task`; each task's twopass uses that many threads).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub cpus: u32,
    /// Print the scripts instead of submitting them.
    #[arg(long)]
    pub dry_run: bool,
    /// Extra `sbatch` options for every job (such as `--partition=render`), repeatable.
    #[arg(long = "sbatch", value_name = "OPTION", allow_hyphen_values = true)]
    pub sbatch: Vec<String>,
    /// The scene and the flags of `twopass render` or `twopass bake`, after `--`.
    #[arg(last = true, required = true, value_name = "SCENE [FLAGS]")]
    pub command: Vec<String>,
}

/// Runs a `twopass slurm` subcommand.
pub fn run(cmd: &SlurmCommand, ctx: &Context) -> Result<(), CliError> {
    match cmd {
        SlurmCommand::Render(args) => submit::run(script::Kind::Render, args, ctx),
        SlurmCommand::Bake(args) => submit::run(script::Kind::Bake, args, ctx),
        SlurmCommand::Status(args) => status::run(args, ctx),
    }
}
