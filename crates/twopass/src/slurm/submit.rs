//! Submitting a plan with `sbatch --parsable` (or printing it with `--dry-run`), and the
//! record of the job `slurm status` reads.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde::{Deserialize, Serialize};

use super::SubmitArgs;
use super::script::{Kind, Plan, plan};
use crate::context::Context;
use crate::error::CliError;

/// The record of a submitted job, `<dir>/job.json`.
#[derive(Debug, Serialize, Deserialize)]
pub struct JobRecord {
    /// `render` or `bake`.
    pub kind: String,
    /// Parts of the array.
    pub parts: u32,
    /// The solve's job id, when there is a solve.
    pub solve_job: Option<String>,
    /// The job array's id.
    pub array_job: Option<String>,
    /// The merge's job id.
    pub merge_job: Option<String>,
    /// Every part file, part 1 first.
    pub part_files: Vec<PathBuf>,
    /// Where the merge writes.
    pub output: PathBuf,
}

/// The name of the job record in a job's folder.
pub const JOB_RECORD: &str = "job.json";

/// Submits `sbatch --parsable [options] script` and returns the job id.
fn sbatch(script: &Path, options: &[String]) -> Result<String, CliError> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(options)
        .arg(script)
        .output()
        .map_err(|e| {
            CliError::Input(format!(
                "sbatch: cannot run it ({e}); submit from a Slurm login node, or print the \
                 scripts with --dry-run"
            ))
        })?;
    if !out.status.success() {
        return Err(CliError::Input(format!(
            "{}: sbatch refused it: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    // `--parsable` prints `jobid` or `jobid;cluster`.
    let id = text.trim().split(';').next().unwrap_or("").to_owned();
    if id.is_empty() {
        return Err(CliError::Input(format!(
            "{}: sbatch printed no job id",
            script.display()
        )));
    }
    Ok(id)
}

/// Plans the job and submits it (or prints it with `--dry-run`).
pub fn run(kind: Kind, args: &SubmitArgs, ctx: &Context) -> Result<(), CliError> {
    let plan = plan(kind, args, ctx)?;
    let scripts = plan.dir.join("scripts");
    let files = [
        ("solve.sbatch", plan.solve.as_deref()),
        ("parts.sbatch", Some(plan.array.as_str())),
        ("merge.sbatch", Some(plan.merge.as_str())),
    ];
    if args.dry_run {
        for (name, text) in files {
            if let Some(text) = text {
                outln!("# {}", scripts.join(name).display());
                out!("{text}");
                outln!();
            }
        }
        let solve = if plan.solve.is_some() {
            "sbatch --parsable solve.sbatch  # -> SOLVE\n".to_owned()
                + "sbatch --parsable --dependency=afterok:SOLVE parts.sbatch  # -> ARRAY\n"
        } else {
            "sbatch --parsable parts.sbatch  # -> ARRAY\n".to_owned()
        };
        outln!(
            "# submitted as:\n{solve}sbatch --parsable --dependency=afterany:ARRAY merge.sbatch"
        );
        return Ok(());
    }
    for sub in ["scripts", "logs", "parts", "solve"] {
        crate::output::create_dir(&plan.dir.join(sub))?;
    }
    for (name, text) in files {
        if let Some(text) = text {
            crate::output::write_atomic(&scripts.join(name), text.as_bytes())?;
        }
    }
    let solve_job = match &plan.solve {
        Some(_) => Some(sbatch(&scripts.join("solve.sbatch"), &[])?),
        None => None,
    };
    let after_solve: Vec<String> = solve_job
        .iter()
        .map(|id| format!("--dependency=afterok:{id}"))
        .collect();
    let array_job = sbatch(&scripts.join("parts.sbatch"), &after_solve)?;
    let merge_job = sbatch(
        &scripts.join("merge.sbatch"),
        &[format!("--dependency=afterany:{array_job}")],
    )?;
    let record = JobRecord {
        kind: kind.command().into(),
        parts: plan.parts,
        solve_job,
        array_job: Some(array_job),
        merge_job: Some(merge_job),
        part_files: plan.part_files.clone(),
        output: plan.output.clone(),
    };
    let json = serde_json::to_vec_pretty(&record).map_err(|e| CliError::Encode {
        path: plan.dir.join(JOB_RECORD),
        message: e.to_string(),
    })?;
    crate::output::write_atomic(&plan.dir.join(JOB_RECORD), &json)?;
    report(&plan, &record, ctx)
}

fn report(plan: &Plan, record: &JobRecord, ctx: &Context) -> Result<(), CliError> {
    crate::output::report(record, ctx, || {
        if let Some(id) = &record.solve_job {
            outln!("solve job {id}");
        }
        outln!(
            "parts job array {} ({} tasks), after the solve",
            record.array_job.as_deref().unwrap_or("?"),
            record.parts
        );
        outln!(
            "merge job {}, after the array",
            record.merge_job.as_deref().unwrap_or("?")
        );
        outln!("parts land in {}", plan.dir.join("parts").display());
        outln!("merged outputs in {}", plan.output.display());
        outln!("logs in {}", plan.dir.join("logs").display());
        outln!("progress: twopass slurm status {}", plan.dir.display());
        Ok(())
    })
}
