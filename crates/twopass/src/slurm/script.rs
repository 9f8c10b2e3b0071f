//! The job plan of `twopass slurm render|bake`: the user's command checked by `twopass`'s
//! own parser, the solve's flags picked out of it, and the three `sbatch` scripts.

use std::path::{Path, PathBuf};

use clap::{Args, Parser};

use super::SubmitArgs;
use crate::bake::BakeArgs;
use crate::context::Context;
use crate::error::CliError;
use crate::part::PartIndex;
use crate::part::file::{part_path, stem};
use crate::pipeline::RenderMethod;
use crate::render::RenderArgs;
use crate::solve::SolveArgs;

/// What a Slurm job computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `twopass render ... --part`.
    Render,
    /// `twopass bake ... --from --part`.
    Bake,
}

impl Kind {
    /// The `twopass` subcommand of the parts.
    pub fn command(self) -> &'static str {
        match self {
            Self::Render => "render",
            Self::Bake => "bake",
        }
    }
}

#[derive(Parser)]
struct RenderLine {
    #[command(flatten)]
    ctx: Context,
    #[command(flatten)]
    args: RenderArgs,
}

#[derive(Parser)]
struct BakeLine {
    #[command(flatten)]
    ctx: Context,
    #[command(flatten)]
    args: BakeArgs,
}

/// A job ready to submit: its folder, the scripts and the files they write.
#[derive(Debug)]
pub struct Plan {
    /// The job's folder (absolute).
    pub dir: PathBuf,
    /// Parts of the array.
    pub parts: u32,
    /// The solve's script, when the work needs a solution.
    pub solve: Option<String>,
    /// The job array's script.
    pub array: String,
    /// The merge's script.
    pub merge: String,
    /// Every part file the array writes, part 1 first.
    pub part_files: Vec<PathBuf>,
    /// Where the merge writes (`--output` of `twopass slurm`, default `<dir>/out`).
    pub output: PathBuf,
}

/// Quotes `s` for the shell (single quotes; a quote inside as `'\''`).
pub fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c))
    {
        return s.to_owned();
    }
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The flags of `command` (the user's, after the scene) that the solve takes: the solver's
/// (`SolveArgs`), `--preset`/`--presets`, `--seed` and `--confine`, each with its value.
fn solve_flags(command: &[String]) -> (Vec<String>, Vec<String>) {
    let solver = SolveArgs::augment_args(clap::Command::new("solve"));
    let mut takes: Vec<(String, bool)> = solver
        .get_arguments()
        .filter_map(|a| Some((a.get_long()?.to_owned(), a.get_action().takes_values())))
        .collect();
    takes.extend(
        [
            ("preset", true),
            ("presets", true),
            ("seed", true),
            ("confine", false),
        ]
        .map(|(n, v)| (n.to_owned(), v)),
    );
    let (mut solve, mut rest) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < command.len() {
        let word = &command[i];
        let name = word
            .strip_prefix("--")
            .map(|n| n.split_once('=').map_or(n, |(n, _)| n));
        match name.and_then(|n| takes.iter().find(|(t, _)| t == n)) {
            Some((_, value)) => {
                solve.push(word.clone());
                if *value && !word.contains('=') && i + 1 < command.len() {
                    i += 1;
                    solve.push(command[i].clone());
                }
            }
            None => rest.push(word.clone()),
        }
        i += 1;
    }
    // The seed and the preset shape the parts too: they keep them.
    rest.extend(
        solve
            .iter()
            .enumerate()
            .filter(|(j, w)| {
                let keep = |w: &str| {
                    ["--seed", "--preset", "--presets"]
                        .iter()
                        .any(|f| w == *f || w.starts_with(&format!("{f}=")))
                };
                keep(w) || (*j > 0 && keep(&solve[j - 1]) && !solve[j - 1].contains('='))
            })
            .map(|(_, w)| w.clone())
            .collect::<Vec<_>>(),
    );
    (solve, rest)
}

/// A usage error from the user's command as `twopass` parses it.
fn usage(kind: Kind, e: &clap::Error) -> CliError {
    let text = e.render().to_string();
    let first = text
        .lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("error: ");
    CliError::Usage(format!("the {} command after --: {first}", kind.command()))
}

/// Checks the user's command and builds the plan.
pub fn plan(kind: Kind, args: &SubmitArgs, ctx: &Context) -> Result<Plan, CliError> {
    if ctx.width.is_some() || ctx.height.is_some() || ctx.seed != 0 || ctx.confine {
        return Err(CliError::Usage(
            "--width, --height, --seed and --confine belong to the command after --, which \
             `twopass slurm` passes to every job as it is"
                .into(),
        ));
    }
    let argv =
        std::iter::once(format!("twopass {}", kind.command())).chain(args.command.iter().cloned());
    // The gathered hybrid's own default mesh (`render::hybrid_element_size`), which the solve
    // job must use for the parts to render what one `render` would.
    let mut hybrid_mesh = None;
    let (line_ctx, scene, name, needs_solve, no_more) = match kind {
        Kind::Render => {
            let line = RenderLine::try_parse_from(argv).map_err(|e| usage(kind, &e))?;
            let preset = match &line.args.preset {
                Some(p) => Some(crate::preset::load(
                    &line.args.scene,
                    line.args.presets.as_deref(),
                    p,
                )?),
                None => None,
            };
            let method = preset
                .as_ref()
                .map_or(line.args.method.unwrap_or(RenderMethod::Hybrid), |p| {
                    p.method
                });
            if line.args.adaptive.is_some() {
                return Err(CliError::Usage(
                    "--adaptive cannot be split into parts (a pixel is refined by its \
                     neighbours over the whole image)"
                        .into(),
                ));
            }
            let needs = method.needs_radiosity() && line.args.bake.is_none();
            let preset_sized = preset.as_ref().is_some_and(|p| p.radiosity.is_some());
            if needs && method == RenderMethod::Hybrid {
                let (scene, _) = ctx.load_scene(&line.args.scene)?;
                hybrid_mesh = crate::render::hybrid_element_size(
                    method,
                    preset_sized,
                    &line.args.solve,
                    &scene,
                )
                .map(|size| format!("--element-size={size}"));
            }
            let name = format!("{}-{}", stem(&line.args.scene), method.name());
            let no_more = line.args.part.is_some();
            (line.ctx, line.args.scene, name, needs, no_more)
        }
        Kind::Bake => {
            let line = BakeLine::try_parse_from(argv).map_err(|e| usage(kind, &e))?;
            if line.args.solve.time_budget.is_some() {
                return Err(CliError::Usage(
                    "--time-budget: parts gathered against a clock do not merge bit for bit".into(),
                ));
            }
            let name = format!("{}-bake", stem(&line.args.scene));
            let no_more = line.args.part.is_some() || line.args.from.is_some();
            (line.ctx, line.args.scene, name, true, no_more)
        }
    };
    if line_ctx.output.is_some() || no_more || line_ctx.threads.is_some() {
        return Err(CliError::Usage(
            "the command after -- takes neither --output, --threads, --part nor --from: \
             `twopass slurm` sets them (give --output and --cpus to `twopass slurm`)"
                .into(),
        ));
    }
    if args.command.first().map(PathBuf::from) != Some(scene.clone()) {
        return Err(CliError::Usage(
            "the command after -- starts with the scene: -- SCENE [FLAGS]".into(),
        ));
    }
    let cwd = std::env::current_dir().map_err(|e| CliError::io(".", e))?;
    let dir = cwd.join(
        args.dir
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("slurm-{}", stem(&scene)))),
    );
    let output = ctx
        .output
        .as_ref()
        .map_or_else(|| dir.join("out"), |o| cwd.join(o));
    let exe = std::env::current_exe().map_err(|e| CliError::io("twopass", e))?;
    let exe = quote(&exe.display().to_string());
    let path = |p: &Path| quote(&p.display().to_string());
    let scene_q = quote(&args.command[0]);
    let threads = format!("--threads {}", args.cpus);
    let (mut solve_words, rest) = solve_flags(&args.command[1..]);
    solve_words.extend(hybrid_mesh);
    let rest_q = |words: &[String]| words.iter().map(|w| quote(w)).collect::<Vec<_>>().join(" ");
    let header = |job: &str, log: &str, extra: &[&str]| {
        let mut lines = vec![
            "#!/bin/bash".to_owned(),
            format!("#SBATCH --job-name=twopass-{name}-{job}"),
            format!("#SBATCH --chdir={}", cwd.display()),
            format!("#SBATCH --output={}", dir.join("logs").join(log).display()),
            "#SBATCH --ntasks=1".to_owned(),
            format!("#SBATCH --cpus-per-task={}", args.cpus),
        ];
        lines.extend(extra.iter().map(|e| format!("#SBATCH {e}")));
        lines.extend(args.sbatch.iter().map(|o| format!("#SBATCH {o}")));
        lines.push("set -euo pipefail".to_owned());
        lines.join("\n")
    };
    let solution = dir.join("solve").join(format!("{}.bake", stem(&scene)));
    let solve = needs_solve.then(|| {
        format!(
            "{}\n# The radiosity solution, once, for every part.\nexec {exe} bake {scene_q} {} \
             --format bake --gather off {threads} --output {}\n",
            header("solve", "solve-%j.out", &[]),
            rest_q(&solve_words),
            path(&dir.join("solve")),
        )
    });
    let parts_dir = dir.join("parts");
    let (task_words, from) = match (kind, needs_solve) {
        (Kind::Render, true) => (rest.clone(), format!("--bake {}", path(&solution))),
        (Kind::Render, false) => (args.command[1..].to_vec(), String::new()),
        (Kind::Bake, _) => (
            args.command[1..].to_vec(),
            format!("--from {}", path(&solution)),
        ),
    };
    let n = args.parts;
    let array = format!(
        "{}\n# Part ${{SLURM_ARRAY_TASK_ID}} of {n}, written atomically: a requeued task redoes \
         its own part.\nexec {exe} {} {scene_q} {} {from} --part \"${{SLURM_ARRAY_TASK_ID}}/{n}\" \
         {threads} --json --output {}/\n",
        header(
            "part",
            "part-%A_%a.out",
            &[&format!("--array=1-{n}"), "--requeue"]
        ),
        kind.command(),
        rest_q(&task_words),
        path(&parts_dir),
    );
    let part_files: Vec<PathBuf> = (1..=n)
        .map(|index| part_path(Some(&parts_dir), &name, PartIndex { index, of: n }))
        .collect();
    let merge = format!(
        "{}\n# Every part by name: a missing or damaged one is named in the error.\nexec {exe} \
         merge {} {threads} --json --output {}\n",
        header("merge", "merge-%j.out", &[]),
        part_files
            .iter()
            .map(|p| path(p))
            .collect::<Vec<_>>()
            .join(" "),
        path(&output),
    );
    Ok(Plan {
        dir,
        parts: n,
        solve,
        array,
        merge,
        part_files,
        output,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_owned).collect()
    }

    #[test]
    fn the_solve_takes_the_solver_flags_and_the_parts_keep_the_rest() {
        let (solve, rest) = solve_flags(&words(
            "--method hybrid --unshot 0.01 --seed 3 --no-adaptive --width 64 --element-size=80",
        ));
        assert_eq!(
            solve,
            words("--unshot 0.01 --seed 3 --no-adaptive --element-size=80")
        );
        assert_eq!(rest, words("--method hybrid --width 64 --seed 3"));
    }

    #[test]
    fn quoting_keeps_plain_words_and_quotes_the_rest() {
        assert_eq!(quote("scenes/box.toml"), "scenes/box.toml");
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), r"'it'\''s'");
    }
}
