//! Runs `twopass` itself as a child process and measures it: wall time, and peak resident
//! memory read from the child's `/proc/<pid>/status` (`VmHWM`, a high-water mark) every
//! [`POLL`] while it runs. The workspace forbids `unsafe`, which `wait4`'s resource usage
//! would take; since the kernel keeps the high-water mark itself, only growth in the child's
//! last [`POLL`] can escape the figure (Linux; `None` elsewhere).

use std::ffi::OsString;
use std::io::Read as _;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::error::CliError;

/// How often the child's peak resident memory is read.
const POLL: Duration = Duration::from_millis(10);
/// Most bytes of a failed child's standard error quoted in the error.
const STDERR_TAIL: usize = 2000;

/// What a child cost.
#[derive(Debug, Clone, Copy)]
pub struct ChildRun {
    /// Wall-clock seconds from spawn to exit.
    pub seconds: f64,
    /// Peak resident memory, bytes (`None` where /proc does not say).
    pub peak_bytes: Option<u64>,
}

/// The `VmHWM` of process `pid`, bytes.
fn high_water(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Runs this executable with `args` (its output discarded, standard error kept for the
/// message when it fails) and waits for it; a failure is an error quoting the command line
/// and the end of its standard error.
pub fn run_twopass(args: &[OsString]) -> Result<ChildRun, CliError> {
    let exe = std::env::current_exe().map_err(|e| CliError::io("(the twopass executable)", e))?;
    let shown = || {
        let words: Vec<String> = args
            .iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        format!("twopass {}", words.join(" "))
    };
    let started = Instant::now();
    let mut child = Command::new(&exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| CliError::io(&exe, e))?;
    // Drain standard error on a thread so a chatty child never blocks on a full pipe.
    let mut stderr = child.stderr.take().expect("standard error is piped");
    let reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        let _ = stderr.read_to_end(&mut text);
        text
    });
    let pid = child.id();
    let mut peak = None;
    let status = loop {
        if let Some(hwm) = high_water(pid) {
            peak = Some(peak.map_or(hwm, |p: u64| p.max(hwm)));
        }
        match child.try_wait().map_err(|e| CliError::io(&exe, e))? {
            Some(status) => break status,
            None => std::thread::sleep(POLL),
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    let text = reader.join().unwrap_or_default();
    if !status.success() {
        let text = String::from_utf8_lossy(&text);
        let tail = text
            .char_indices()
            .rev()
            .nth(STDERR_TAIL)
            .map_or(&*text, |(i, _)| &text[i..]);
        return Err(CliError::Input(format!(
            "`{}` failed ({status}): {}",
            shown(),
            tail.trim()
        )));
    }
    Ok(ChildRun {
        seconds,
        peak_bytes: peak,
    })
}
