//! What the sweep reports: one row per measured run, the time each method takes to reach each
//! target, the reference it was measured against; and the table printed on the terminal.

use std::path::PathBuf;

use serde::Serialize;

use super::reference::ReferenceKey;
use crate::error::CliError;
use crate::preset::Preset;

/// One measured run: a CSV row.
#[derive(Debug, Clone, Serialize)]
pub(super) struct SweepRow {
    pub(super) method: &'static str,
    /// The knob this run varies from the base setting.
    pub(super) knob: &'static str,
    pub(super) spp: u32,
    /// First-pass samples per pixel of adaptive anti-aliasing (empty: `spp` everywhere).
    pub(super) adaptive_aa: Option<u32>,
    pub(super) depth: u32,
    pub(super) shadow_grid: u32,
    /// Gather rays per camera sample (the gathered hybrid's; the others ignore it).
    pub(super) gather_rays: u32,
    /// Rays per point of the final gather over the element mesh (`radiosity-gathered`; empty
    /// for the solution as solved).
    pub(super) final_gather: Option<u32>,
    /// Radiosity settings (empty for Whitted and the path tracer).
    pub(super) element_size: Option<f32>,
    pub(super) unshot: Option<f64>,
    pub(super) visibility_min: Option<u32>,
    pub(super) visibility_max: Option<u32>,
    pub(super) adaptive: Option<bool>,
    pub(super) elements: Option<usize>,
    /// Unshot fraction the solve reached.
    pub(super) unshot_reached: Option<f64>,
    /// Wall-clock seconds of the radiosity solve (0 without one).
    pub(super) radiosity_seconds: f64,
    pub(super) render_seconds: f64,
    /// Solve plus render, seconds.
    pub(super) total_seconds: f64,
    /// Shadow rays of the solve.
    pub(super) radiosity_rays: u64,
    /// Camera and secondary rays of the render.
    pub(super) rays: u64,
    pub(super) shadow_rays: u64,
    /// Largest resident memory of the solve and the render, MiB.
    pub(super) peak_memory_mib: Option<f64>,
    pub(super) mae: f64,
    pub(super) rmse: f64,
    pub(super) rel_rmse: f64,
    pub(super) ssim: f64,
    /// On the Pareto front of all runs.
    pub(super) pareto: bool,
    /// On the Pareto front of its own method.
    pub(super) method_pareto: bool,
}

/// Time each method takes to reach a target error.
#[derive(Debug, Serialize)]
pub(super) struct Reach {
    pub(super) method: &'static str,
    pub(super) target_rel_rmse: f64,
    /// Seconds, interpolated on log-log axes along the method's front; `None`: not reached.
    pub(super) seconds: Option<f64>,
    /// `false` when even the cheapest run was below the target (the time is an upper bound).
    pub(super) interpolated: bool,
    /// `seconds` over the reference path tracer's, when both reached it.
    pub(super) ratio_to_path_tracer: Option<f64>,
}

/// The converged reference the runs were measured against.
#[derive(Debug, Serialize)]
pub(super) struct ReferenceInfo {
    pub(super) exr: PathBuf,
    pub(super) settings: ReferenceKey,
    pub(super) render_seconds: f64,
    pub(super) cached: bool,
    pub(super) noise_rel_rmse: f64,
}

/// The JSON report: the setting, the reference, every row, the reach table and the presets.
#[derive(Debug, Serialize)]
pub(super) struct TradeoffReport {
    pub(super) scene: PathBuf,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) threads: usize,
    pub(super) seed: u64,
    pub(super) reference: ReferenceInfo,
    pub(super) skipped: Vec<String>,
    pub(super) rows: Vec<SweepRow>,
    pub(super) reach: Vec<Reach>,
    pub(super) presets: Vec<Preset>,
    pub(super) csv: PathBuf,
    pub(super) plot: PathBuf,
    pub(super) presets_file: PathBuf,
}

/// Prints the table of runs, the time to reach each target and the presets.
pub(super) fn print_report(r: &TradeoffReport) -> Result<(), CliError> {
    for s in &r.skipped {
        outln!("skipped {s}");
    }
    outln!(
        "{}: {} x {}, {} threads; reference {} spp ({:.1} s{}), its noise {:.2} %",
        r.scene.display(),
        r.width,
        r.height,
        r.threads,
        r.reference.settings.spp,
        r.reference.render_seconds,
        if r.reference.cached { ", cached" } else { "" },
        100.0 * r.reference.noise_rel_rmse
    );
    outln!(
        "{:<14} {:<16} {:>5} {:>4} {:>4} {:>9} {:>8} {:>8} {:>9} {:>9} {:>9} {:>7}",
        "method",
        "knob",
        "spp",
        "grid",
        "dep",
        "elem size",
        "elements",
        "unshot",
        "solve s",
        "total s",
        "rel RMSE",
        "peak MiB"
    );
    for row in &r.rows {
        let opt = |x: Option<String>| x.unwrap_or_else(|| "-".to_owned());
        outln!(
            "{:<14} {:<16} {:>5} {:>4} {:>4} {:>9} {:>8} {:>8} {:>9.3} {:>9.3} {:>8.2}%{} {:>7}",
            row.method,
            row.knob,
            row.spp,
            row.shadow_grid,
            row.depth,
            opt(row.element_size.map(|e| format!("{e:.1}"))),
            opt(row.elements.map(|e| e.to_string())),
            opt(row.unshot.map(|u| format!("{u:.0e}"))),
            row.radiosity_seconds,
            row.total_seconds,
            100.0 * row.rel_rmse,
            if row.pareto { "*" } else { " " },
            opt(row.peak_memory_mib.map(|m| format!("{m:.0}"))),
        );
    }
    outln!("* on the Pareto front of all methods");
    for reach in &r.reach {
        outln!(
            "{:<14} reaches {:>5.2} % in {}{}",
            reach.method,
            100.0 * reach.target_rel_rmse,
            reach.seconds.map_or_else(
                || "(not reached)".to_owned(),
                |s| format!("{}{s:.3} s", if reach.interpolated { "" } else { "<= " })
            ),
            reach
                .ratio_to_path_tracer
                .map_or_else(String::new, |x| format!(
                    ", {x:.3} x the path tracer's time"
                ))
        );
    }
    for p in &r.presets {
        outln!(
            "preset {:<8} target {:>5.2} %{}: {} at {} spp{}, grid {}, depth {}{}{} -> {:.2} % in {:.3} s",
            p.name,
            100.0 * p.target_rel_rmse,
            if p.reached { "" } else { " (not reached)" },
            p.method.name(),
            p.render.spp,
            p.render
                .adaptive
                .map_or_else(String::new, |b| format!(" (adaptive from {b})")),
            p.render.shadow_grid,
            p.render.depth,
            if p.method == crate::pipeline::RenderMethod::Hybrid {
                format!(", gather rays {}", p.render.gather_rays)
            } else {
                String::new()
            },
            p.radiosity.map_or_else(String::new, |k| format!(
                ", elements {:.1}, unshot {:.0e}, visibility {}-{}, adaptive {}",
                k.element_size, k.unshot, k.visibility_min, k.visibility_max, k.adaptive
            )),
            100.0 * p.measured_rel_rmse,
            p.measured_seconds
        );
    }
    outln!(
        "wrote {}, {}, {} and the JSON beside them",
        r.csv.display(),
        r.plot.display(),
        r.presets_file.display()
    );
    Ok(())
}
