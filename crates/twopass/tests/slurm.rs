//! `twopass slurm` on a real Slurm cluster (scripts/ci/slurm-up.sh starts one on this host):
//! a 4-part render and a 4-shard lightmap gather merged bit for bit equal to the single
//! process, a cancelled and requeued task whose part the merge then takes, and a mixed set
//! refused. Without a cluster these tests note it and pass; in CI with `TWOPASS_SLURM=1` they
//! fail instead.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{BOX, SPHERES, assert_exit, assert_ok, cli, repo};

/// Longest wait for a submitted job, real time (the jobs are seconds of work each).
const JOB_LIMIT: Duration = Duration::from_secs(300);

/// Longest wait for `sinfo`: with Slurm installed but no controller up, it retries for about
/// a minute before it gives up.
const SINFO_LIMIT: Duration = Duration::from_secs(15);

/// Whether a Slurm node takes jobs (asked once per test binary).
fn node_takes_jobs() -> bool {
    static UP: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *UP.get_or_init(|| {
        let Ok(mut child) = Command::new("sinfo")
            .args(["-h", "-o", "%T"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
        else {
            return false;
        };
        let start = Instant::now();
        loop {
            match child.try_wait() {
                Ok(Some(status)) if status.success() => break,
                Ok(None) if start.elapsed() < SINFO_LIMIT => {
                    std::thread::sleep(Duration::from_millis(100));
                }
                _ => {
                    let _ = child.kill();
                    let _ = child.wait();
                    return false;
                }
            }
        }
        let mut text = String::new();
        let _ = std::io::Read::read_to_string(&mut child.stdout.take().unwrap(), &mut text);
        text.lines()
            .any(|s| ["idle", "mixed", "allocated", "completing"].contains(&s.trim()))
    })
}

/// Whether a Slurm cluster takes jobs; in CI with `TWOPASS_SLURM=1`, a panic when none does.
fn cluster_up() -> bool {
    let up = node_takes_jobs();
    if !up {
        let required = std::env::var_os("CI").is_some()
            && std::env::var("TWOPASS_SLURM").is_ok_and(|v| v == "1");
        assert!(
            !required,
            "no Slurm node takes jobs (sinfo): .ci/run starts one with scripts/ci/slurm-up.sh"
        );
        eprintln!("note: `twopass slurm` not run on a cluster: no Slurm node answers sinfo");
    }
    up
}

/// The job ids of a `twopass slurm ... --json` submission: solve (if any), array, merge.
fn submit(
    kind: &str,
    dir: &Path,
    parts: u32,
    output: &Path,
    command: &[&str],
) -> serde_json::Value {
    let out = cli("slurm")
        .arg(kind)
        .words(&format!("--parts {parts} --json --dir"))
        .arg(dir)
        .output(output)
        .words("--")
        .args(command)
        .run();
    assert_ok(&out);
    serde_json::from_slice(&out.stdout).expect("the job record is JSON")
}

fn id(record: &serde_json::Value, key: &str) -> String {
    record[key].as_str().expect("a job id").to_owned()
}

/// Lines of `squeue` for `jobs` (each array task on a line of its own): `id state`.
fn squeue(jobs: &[String]) -> String {
    let out = Command::new("squeue")
        .args(["-h", "-r", "-o", "%i %T", "-j", &jobs.join(",")])
        .output()
        .expect("squeue runs");
    let err = String::from_utf8_lossy(&out.stderr);
    // Jobs gone from the controller's memory are no longer queued.
    assert!(
        out.status.success() || err.contains("Invalid job id"),
        "squeue: {err}"
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Waits until none of `jobs` is queued or running, at most [`JOB_LIMIT`]; on timeout, fails
/// with the queue and the logs of `dir`.
fn wait(jobs: &[String], dir: &Path) {
    let start = Instant::now();
    loop {
        let queue = squeue(jobs);
        if queue.trim().is_empty() {
            return;
        }
        assert!(
            start.elapsed() < JOB_LIMIT,
            "jobs still queued after {JOB_LIMIT:?}:\n{queue}\nlogs:\n{}",
            logs(dir)
        );
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// Every log of a job folder, for failure messages.
fn logs(dir: &Path) -> String {
    let mut text = String::new();
    if let Ok(entries) = std::fs::read_dir(dir.join("logs")) {
        for e in entries.flatten() {
            let body = std::fs::read_to_string(e.path()).unwrap_or_default();
            text += &format!("== {}\n{body}\n", e.path().display());
        }
    }
    text
}

/// Bytes of `path`, failing with the job's logs when it is missing.
fn read(path: &Path, dir: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}\nlogs:\n{}", path.display(), logs(dir)))
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Every layer of an EXR as bit patterns, by name.
fn exr_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    twopass_composite::write::read_exr_layers(path)
        .unwrap()
        .iter()
        .map(|(name, image)| {
            let bits = image
                .pixels()
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits));
            (name.to_owned(), bits.collect())
        })
        .collect()
}

#[test]
fn slurm_render_and_gather_merge_bit_for_bit() {
    if !cluster_up() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let spheres = s(&repo(SPHERES));
    let render: Vec<&str> = [spheres.as_str()]
        .into_iter()
        .chain(
            "--method hybrid --width 64 --spp 2 --seed 9 --png --layers --element-size 80 --patch-size 150 --unshot 1e-2"
                .split(' '),
        )
        .collect();
    let box_scene = s(&repo(BOX));
    let gather: Vec<&str> = [box_scene.as_str()]
        .into_iter()
        .chain("--lightmap --texel-size 8 --gather 8 --format vertex-glb".split(' '))
        .collect();
    let (rjob, bjob) = (d.join("render-job"), d.join("bake-job"));
    let rec_r = submit("render", &rjob, 4, &d.join("render-out"), &render);
    let rec_b = submit("bake", &bjob, 4, &d.join("bake-out"), &gather);
    // The single process meanwhile.
    let single = d.join("single/x.exr");
    assert_ok(&cli("render --quiet").args(&render).output(&single).run());
    let single_bake = d.join("single-bake");
    assert_ok(&cli("bake --quiet").args(&gather).output(&single_bake).run());
    let jobs: Vec<String> = ["solve_job", "array_job", "merge_job"]
        .iter()
        .flat_map(|k| [id(&rec_r, k), id(&rec_b, k)])
        .collect();
    wait(&jobs, d);
    let merged = d.join("render-out/cornell-spheres-hybrid.exr");
    read(&merged, &rjob);
    assert_eq!(exr_bits(&merged), exr_bits(&single), "render EXR");
    assert_eq!(
        read(&merged.with_extension("png"), &rjob),
        read(&single.with_extension("png"), &rjob),
        "render PNG"
    );
    for file in [
        "cornell-box.lightmap.exr",
        "cornell-box.lightmap.png",
        "cornell-box.lightmap.glb",
        "cornell-box.vertex.glb",
    ] {
        assert!(
            read(&d.join("bake-out").join(file), &bjob) == read(&single_bake.join(file), &bjob),
            "{file} differs"
        );
    }
    // The status of a finished job: every part, their cost, the merge.
    let out = cli("slurm status --json").arg(&bjob).run();
    assert_ok(&out);
    let status: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (status["done"].as_u64(), status["merged"].as_bool()),
        (Some(4), Some(true))
    );
    assert!(status["rays"].as_u64().unwrap() > 0);
}

#[test]
fn a_cancelled_and_requeued_task_redoes_its_part_and_the_merge_succeeds() {
    if !cluster_up() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // About a second of work per task, so that the test catches task 2 running; the box has
    // no glass, so no part carries a light tracing pass.
    let box_scene = s(&repo(BOX));
    let render = [
        &box_scene,
        "--method",
        "reference",
        "--width",
        "64",
        "--spp",
        "1024",
        "--layers",
    ];
    let job = d.join("job");
    let out_dir = d.join("out");
    let rec = submit("render", &job, 4, &out_dir, &render);
    let (array, merge) = (id(&rec, "array_job"), id(&rec, "merge_job"));
    let task = format!("{array}_2");
    let start = Instant::now();
    while !squeue(std::slice::from_ref(&array)).contains(&format!("{task} RUNNING")) {
        assert!(
            start.elapsed() < JOB_LIMIT,
            "task {task} never ran:\n{}",
            logs(&job)
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let run = |args: &[&str]| {
        let out = Command::new(args[0]).args(&args[1..]).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&["scancel", &task]);
    while squeue(std::slice::from_ref(&array)).contains(&format!("{task} RUNNING")) {
        std::thread::sleep(Duration::from_millis(50));
    }
    run(&["scontrol", "requeue", &task]);
    // A requeued job waits before it is eligible again (its begin time is set about two
    // minutes ahead, once it is pending); the test makes it eligible now.
    loop {
        let out = Command::new("squeue")
            .args(["-h", "-o", "%T %r", "-j", &task])
            .output()
            .unwrap();
        let state = String::from_utf8_lossy(&out.stdout).into_owned();
        if state.contains("BeginTime") {
            run(&[
                "scontrol",
                "update",
                &format!("jobid={task}"),
                "StartTime=now",
            ]);
        } else if state.contains("RUNNING") || state.trim().is_empty() {
            break;
        }
        assert!(
            start.elapsed() < JOB_LIMIT,
            "requeued task {task} never ran: {state}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    wait(&[array, merge], d);
    let merged = out_dir.join("cornell-box-reference.exr");
    read(&merged, &job);
    let single = d.join("single.exr");
    assert_ok(&cli("render --quiet").args(&render).output(&single).run());
    assert_eq!(exr_bits(&merged), exr_bits(&single));
    // Part 2's log shows it ran twice (its first run cancelled).
    let log = std::fs::read_dir(job.join("logs"))
        .unwrap()
        .flatten()
        .find(|e| e.file_name().to_string_lossy().ends_with("_2.out"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .unwrap();
    assert!(log.contains("\"part\": \"2/4\""), "{log}");
}

#[test]
fn a_set_with_a_part_of_another_seed_is_refused() {
    if !cluster_up() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let spheres = s(&repo(SPHERES));
    let job = |seed: &str| -> (PathBuf, serde_json::Value) {
        let dir = d.join(format!("seed{seed}"));
        let render = [
            &spheres, "--method", "whitted", "--width", "16", "--spp", "1", "--seed", seed,
            "--layers",
        ];
        let rec = submit("render", &dir, 4, &dir.join("out"), &render);
        (dir, rec)
    };
    let ((a, rec_a), (b, rec_b)) = (job("1"), job("2"));
    let jobs: Vec<String> = ["array_job", "merge_job"]
        .iter()
        .flat_map(|k| [id(&rec_a, k), id(&rec_b, k)])
        .collect();
    wait(&jobs, d);
    let part =
        |dir: &Path, i: u32| dir.join(format!("parts/cornell-spheres-whitted.{i}-of-4.part"));
    let (p1, p2, p3, p4) = (part(&a, 1), part(&b, 2), part(&a, 3), part(&a, 4));
    let out = cli("merge")
        .args(&[&p1, &p2, &p3, &p4])
        .output(d.join("mixed.exr"))
        .run();
    assert_exit(&out, 1);
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        format!(
            "error: {}: another seed: 2, not 1 as in {}; nothing merged\n",
            s(&p2),
            s(&p1)
        )
    );
    assert!(!d.join("mixed.exr").exists());
}

#[test]
fn dry_run_prints_the_three_scripts_and_refuses_flags_out_of_place() {
    let scene = s(&repo(BOX));
    let dir = tempfile::tempdir().unwrap();
    let job = dir.path().join("job");
    let out = cli("slurm render --parts 3 --dry-run --dir")
        .arg(&job)
        .words("--")
        .arg(&scene)
        .words("--method hybrid --width 32 --unshot 0.01")
        .run();
    assert_ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    for want in [
        "# The radiosity solution, once, for every part.",
        "--format bake --gather off",
        "#SBATCH --array=1-3",
        "#SBATCH --requeue",
        "--part \"${SLURM_ARRAY_TASK_ID}/3\"",
        "cornell-box-hybrid.3-of-3.part",
        "sbatch --parsable --dependency=afterany:ARRAY merge.sbatch",
    ] {
        assert!(text.contains(want), "no {want:?} in\n{text}");
    }
    // The solve takes the solver's flags and, for the gathered hybrid, its own default mesh
    // (what `render --method hybrid` solves on alone: diagonal / 12).
    let (box_scene, _) = twopass_scene::load(repo(BOX)).unwrap();
    let mesh = format!(
        "--unshot 0.01 --element-size={} --format bake",
        box_scene.bounds.diagonal() / 12.0
    );
    assert!(text.contains(&mesh), "no {mesh:?} in\n{text}");
    // The parts read the solve's solution instead of solving again.
    let parts = text.split("parts.sbatch").nth(1).unwrap();
    assert!(
        !parts.contains("--unshot") && parts.contains("--bake"),
        "{parts}"
    );
    // Nothing is written by a dry run.
    assert!(!job.exists());
    // Whitted needs no solve.
    let out = cli("slurm render --parts 2 --dry-run --dir")
        .arg(&job)
        .words("--")
        .arg(&scene)
        .words("--method whitted")
        .run();
    assert_ok(&out);
    assert!(!String::from_utf8_lossy(&out.stdout).contains("solve.sbatch"));
    // Flags of the command given to `slurm` itself, or that `slurm` sets, are usage errors.
    for (before, after) in [
        ("--width 32", "--method whitted"),
        ("", "--method whitted --output x.exr"),
        ("", "--method whitted --part 1/2"),
        ("", "--method whitted --adaptive 4"),
    ] {
        let out = cli("slurm render --parts 2 --dry-run")
            .words(before)
            .words("--")
            .arg(&scene)
            .words(after)
            .run();
        assert_exit(&out, 2);
    }
}
