//! `render`'s summary: the JSON record `--json` prints, and the report lines on the terminal.

use std::path::PathBuf;

use serde::Serialize;
use twopass_trace::{LightPlan, SplitPlan};

use crate::error::CliError;
use crate::pipeline::RenderMethod;
use crate::render_plan::RenderPlan;

#[derive(Debug, Serialize)]
pub(super) struct Summary {
    pub(super) scene: PathBuf,
    pub(super) method: RenderMethod,
    pub(super) preset: Option<String>,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) spp: u32,
    /// Pixels adaptive anti-aliasing rendered with `spp` (the others with its first pass).
    pub(super) refined_pixels: u64,
    pub(super) radiosity: Option<&'static str>,
    pub(super) radiosity_seconds: f64,
    pub(super) render_seconds: f64,
    pub(super) rays: u64,
    pub(super) shadow_rays: u64,
    pub(super) mrays_per_s: f64,
    pub(super) non_finite_samples: u64,
    /// Light paths of the light tracing pass (0 without one).
    pub(super) light_paths: u64,
    /// What the pilot measured when it planned the light paths (the path tracer's caustics).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) light_plan: Option<LightPlanSummary>,
    /// Continuations per camera sample of the path tracer's path splitting (1 without).
    pub(super) splits: u32,
    /// What the pilot measured when it planned the continuations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) split_plan: Option<SplitPlanSummary>,
    /// Mean of the final image over pixels, per channel, W/(m^2 sr).
    pub(super) mean: [f32; 3],
    /// The multi-layer EXR; none when `--output` names a PNG file.
    pub(super) exr: Option<PathBuf>,
    pub(super) png: Option<PathBuf>,
    pub(super) skipped: Vec<String>,
    /// The planner's measurements and choice (`--target-error`, `--time-budget`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) plan: Option<RenderPlan>,
    /// How the samples were spread by noise (a render without `--spp`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) allocation: Option<crate::allocation::Allocation>,
}

/// [`twopass_trace::LightPlan`] for the JSON summary.
#[derive(Debug, Serialize)]
pub(super) struct LightPlanSummary {
    /// Light paths per camera sample the pilot picked.
    paths_per_sample: f32,
    /// Summed relative variance of one camera sample per pixel over the image.
    camera_variance: f64,
    /// Summed relative variance of one light path's contribution over the image.
    light_variance: f64,
    /// Rays per camera sample.
    camera_rays: f64,
    /// Rays per light path.
    light_rays: f64,
}

/// [`twopass_trace::SplitPlan`] for the JSON summary.
#[derive(Debug, Serialize)]
pub(super) struct SplitPlanSummary {
    /// Continuations per camera sample the pilot picked.
    splits: u32,
    /// Relative variance of the prefix over the image, at the pilot's samples per pixel.
    prefix_variance: f64,
    /// Relative variance of the continuations over the image, at one per camera sample.
    continuation_variance: f64,
    /// Rays per camera sample outside the continuations.
    prefix_rays: f64,
    /// Rays per continuation.
    continuation_rays: f64,
}

impl From<&LightPlan> for LightPlanSummary {
    fn from(p: &LightPlan) -> Self {
        Self {
            paths_per_sample: p.paths_per_sample,
            camera_variance: p.camera_variance,
            light_variance: p.light_variance,
            camera_rays: p.camera_cost,
            light_rays: p.light_cost,
        }
    }
}

impl From<&SplitPlan> for SplitPlanSummary {
    fn from(p: &SplitPlan) -> Self {
        Self {
            splits: p.splits,
            prefix_variance: p.prefix_variance,
            continuation_variance: p.continuation_variance,
            prefix_rays: p.prefix_cost,
            continuation_rays: p.continuation_cost,
        }
    }
}

impl Summary {
    /// Prints the report lines; `adaptive` is the adaptive sampling's first pass, spp.
    pub(super) fn print(&self, adaptive: Option<u32>) -> Result<(), CliError> {
        let summary = self;
        for s in &summary.skipped {
            outln!("{s}");
        }
        if let Some(p) = &summary.plan {
            outln!("planned: {} (pilots {:.2} s)", p.reason, p.pilot_seconds);
        }
        if let Some(source) = summary.radiosity {
            outln!(
                "radiosity from {source} in {:.2} s",
                summary.radiosity_seconds
            );
        }
        let adaptive = adaptive.map_or(String::new(), |base| {
            format!(
                " (adaptive: {base} spp everywhere, {} pixels refined)",
                summary.refined_pixels
            )
        });
        let adaptive = summary.allocation.map_or(adaptive, |a| {
            format!(
                " on average (by noise: pilots of 2 x {} spp, {}-{} spp per pixel)",
                a.pilot_spp, a.min_spp, a.max_spp
            )
        });
        outln!(
            "{} {} x {} at {} spp{adaptive} in {:.2} s ({:.2} Mrays/s, {} non-finite samples dropped)",
            summary.method.name(),
            summary.width,
            summary.height,
            summary.spp,
            summary.render_seconds,
            summary.mrays_per_s,
            summary.non_finite_samples
        );
        match &summary.light_plan {
            Some(p) => outln!(
                "light tracing: {} paths for the caustics, {:.3} per camera sample as a pilot planned \
                 (relative variance {:.3e} per camera sample, {:.3e} per light path; {:.2} and {:.2} rays)",
                summary.light_paths,
                p.paths_per_sample,
                p.camera_variance,
                p.light_variance,
                p.camera_rays,
                p.light_rays
            ),
            None if summary.light_paths > 0 => {
                outln!(
                    "light tracing: {} paths for the caustics",
                    summary.light_paths
                )
            }
            None => {}
        }
        match &summary.split_plan {
            Some(p) => outln!(
                "path splitting: {} continuations per camera sample as a pilot planned \
                 (relative variance {:.3e} of the prefix, {:.3e} of one continuation; {:.2} and {:.2} rays)",
                p.splits,
                p.prefix_variance,
                p.continuation_variance,
                p.prefix_rays,
                p.continuation_rays
            ),
            None if summary.splits > 1 => {
                outln!(
                    "path splitting: {} continuations per camera sample",
                    summary.splits
                )
            }
            None => {}
        }
        if let Some(p) = &summary.exr {
            outln!("wrote {}", p.display());
        }
        if let Some(p) = &summary.png {
            outln!("wrote {}", p.display());
        }
        Ok(())
    }
}
