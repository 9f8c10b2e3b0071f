//! Camera samples per pixel chosen pixel by pixel ([`SampleBudget`]), for
//! [`crate::render_budgeted`]: from two pilot renders' noise, and as runs that continue each
//! pixel's sample sequence.

use twopass_image::Image;

/// Camera samples per pixel chosen pixel by pixel, for [`crate::render_budgeted`]: a converged
/// reference spends its samples where its own noise is, instead of the same number everywhere.
/// Each pixel's estimate is the mean of its own samples; only how many it gets differs. It is
/// unbiased when the counts do not depend on those samples (a reference whose pilots are
/// renders of their own); runs that continue the pilots' sequences keep the pilots' samples.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleBudget {
    width: u32,
    height: u32,
    /// Row-major, at least 1 each.
    samples: Vec<u32>,
    /// With [`SampleBudget::continuing`]: the index of every pixel's first sample.
    first: Option<u32>,
}

/// Half width (pixels) of the box filter [`SampleBudget::from_pilots`] smooths the pilots'
/// noise with: a pixel's own squared difference is one draw of its variance, its 5 x 5
/// neighbourhood's mean a steadier one.
pub const BUDGET_SMOOTHING: usize = 2;

/// The least share of the mean samples per pixel [`SampleBudget::from_pilots`] gives any pixel
/// (before rounding): a pixel whose pilots happened to agree still gets a quarter of the mean.
pub const BUDGET_FLOOR: f64 = 0.25;

impl SampleBudget {
    /// `spp` samples in every pixel of a `width` x `height` image.
    pub fn uniform(width: u32, height: u32, spp: u32) -> Self {
        Self {
            width,
            height,
            samples: vec![spp.max(1); width as usize * height as usize],
            first: None,
        }
    }

    /// About `spp` samples per pixel on average, each pixel's share proportional to the noise
    /// of the two pilot renders `a` and `b` there (independent, or two runs of one sequence,
    /// [`SampleBudget::continuing`]): the standard deviation of a
    /// pixel's sample, weighted as the relative error measures it, estimated by
    /// `sum_c (a - b)^2 / (m^2 + 0.01)` with `m` the pilots' mean (the metric's
    /// `REL_EPSILON`), smoothed over [`BUDGET_SMOOTHING`] pixels and square-rooted, floored at
    /// [`BUDGET_FLOOR`] of its mean. For a fixed total, samples proportional to the standard
    /// deviation minimise the summed variance (`sum sigma_i^2 / n_i` with `sum n_i` fixed).
    /// Every pixel gets at least one sample. `None` when the pilots differ in size from each
    /// other or are empty; a non-finite pixel counts as no noise.
    pub fn from_pilots(a: &Image, b: &Image, spp: u32) -> Option<Self> {
        let (width, height) = a.size();
        if b.size() != (width, height) || width == 0 || height == 0 {
            return None;
        }
        let (w, h) = (width as usize, height as usize);
        let var: Vec<f64> = a
            .pixels()
            .iter()
            .zip(b.pixels())
            .map(|(p, q)| {
                let (p, q) = (p.as_dvec3(), q.as_dvec3());
                let m = 0.5 * (p + q);
                let d = p - q;
                let v = (d * d / (m * m + 0.01)).element_sum();
                if v.is_finite() { v } else { 0.0 }
            })
            .collect();
        let r = BUDGET_SMOOTHING;
        let var = &var;
        let sigma: Vec<f64> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let (xs, ys) = (
                    x.saturating_sub(r)..(x + r + 1).min(w),
                    y.saturating_sub(r)..(y + r + 1).min(h),
                );
                let n = (xs.len() * ys.len()) as f64;
                let sum: f64 = ys
                    .flat_map(|y| xs.clone().map(move |x| var[y * w + x]))
                    .sum();
                (sum / n).sqrt()
            })
            .collect();
        let mean = sigma.iter().sum::<f64>() / sigma.len() as f64;
        let weights: Vec<f64> = if mean > 0.0 && mean.is_finite() {
            sigma.iter().map(|&s| s.max(BUDGET_FLOOR * mean)).collect()
        } else {
            vec![1.0; sigma.len()]
        };
        let total = weights.iter().sum::<f64>();
        let scale = f64::from(spp.max(1)) * weights.len() as f64 / total;
        let samples = weights
            .iter()
            .map(|&wt| (wt * scale).round().clamp(1.0, f64::from(u32::MAX)) as u32)
            .collect();
        Some(Self {
            width,
            height,
            samples,
            first: None,
        })
    }

    /// The same samples per pixel, taken as samples `first`, `first + 1`, ... of each pixel's
    /// sequence instead of from its start, so that renders of consecutive runs (`0..a`,
    /// `a..b`, ...) are together exactly the one stratified sequence of their sum: their
    /// sample-weighted mean is the estimate of a single render of all the samples. The camera
    /// samples are then the sampler's own low-discrepancy points over the pixel (a square grid
    /// over them would depend on the count), and the light tracing pass, if any, takes streams
    /// of its own for each `first`.
    pub fn continuing(self, first: u32) -> Self {
        Self {
            first: Some(first),
            ..self
        }
    }

    /// The index of every pixel's first sample, with [`SampleBudget::continuing`].
    pub fn first(&self) -> Option<u32> {
        self.first
    }

    /// Image size, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Samples of pixel (`x`, `y`).
    pub fn samples(&self, x: u32, y: u32) -> u32 {
        self.samples[y as usize * self.width as usize + x as usize]
    }

    /// Samples of the whole image.
    pub fn total(&self) -> u64 {
        self.samples.iter().map(|&n| u64::from(n)).sum()
    }

    /// Fewest and most samples of any pixel.
    pub fn range(&self) -> (u32, u32) {
        self.samples
            .iter()
            .fold((u32::MAX, 0), |(lo, hi), &n| (lo.min(n), hi.max(n)))
    }
}
