//! `twopass slurm status DIR`: how many parts of a submitted job are done (whole, checked
//! part files), their rays and seconds, and whether the merge has written its outputs.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::submit::{JOB_RECORD, JobRecord};
use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass slurm status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    /// The job's folder (`--dir` of `twopass slurm render|bake`).
    pub dir: PathBuf,
}

#[derive(Serialize)]
struct Status {
    parts: u32,
    done: u32,
    /// Parts not written yet, as `I/N`.
    missing: Vec<String>,
    /// Part files that are there but damaged, with why.
    damaged: Vec<String>,
    rays: u64,
    shadow_rays: u64,
    seconds: f64,
    merged: bool,
    output: PathBuf,
    jobs: Vec<String>,
}

/// Reads the job record and the part files.
pub fn run(args: &StatusArgs, ctx: &Context) -> Result<(), CliError> {
    let record_path = args.dir.join(JOB_RECORD);
    let text =
        crate::output::read_small(&record_path).map_err(|e| CliError::io(&record_path, e))?;
    let record: JobRecord = serde_json::from_slice(&text).map_err(|e| {
        CliError::Input(format!(
            "{}: not a job record of `twopass slurm` ({e})",
            record_path.display()
        ))
    })?;
    let mut s = Status {
        parts: record.parts,
        done: 0,
        missing: Vec::new(),
        damaged: Vec::new(),
        rays: 0,
        shadow_rays: 0,
        seconds: 0.0,
        merged: false,
        output: record.output.clone(),
        jobs: [&record.solve_job, &record.array_job, &record.merge_job]
            .into_iter()
            .flatten()
            .cloned()
            .collect(),
    };
    for (i, file) in record.part_files.iter().enumerate() {
        if !file.exists() {
            s.missing.push(format!("{}/{}", i + 1, record.parts));
            continue;
        }
        match crate::part::file::read_header(file) {
            Ok(h) => {
                s.done += 1;
                s.rays += h.cost.rays;
                s.shadow_rays += h.cost.shadow_rays;
                s.seconds += h.cost.seconds;
            }
            Err(e) => s.damaged.push(e.to_string()),
        }
    }
    s.merged = match record.kind.as_str() {
        // The merge of a bake writes its manifest last.
        "bake" => std::fs::read_dir(&record.output).is_ok_and(|mut d| {
            d.any(|e| e.is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".manifest.json")))
        }),
        _ => {
            std::fs::read_dir(&record.output).is_ok_and(|mut d| d.next().is_some())
                || record.output.is_file()
        }
    };
    crate::output::report(&s, ctx, || {
        let missing = if s.missing.is_empty() {
            String::new()
        } else {
            format!(" (not yet: {})", s.missing.join(", "))
        };
        outln!(
            "{} of {} parts done{missing}: {} rays, {} shadow rays, {:.2} s in the parts",
            s.done,
            s.parts,
            s.rays,
            s.shadow_rays,
            s.seconds
        );
        for d in &s.damaged {
            outln!("damaged: {d}");
        }
        outln!(
            "merged: {} ({})",
            if s.merged { "yes" } else { "not yet" },
            s.output.display()
        );
        if !s.jobs.is_empty() {
            outln!(
                "jobs: {} (squeue -j {})",
                s.jobs.join(", "),
                s.jobs.join(",")
            );
        }
        Ok(())
    })
}
