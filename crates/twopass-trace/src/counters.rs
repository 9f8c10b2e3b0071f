//! The counters the passes share: the rays one camera sample traces ([`Tally`]) and a
//! render's progress ([`RenderProgress`]), which another thread may read while it runs.

use std::sync::atomic::{AtomicU64, Ordering};

/// Ray counts of one camera sample, summed into the render statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Closest-hit queries (camera, reflection, refraction and path rays).
    pub rays: u64,
    /// Occlusion queries (shadow rays).
    pub shadow_rays: u64,
}

impl Tally {
    /// Adds another tally.
    pub fn add(&mut self, other: Tally) {
        self.rays += other.rays;
        self.shadow_rays += other.shadow_rays;
    }
}

/// Progress of a render, readable from any thread while it runs (for a progress bar).
#[derive(Debug, Default)]
pub struct RenderProgress {
    done: AtomicU64,
    total: AtomicU64,
}

impl RenderProgress {
    /// A counter at zero.
    pub fn new() -> Self {
        Self::default()
    }

    /// Work finished so far, in pixels (a light tracing pass counts as many units as the
    /// image has pixels).
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Work of the whole render, in pixels (twice the image's pixels when the integrator adds
    /// a light tracing pass; 0 before it starts).
    pub fn total(&self) -> u64 {
        self.total.load(Ordering::Relaxed)
    }

    /// Starts a render of `total` units of work: nothing done yet.
    pub(crate) fn start(&self, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    /// Adds `units` to the work done.
    pub(crate) fn add_done(&self, units: u64) {
        self.done.fetch_add(units, Ordering::Relaxed);
    }

    /// Fraction finished, in [0, 1] (0 before the render starts).
    pub fn fraction(&self) -> f64 {
        let t = self.total();
        if t == 0 {
            0.0
        } else {
            self.done() as f64 / t as f64
        }
    }
}
