//! How many light paths a render's light tracing pass traces per camera sample, when its
//! settings leave it to the render ([`LightPaths::Planned`]).
//!
//! The render's two passes are independent estimators whose images add: the camera pass with
//! `n` samples per pixel, of error `S_cam / n`, and the light tracing pass with `N = r n P`
//! paths (`P` pixels, `r` light paths per camera sample), of error `S_L / N`. Their costs are
//! `c_cam` per camera sample and `c_L` per light path. The product of error and time, whose
//! inverse is the render's efficiency, is `(S_cam + S_L / (r P)) (c_cam + r c_L) P`, least at
//!
//! `r* = sqrt((S_L / P) c_cam / (S_cam c_L))`,
//!
//! the same at every sample count. A one-per-sample pass spends half the time of a scene
//! whose caustics are a small part of its noise on them (the glass sphere of the Cornell
//! spheres, the chrome room of `bench bakes`), and too little on a room that only light
//! through glass reaches.
//!
//! **The pilot.** The errors are measured as the image metric weighs them: the relative
//! squared error `sum_c (x - r)^2 / (r^2 + 0.01)`, `r` the pixel's value (the planner's and the
//! benchmarks' metric, [`crate::budget::SampleBudget::from_pilots`]).
//! - `S_cam`: [`PILOT_SAMPLES`] camera samples at every pixel of a grid of step `g` (the pilot
//!   takes about 1/64 of the render's camera samples, `g` from 2 to 32), their per-channel
//!   sample variance summed over the grid and scaled to the image's pixels.
//! - `S_L`: as many light paths as the camera pilot has samples (at least one chunk of the
//!   pass), the per-pixel variance of one path's contribution (its second moment less the
//!   square of its mean) summed over the image.
//! - `r`, the weight's pixel value, for the pixels of a grid point's cell: the larger of the
//!   median of that point's camera samples and the median of the 3 x 3 grid points' means
//!   around it, plus the light pilot's mean over the cell. A point's own mean would weigh a
//!   rare bright sample down by the value it gave, and miss the noise that dominates.
//! - `c_cam`, `c_L`: rays (closest-hit and shadow) per sample and per path, counted, not timed,
//!   so that the plan, and the image, are the same on any thread count and in every process
//!   of a split render.
//!
//! The pilot's own samples and paths take streams apart from the render's and are not part of
//! the image (nor of its ray counts): the counts that depend on them stay independent of the
//! estimate, which stays unbiased. The pick is clamped to [`PLANNED_RANGE`]: a pilot that saw
//! no caustic still leaves the pass its floor.
//!
//! **Limits.** `S_cam` is the variance of independent samples; a pixel's stratified samples do
//! better, more so the more of them there are, so the plan leans to fewer light paths than the
//! best (on the path tracer the plans measured are within a factor of 1.4 of the best fixed
//! ratio swept: docs/benchmarks.md, "The caustic pass's light paths"). An integrator whose noise
//! falls much faster than one over its samples (the gathered hybrid, whose gather rays are
//! stratified over a pixel's samples) is far from that model and keeps a fixed ratio.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::random::mix64;

use twopass_scene::{Camera, Scene};

use crate::counters::{RenderProgress, Tally};
use crate::film::Radiance;
use crate::light_tracing::{LightPaths, LightTracer, light_chunks};

/// The render's camera sample: `(seed, pixel, sample index, k, tally)` gives sample `s` of the
/// pixel under `seed`, in stratum `s` of a `k` x `k` grid over it, its rays counted in `tally`.
pub(crate) type CameraSample<'a> =
    &'a (dyn Fn(u64, (u32, u32), u32, u32, &mut Tally) -> Radiance + Sync);

/// Light paths per camera sample a plan picks at least and at most.
pub const PLANNED_RANGE: (f32, f32) = (1.0 / 64.0, 16.0);

/// Camera samples the pilot takes at each pixel of its grid (a 2 x 2 stratified set).
pub const PILOT_SAMPLES: u32 = 4;

/// Mixed into the render's seed for the pilot's streams, so they repeat none of the render's.
const PILOT_SEED_MIX: u64 = 0x7069_6c6f_745f_6c74;

/// The metric's offset (see the module documentation).
const REL_EPSILON: f64 = 0.01;

/// What a pilot measured, and the light paths per camera sample it picked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightPlan {
    /// Light paths per camera sample: the pick, within [`PLANNED_RANGE`].
    pub paths_per_sample: f32,
    /// `S_cam`: the variance of one camera sample per pixel, as squared relative error
    /// (dimensionless), summed over the image's pixels and channels.
    pub camera_variance: f64,
    /// `S_L`: the variance of one light path's contribution, as squared relative error
    /// (dimensionless), summed over the image's pixels and channels.
    pub light_variance: f64,
    /// Rays (closest-hit and shadow) per camera sample.
    pub camera_cost: f64,
    /// Rays per light path.
    pub light_cost: f64,
}

/// The light paths per camera sample of `tracer`'s pass in a render of `scene` through
/// `camera` whose camera pass (`sample`) takes `spp` samples per pixel on average: its
/// [`LightPaths::PerSample`], or the plan's pick ([`plan`]) with [`LightPaths::Planned`].
pub(crate) fn per_sample(
    (scene, camera): (&Scene, &Camera),
    sample: CameraSample<'_>,
    tracer: &LightTracer,
    seed: u64,
    spp: f64,
) -> (f32, Option<LightPlan>) {
    match tracer.settings().paths {
        LightPaths::PerSample(r) => (r, None),
        LightPaths::Planned => {
            let p = plan((scene, camera), sample, tracer, seed, spp);
            (p.paths_per_sample, Some(p))
        }
    }
}

/// The pilot step: about 1/64 of the render's `spp` samples per pixel, on a grid of at least
/// 256 points where the image has them.
fn grid_step(width: u32, height: u32, spp: f64) -> u32 {
    let pixels = f64::from(width) * f64::from(height);
    let step = (16.0 / spp.max(1e-3).sqrt()).round().clamp(2.0, 32.0);
    let most = (pixels / 256.0).sqrt().floor().max(1.0);
    step.min(most) as u32
}

/// Measures both passes of a render (see the module documentation) and picks the light paths
/// per camera sample that give the least error for the time.
pub(crate) fn plan(
    (scene, camera): (&Scene, &Camera),
    sample: CameraSample<'_>,
    tracer: &LightTracer,
    seed: u64,
    spp: f64,
) -> LightPlan {
    let (width, height) = (camera.width, camera.height);
    let step = grid_step(width, height, spp);
    let (gw, gh) = (width.div_ceil(step), height.div_ceil(step));
    let seed = mix64(seed ^ PILOT_SEED_MIX);

    // Camera pilot: each grid point's mean and per-channel sample variance, row by row.
    let rows: Vec<(Vec<Moments>, Tally)> = (0..gh)
        .into_par_iter()
        .map(|gy| {
            let mut tally = Tally::default();
            let row = (0..gw)
                .map(|gx| {
                    let xy = (
                        (gx * step + step / 2).min(width - 1),
                        (gy * step + step / 2).min(height - 1),
                    );
                    moments(sample, seed, xy, &mut tally)
                })
                .collect();
            (row, tally)
        })
        .collect();
    let mut camera_tally = Tally::default();
    let mut grid = Vec::with_capacity((gw * gh) as usize);
    for (row, t) in rows {
        camera_tally.add(t);
        grid.extend(row);
    }

    // Light pilot: each pixel's first and second moments of one path's contribution.
    let paths = (u64::from(gw) * u64::from(gh) * u64::from(PILOT_SAMPLES)).max(4096);
    let (splats, light_tally) = tracer.trace_share(
        scene,
        camera,
        paths,
        seed,
        0..light_chunks(paths),
        &RenderProgress::new(),
        0,
    );
    let pixels = width as usize * height as usize;
    let mut first = vec![DVec3::ZERO; pixels];
    let mut second = vec![DVec3::ZERO; pixels];
    // A path's splats on one pixel (its layers, or vertices seen in the same pixel) come one
    // after another: their sum is the path's contribution there.
    let mut run: Option<(u32, DVec3)> = None;
    let mut close = |run: Option<(u32, DVec3)>| {
        if let Some((p, v)) = run
            && v.is_finite()
        {
            first[p as usize] += v;
            second[p as usize] += v * v;
        }
    };
    for &(pixel, _, value) in &splats {
        let v = value.as_dvec3();
        run = match run {
            Some((p, sum)) if p == pixel => Some((p, sum + v)),
            other => {
                close(other);
                Some((pixel, v))
            }
        };
    }
    close(run);

    // The light pilot's mean over each grid point's cell, for the weights.
    let n = paths as f64;
    let mut cell_light = vec![DVec3::ZERO; grid.len()];
    let cell = |x: u32, y: u32| ((y / step) * gw + x / step) as usize;
    for (i, f) in first.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        cell_light[cell(x, y)] += *f / n;
    }
    let value: Vec<DVec3> = (0..grid.len())
        .map(|c| {
            let (cx, cy) = (c as u32 % gw, c as u32 / gw);
            let area = f64::from(step.min(width - cx * step) * step.min(height - cy * step));
            grid[c].0 + cell_light[c] / area
        })
        .collect();
    // The weight's pixel value is robust to the pilot's own noise: a grid point whose few
    // samples hit a rare bright path would weigh that noise down by the value it gave, and
    // the sum would miss exactly the noise that dominates. So it is the larger of the median
    // of its own samples (high where most of them see something bright: an edge, a highlight)
    // and the median of the 3 x 3 grid points' means around it (high in a bright region).
    let weights: Vec<DVec3> = (0..grid.len())
        .map(|c| {
            let around = neighbourhood_median(&value, gw as usize, gh as usize, c);
            let own = grid[c].2 + (value[c] - grid[c].0);
            let m = around.max(own);
            DVec3::ONE / (m * m + REL_EPSILON)
        })
        .collect();

    let scale = pixels as f64 / grid.len() as f64;
    let camera_variance = grid
        .iter()
        .zip(&weights)
        .map(|((_, var, _), w)| (*var * *w).element_sum())
        .sum::<f64>()
        * scale;
    let light_variance = first
        .iter()
        .zip(&second)
        .enumerate()
        .map(|(i, (f, s))| {
            let mean = *f / n;
            let var = (*s / n - mean * mean).max(DVec3::ZERO);
            let (x, y) = (i as u32 % width, i as u32 / width);
            (var * weights[cell(x, y)]).element_sum()
        })
        .sum::<f64>();
    let camera_cost = (camera_tally.rays + camera_tally.shadow_rays) as f64
        / (grid.len() as f64 * f64::from(PILOT_SAMPLES));
    let light_cost = (light_tally.rays + light_tally.shadow_rays) as f64 / n;
    LightPlan {
        paths_per_sample: pick(
            camera_variance,
            light_variance,
            camera_cost,
            light_cost,
            pixels as f64,
        ),
        camera_variance,
        light_variance,
        camera_cost,
        light_cost,
    }
}

/// `r* = sqrt((S_L / P) c_cam / (S_cam c_L))` within [`PLANNED_RANGE`]: the floor when
/// neither pass showed noise, the top when only the light pass did.
fn pick(
    camera_variance: f64,
    light_variance: f64,
    camera_cost: f64,
    light_cost: f64,
    pixels: f64,
) -> f32 {
    let (lo, hi) = PLANNED_RANGE;
    let r = ((light_variance / pixels) * camera_cost / (camera_variance * light_cost)).sqrt();
    if r.is_nan() {
        lo
    } else {
        (r as f32).clamp(lo, hi)
    }
}

/// Per channel, the median of `values` (a `w` x `h` grid, row-major) over the 3 x 3 points
/// around point `i` (fewer at the grid's edges; the upper median of an even count).
pub(crate) fn neighbourhood_median(values: &[DVec3], w: usize, h: usize, i: usize) -> DVec3 {
    let (x, y) = (i % w, i / w);
    let mut around = [[0.0f64; 9]; 3];
    let mut n = 0;
    for yy in y.saturating_sub(1)..(y + 2).min(h) {
        for xx in x.saturating_sub(1)..(x + 2).min(w) {
            let v = values[yy * w + xx];
            for (c, a) in around.iter_mut().enumerate() {
                a[n] = v[c];
            }
            n += 1;
        }
    }
    let median = |a: &mut [f64]| {
        a.sort_by(f64::total_cmp);
        a[a.len() / 2]
    };
    let [r, g, b] = &mut around;
    DVec3::new(
        median(&mut r[..n]),
        median(&mut g[..n]),
        median(&mut b[..n]),
    )
}

/// Per channel, the mean, sample variance and median of a pilot pixel's camera samples.
type Moments = (DVec3, DVec3, DVec3);

/// The [`Moments`] of [`PILOT_SAMPLES`] camera samples of pixel `xy` (their totals over the
/// layers); non-finite samples left out.
fn moments(sample: CameraSample<'_>, seed: u64, xy: (u32, u32), tally: &mut Tally) -> Moments {
    let k = PILOT_SAMPLES.isqrt();
    let values: Vec<DVec3> = (0..PILOT_SAMPLES)
        .map(|s| sample(seed, xy, s, k, tally).total().as_dvec3())
        .filter(|v| v.is_finite())
        .collect();
    if values.len() < 2 {
        let v = values.first().copied().unwrap_or(DVec3::ZERO);
        return (v, DVec3::ZERO, v);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<DVec3>() / n;
    let var = values
        .iter()
        .map(|v| (*v - mean) * (*v - mean))
        .sum::<DVec3>()
        / (n - 1.0);
    let median = DVec3::from_array(std::array::from_fn(|c| {
        let mut x: Vec<f64> = values.iter().map(|v| v[c]).collect();
        x.sort_by(f64::total_cmp);
        let h = x.len() / 2;
        if x.len().is_multiple_of(2) {
            0.5 * (x[h - 1] + x[h])
        } else {
            x[h]
        }
    }));
    (mean, var, median)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pick_is_the_square_root_rule_within_its_range() {
        // S_L / P = 0.04, c_cam = 1, S_cam = 1, c_L = 1: r* = 0.2.
        let r = pick(1.0, 0.04 * 100.0, 1.0, 1.0, 100.0);
        assert!((r - 0.2).abs() < 1e-6, "{r}");
        // Light paths four times as costly: half as many.
        let r = pick(1.0, 4.0, 1.0, 4.0, 100.0);
        assert!((r - 0.1).abs() < 1e-6, "{r}");
        assert_eq!(pick(1.0, 0.0, 1.0, 1.0, 100.0), PLANNED_RANGE.0);
        assert_eq!(pick(0.0, 1.0, 1.0, 1.0, 100.0), PLANNED_RANGE.1);
        assert_eq!(pick(0.0, 0.0, 1.0, 1.0, 100.0), PLANNED_RANGE.0);
        assert_eq!(pick(1.0, 1.0, 1.0, 0.0, 100.0), PLANNED_RANGE.1);
    }

    #[test]
    fn the_pilot_takes_about_a_64th_of_the_samples() {
        // 256 x 256 at 16 spp: a grid of step 4, 4096 points of 4 samples.
        assert_eq!(grid_step(256, 256, 16.0), 4);
        assert_eq!(grid_step(256, 256, 256.0), 2);
        assert_eq!(grid_step(1024, 1024, 1.0), 16);
        // A small image keeps 256 points where it can.
        assert_eq!(grid_step(64, 64, 1.0), 4);
        assert_eq!(grid_step(8, 8, 1.0), 1);
    }
}
