//! Peak resident memory, measured per bench row (Linux; `None` elsewhere).

/// Peak resident memory of this process since the last [`reset_peak_memory`], bytes (Linux:
/// VmHWM of /proc/self/status; `None` elsewhere).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Resets the peak resident memory to the current one (Linux `clear_refs` 5), so each bench
/// row reports its own peak.
pub fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Bytes as MiB.
pub fn mib(bytes: Option<u64>) -> Option<f64> {
    bytes.map(|b| b as f64 / (1024.0 * 1024.0))
}

/// A peak memory figure for a table: whole MiB, or n/a where the platform does not say.
pub fn fmt_mib(m: Option<f64>) -> String {
    m.map_or_else(|| "n/a".to_owned(), |m| format!("{m:.0}"))
}
