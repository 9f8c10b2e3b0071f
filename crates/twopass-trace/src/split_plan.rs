//! How many continuations the path tracer traces from a camera path's first diffuse or glossy
//! vertex (path splitting), when its settings leave it to the render ([`PathSplits::Planned`]).
//!
//! A camera sample of the path tracer is a prefix (the camera ray, any mirror or glass bounces
//! before the first diffuse or glossy vertex, and that vertex's light sample) and, from that
//! vertex on, `N` continuations, each a path of its own weighted `1 / N`. The image's error at
//! `n` samples per pixel is `A + B / N` (`A` the prefix's share, with the variation of what
//! the continuations expect from where the prefix ended; `B` the continuations' own at one per
//! sample) and its cost `n (c1 + N c2)` (`c1` the prefix's rays, `c2` a continuation's). Their
//! product, whose inverse is the render's efficiency, is least at
//!
//! `N* = sqrt(c1 B / (c2 A))`,
//!
//! at most [`MAX_SPLITS`]. In a closed room the indirect light is nearly all of the noise, and
//! splitting pays although a continuation costs more than the prefix: a pixel's continuations
//! are one Sobol sequence over all its samples ([`crate::Sampler::fork`]), stratified `n N`
//! ways. Where much of the noise is in the prefix (many lights sampled one at a time, mirrors
//! and glass seen first) it does not, and the plan keeps one.
//!
//! **The pilot.** Stratification is much of the gain, so the pilot measures the errors as the
//! render will have them: at each point of a pixel grid of about [`PILOT_POINTS`] points, two
//! independent runs of the render's `n` samples per pixel (at most [`PILOT_MOST_SAMPLES`])
//! with one continuation each and two with [`PILOT_SPLITS`] (`K`). A pair's squared difference
//! over two is its error at `n` samples; `V(1) = A + B` and `V(K) = A + B / K` give `A` and
//! `B`. The split runs take the streams of the unsplit ones, so each shares its prefixes with
//! one of them and the prefix's noise, the same in both, falls out of the difference (common
//! random numbers). The errors are weighed as the image metric weighs them, the relative
//! squared error `sum_c (x - r)^2 / (r^2 + 0.01)`, `r` the larger of the median of the point's
//! four runs and the median of the 3 x 3 points' means around it (as [`crate::light_plan`]'s
//! weights). The points' errors are heavy-tailed (a rare bright path in one run), so the points
//! in the largest [`TRIMMED`] of either error are left out: a few fireflies must not decide the
//! plan. `N*` from `A` one standard error (over the points) higher and `B` one lower, and from
//! both the other way, bound the counts the pilot cannot tell apart; the pick is
//! [`UNDECIDED_SPLITS`] within those bounds, the nearer bound outside them. So a scene whose
//! continuations bring nothing (a plane under a lamp, a room lit through glass only) keeps one,
//! a scene whose continuations clearly carry the noise (a sunlit yard) splits four ways, and a
//! scene the pilot sees noisily, two. `c1` and `c2` are rays (closest-hit and shadow) per
//! camera sample, counted, not timed, so that the plan, and the image, are the same on any
//! thread count and in every process of a split render. The pilot's streams are its own, and
//! its samples are not part of the image (nor of its ray counts).
//!
//! **Limits.** `A + B / N` is a secant through the two measured counts; stratified, the
//! continuations lose error faster than `1 / N` up to a few and more slowly after, hence the
//! cap. The estimate of `A` is a small difference of two noisy errors, so on most scenes the
//! pick is the undecided 2 where a sweep of fixed counts found 4-8 best. The pilot costs
//! `2 (2 c1 + (K + 1) c2) n` rays at each point: measured, 9-12 % of a 16-spp render that
//! keeps one continuation, 3 % or less at 64 spp (docs/benchmarks.md, "Path splitting").

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::random::mix64;
use twopass_scene::Camera;

use crate::counters::Tally;
use crate::film::Radiance;
use crate::light_plan::neighbourhood_median;

/// The render's camera sample with a given number of continuations: `(seed, pixel, sample
/// index, k, splits, tally)` gives sample `s` of the pixel under `seed`, in stratum `s` of a
/// `k` x `k` grid over it, its rays counted in `tally`.
pub(crate) type SplitSample<'a> =
    &'a (dyn Fn(u64, (u32, u32), u32, u32, u32, &mut Tally) -> Radiance + Sync);

/// Continuations per camera sample a plan picks at most.
pub const MAX_SPLITS: u32 = 4;

/// Continuations of the pilot's split runs (`K` in the module documentation).
pub const PILOT_SPLITS: u32 = 4;

/// Grid points the pilot measures, about (every pixel of a smaller image).
pub const PILOT_POINTS: u32 = 512;

/// Samples per pixel of each of the pilot's runs, at most (the render's, when fewer).
pub const PILOT_MOST_SAMPLES: u32 = 8;

/// Continuations per camera sample where the pilot cannot tell which count pays best: a
/// count that measured close to the best on every scene tried (docs/benchmarks.md, "Path
/// splitting").
pub const UNDECIDED_SPLITS: u32 = 2;

/// The share of the points with the largest errors that the estimate leaves out.
pub const TRIMMED: f64 = 0.05;

/// Mixed into the render's seed for the pilot's streams, so they repeat none of the render's.
const PILOT_SEED_MIX: u64 = 0x7370_6c69_745f_706c;

/// The metric's offset (see the module documentation).
const REL_EPSILON: f64 = 0.01;

/// How many continuations the path tracer traces from each camera path's first diffuse or
/// glossy vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathSplits {
    /// This many (at least 1; 1 is plain path tracing).
    Fixed(u32),
    /// As many as a pilot measures to give the least error for the time (the module
    /// documentation), decided anew by each render.
    Planned,
}

/// What a pilot measured, and the continuations it picked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitPlan {
    /// Continuations per camera sample: the pick, from 1 to [`MAX_SPLITS`].
    pub splits: u32,
    /// `A`: the prefix's share of the error at the pilot's samples per pixel, as squared
    /// relative error (dimensionless) summed over the channels: the mean over the pilot's
    /// points (those kept, see the module documentation) times the image's pixels.
    pub prefix_variance: f64,
    /// `B`: the continuations' share at one continuation per camera sample, in the same unit.
    pub continuation_variance: f64,
    /// `c1`: rays (closest-hit and shadow) per camera sample outside the continuations.
    pub prefix_cost: f64,
    /// `c2`: rays per continuation.
    pub continuation_cost: f64,
}

/// The grid step that gives about [`PILOT_POINTS`] points over a `width` x `height` image.
fn grid_step(width: u32, height: u32) -> u32 {
    let pixels = f64::from(width) * f64::from(height);
    ((pixels / f64::from(PILOT_POINTS)).sqrt().round() as u32).max(1)
}

/// Measures a render of `spp` samples per pixel on average through `camera` (see the module
/// documentation) and picks the continuations per camera sample that give the least error for
/// the time. `sample` is the render's camera sample with the continuations it is given.
pub(crate) fn plan(camera: &Camera, sample: SplitSample<'_>, seed: u64, spp: f64) -> SplitPlan {
    let (width, height) = (camera.width, camera.height);
    let step = grid_step(width, height);
    let (gw, gh) = (width.div_ceil(step), height.div_ceil(step));
    let n = (spp.round().min(f64::from(PILOT_MOST_SAMPLES)) as u32).max(1);
    let k = n.isqrt();
    let base = mix64(seed ^ PILOT_SEED_MIX);
    let seeds: [u64; 2] = std::array::from_fn(|i| mix64(base.wrapping_add(i as u64 + 1)));

    // Per grid point: the four runs' pixel means (one continuation under each seed, then K
    // under each), and the rays of the unsplit and the split runs.
    let points: Vec<([DVec3; 4], [Tally; 2])> = (0..gw * gh)
        .into_par_iter()
        .map(|i| {
            let xy = (
                ((i % gw) * step + step / 2).min(width - 1),
                ((i / gw) * step + step / 2).min(height - 1),
            );
            let mut tallies = [Tally::default(); 2];
            let runs = std::array::from_fn(|r| {
                let splits = if r < 2 { 1 } else { PILOT_SPLITS };
                let mut sum = DVec3::ZERO;
                let mut finite = 0u32;
                for s in 0..n {
                    let v = sample(seeds[r % 2], xy, s, k, splits, &mut tallies[r / 2]);
                    let v = v.total().as_dvec3();
                    if v.is_finite() {
                        sum += v;
                        finite += 1;
                    }
                }
                sum / f64::from(finite.max(1))
            });
            (runs, tallies)
        })
        .collect();

    let means: Vec<DVec3> = points.iter().map(|(r, _)| (r[0] + r[1]) * 0.5).collect();
    let mut one = Vec::with_capacity(points.len());
    let mut split = Vec::with_capacity(points.len());
    let mut rays = [0u64; 2];
    for (i, (runs, tallies)) in points.iter().enumerate() {
        let around = neighbourhood_median(&means, gw as usize, gh as usize, i);
        let m = around.max(median4(runs));
        let weight = DVec3::ONE / (m * m + REL_EPSILON);
        let half_square = |a: DVec3, b: DVec3| ((a - b) * (a - b) * 0.5 * weight).element_sum();
        one.push(half_square(runs[0], runs[1]));
        split.push(half_square(runs[2], runs[3]));
        for (r, t) in rays.iter_mut().zip(tallies) {
            *r += t.rays + t.shadow_rays;
        }
    }
    let samples = 2.0 * points.len() as f64 * f64::from(n);
    let (c_one, c_split) = (rays[0] as f64 / samples, rays[1] as f64 / samples);
    let kf = f64::from(PILOT_SPLITS);
    let continuation_cost = (c_split - c_one) / (kf - 1.0);
    let prefix_cost = c_one - continuation_cost;
    // Each point's share of A and B, from its two errors; the points in the largest TRIMMED
    // of either error are left out.
    let (cut_one, cut_split) = (upper_cut(&one), upper_cut(&split));
    let (mut a, mut b) = (Mean::default(), Mean::default());
    for (&v1, &vk) in one.iter().zip(&split) {
        if v1 <= cut_one && vk <= cut_split {
            a.add((kf * vk - v1) / (kf - 1.0));
            b.add((v1 - vk) * kf / (kf - 1.0));
        }
    }
    let pixels = f64::from(width) * f64::from(height);
    // The measurement is noisy (a scene's noise is heavy-tailed, and a few hundred points
    // see it), so the pick is 2 where the measurement does not tell it apart from N*: within
    // one standard error of A and B each way, N* may be anywhere from `low` to `high`.
    let bound = |sign: f64| {
        pick(
            (a.mean() + sign * a.error()) * pixels,
            (b.mean() - sign * b.error()) * pixels,
            prefix_cost,
            continuation_cost,
        )
    };
    let (low, high) = (bound(1.0), bound(-1.0));
    SplitPlan {
        splits: UNDECIDED_SPLITS.clamp(low, high),
        prefix_variance: a.mean() * pixels,
        continuation_variance: b.mean() * pixels,
        prefix_cost,
        continuation_cost,
    }
}

/// The value above which lie the largest [`TRIMMED`] of `values` (+inf when that is none);
/// NaN counts as largest.
fn upper_cut(values: &[f64]) -> f64 {
    let drop = (values.len() as f64 * TRIMMED).floor() as usize;
    if drop == 0 {
        return f64::INFINITY;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() - drop - 1]
}

/// A mean of independent terms and its standard error.
#[derive(Debug, Default, Clone, Copy)]
struct Mean {
    sum: f64,
    squares: f64,
    count: f64,
}

impl Mean {
    fn add(&mut self, x: f64) {
        self.sum += x;
        self.squares += x * x;
        self.count += 1.0;
    }

    /// The mean (0 without terms).
    fn mean(&self) -> f64 {
        if self.count > 0.0 {
            self.sum / self.count
        } else {
            0.0
        }
    }

    /// The standard error of the mean (0 with fewer than two terms).
    fn error(&self) -> f64 {
        if self.count < 2.0 {
            return 0.0;
        }
        let mean = self.mean();
        let var = (self.squares - self.count * mean * mean) / (self.count - 1.0);
        (var.max(0.0) / self.count).sqrt()
    }
}

/// `N* = sqrt(c1 B / (c2 A))`, rounded, from 1 to [`MAX_SPLITS`]: 1 when the continuations
/// showed no noise of their own or cost nothing (no path reached a diffuse or glossy vertex),
/// the most when the prefix showed none.
fn pick(prefix_variance: f64, continuation_variance: f64, prefix_cost: f64, cost: f64) -> u32 {
    if !(continuation_variance > 0.0 && cost > 0.0) {
        return 1;
    }
    // No noise of its own in the prefix (or none measured: NaN).
    if prefix_variance.is_nan() || prefix_variance <= 0.0 {
        return MAX_SPLITS;
    }
    let n = (prefix_cost.max(0.0) * continuation_variance / (cost * prefix_variance)).sqrt();
    if n.is_finite() {
        (n.round() as u32).clamp(1, MAX_SPLITS)
    } else {
        MAX_SPLITS
    }
}

/// Per channel, the median of four values (the mean of the middle two).
fn median4(v: &[DVec3; 4]) -> DVec3 {
    DVec3::from_array(std::array::from_fn(|c| {
        let mut x = v.map(|p| p[c]);
        x.sort_by(f64::total_cmp);
        0.5 * (x[1] + x[2])
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pick_is_the_square_root_rule_within_its_range() {
        // c1 = 1, B = 16, c2 = 1, A = 1: N* = 4.
        assert_eq!(pick(1.0, 16.0, 1.0, 1.0), 4);
        // Continuations four times as costly: half as many.
        assert_eq!(pick(1.0, 16.0, 1.0, 4.0), 2);
        // Rounded: sqrt(6.25) = 2.5 rounds to 3, sqrt(5) = 2.24 to 2.
        assert_eq!(pick(1.0, 6.25, 1.0, 1.0), 3);
        assert_eq!(pick(1.0, 5.0, 1.0, 1.0), 2);
        // No noise in the continuations, or no continuation traced: one.
        assert_eq!(pick(1.0, 0.0, 1.0, 1.0), 1);
        assert_eq!(pick(1.0, -0.5, 1.0, 1.0), 1);
        assert_eq!(pick(1.0, 1.0, 1.0, 0.0), 1);
        assert_eq!(pick(f64::NAN, f64::NAN, 1.0, 1.0), 1);
        // No noise in the prefix: the most.
        assert_eq!(pick(0.0, 1.0, 1.0, 1.0), MAX_SPLITS);
        assert_eq!(pick(-1.0, 1.0, 1.0, 1.0), MAX_SPLITS);
        assert_eq!(pick(1e-30, 1.0, 1.0, 1.0), MAX_SPLITS);
    }

    #[test]
    fn the_pilot_measures_about_512_points() {
        assert_eq!(grid_step(256, 256), 11);
        assert_eq!(grid_step(256, 192), 10);
        assert_eq!(grid_step(1024, 1024), 45);
        // A small image: every pixel.
        assert_eq!(grid_step(8, 8), 1);
    }

    #[test]
    fn the_cut_leaves_out_the_largest_twentieth() {
        // 39 ones and a firefly: floor(40 / 20) = 2 values above the cut, the firefly and a
        // one, so the cut is 1 and a value of 1 is kept.
        let mut v = vec![1.0; 39];
        v.push(1e9);
        assert_eq!(upper_cut(&v), 1.0);
        let v: Vec<f64> = (0..300).map(f64::from).collect();
        assert_eq!(upper_cut(&v), 284.0);
        // Fewer than 20 values: none is left out.
        assert_eq!(upper_cut(&[1.0, 3.0]), f64::INFINITY);
        let mut nan = vec![1.0; 20];
        nan[7] = f64::NAN;
        assert_eq!(upper_cut(&nan), 1.0);
    }

    #[test]
    fn the_mean_has_its_standard_error() {
        let mut m = Mean::default();
        assert_eq!((m.mean(), m.error()), (0.0, 0.0));
        for x in [1.0, 2.0, 3.0, 4.0] {
            m.add(x);
        }
        // Sample variance 5/3, over 4 terms: 5/12.
        assert_eq!(m.mean(), 2.5);
        assert!((m.error() - (5.0f64 / 12.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn the_median_of_four_is_the_mean_of_the_middle_two() {
        let v = [
            DVec3::new(1.0, 9.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(100.0, 3.0, 0.0),
            DVec3::new(3.0, 2.0, 4.0),
        ];
        assert_eq!(median4(&v), DVec3::new(2.5, 2.5, 0.0));
    }
}
