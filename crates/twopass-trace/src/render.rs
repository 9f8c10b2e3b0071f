//! The one render loop (ARCHITECTURE.md, "Architecture invariants"; pbrt's
//! `ImageTileIntegrator`): square tiles rendered in parallel with rayon, one random stream per
//! (seed, pixel, sample) so the image is bit-identical for any thread count, stratified
//! supersampling within each pixel (box filter), progress through an atomic counter that another
//! thread may read, and non-finite samples counted and dropped, never written to a layer.

use std::time::{Duration, Instant};

use glam::Vec2;
use rayon::prelude::*;
use smart_default::SmartDefault;
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance;
use twopass_scene::{Camera, CameraRays, Ray, Scene};

use crate::budget::SampleBudget;
use crate::counters::RenderProgress;
use crate::counters::Tally;
use crate::film::{LayerImages, Radiance};
use crate::integrator::{Integrator, SampleState};
use crate::light_plan::LightPlan;
use crate::light_tracing::{LightTracer, Splat, add_splats, finish_splats, light_chunks};
use crate::sampler::{Sampler, stratum};
use crate::split_plan::{PathSplits, SplitPlan};

/// Sampling settings of a render.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Camera samples per pixel (at least 1). The first floor(sqrt(n))^2 are stratified on a
    /// square grid over the pixel, the rest uniform over it.
    #[default(16)]
    pub samples_per_pixel: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Jitter the camera samples within their strata (`false`: stratum centres, and the pixel
    /// centre for the unstratified rest: regular supersampling, exactly reproducible geometry).
    #[default(true)]
    pub jitter: bool,
    /// Tile edge, pixels (at least 1): the unit of parallel work and of progress.
    #[default(16)]
    pub tile_size: u32,
    /// Adaptive anti-aliasing, or `None` for `samples_per_pixel` in every pixel.
    pub adaptive: Option<AdaptiveSampling>,
}

/// Adaptive anti-aliasing: images of the radiosity-based methods are smooth but at edges, so
/// every pixel first takes `base` samples, and only a pixel whose samples disagree, or whose
/// mean disagrees with a neighbour's, is rendered again with the full
/// [`RenderSettings::samples_per_pixel`] (its first estimate is then dropped, so each pixel's
/// value is a mean of one stratified set). Disagreement is a luminance contrast
/// `(max - min) / (max + min)`, free of the image's scale. Deterministic: a pixel's
/// refinement depends on the first pass of the whole image only.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSampling {
    /// Samples per pixel of the first pass (at least 1; a square number is stratified).
    #[default(4)]
    pub base: u32,
    /// Contrast in [0, 1] above which a pixel is refined: between the luminances of its own
    /// first-pass samples, or between its mean and any of its four neighbours' means.
    #[default(0.05)]
    pub contrast: f32,
}

/// Contrast `(max - min) / (max + min)` of two luminances (0 when both are 0).
fn contrast(lo: f32, hi: f32) -> f32 {
    let sum = hi + lo;
    if sum > 0.0 { (hi - lo) / sum } else { 0.0 }
}

/// What a render measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderStats {
    /// The integrator's name.
    pub method: &'static str,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Camera samples per pixel.
    pub samples_per_pixel: u32,
    /// Camera samples taken (with adaptive sampling, the first pass's and the refined
    /// pixels').
    pub samples: u64,
    /// Pixels adaptive sampling rendered again with the full samples per pixel (0 without).
    pub refined_pixels: u64,
    /// Samples with a NaN or infinite value in any layer: counted, left out of their pixel's
    /// mean (which is over the finite samples only), never written.
    pub non_finite: u64,
    /// Closest-hit rays traced (camera rays included).
    pub rays: u64,
    /// Shadow rays traced (with the light tracing pass's connections to the camera).
    pub shadow_rays: u64,
    /// Light paths of the integrator's light tracing pass (0 without one).
    pub light_paths: u64,
    /// What the pilot measured when the pass's light paths were planned
    /// ([`crate::LightPaths::Planned`]).
    pub light_plan: Option<LightPlan>,
    /// Continuations per camera sample from its first diffuse or glossy vertex (path
    /// splitting; 1 without).
    pub splits: u32,
    /// What the pilot measured when the continuations were planned
    /// ([`crate::PathSplits::Planned`]).
    pub split_plan: Option<SplitPlan>,
    /// Wall-clock time of the render.
    pub elapsed: Duration,
}

impl RenderStats {
    /// All rays (closest-hit and shadow) per second of wall-clock time.
    pub fn rays_per_second(&self) -> f64 {
        (self.rays + self.shadow_rays) as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// The result of a render: the layers (their sum is the image) and the statistics.
#[derive(Debug, Clone)]
pub struct RenderOutput {
    /// One linear RGB image per layer, radiance in W/(m^2 sr).
    pub layers: LayerImages,
    /// What the render measured.
    pub stats: RenderStats,
}

struct TileResult {
    x0: u32,
    y0: u32,
    w: u32,
    pixels: Vec<Radiance>,
    /// Per pixel, the contrast of its samples' luminances.
    spread: Vec<f32>,
    tally: Tally,
    non_finite: u64,
    samples: u64,
}

/// What every pixel estimate of one render shares.
struct Pass<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    /// The camera's ray directions, what they share made once.
    rays: CameraRays,
    integrator: &'a dyn Integrator,
    settings: &'a RenderSettings,
    /// Continuations per camera sample ([`SampleState::splits`]).
    splits: u32,
}

impl Pass<'_> {
    /// Camera sample `s` of pixel (`x`, `y`) under `seed`: in stratum `s` of a `k` x `k` grid
    /// over the pixel when `s < k * k`, anywhere in it otherwise. Its rays go to `tally`.
    fn sample(&self, seed: u64, xy: (u32, u32), s: u32, k: u32, tally: &mut Tally) -> Radiance {
        self.sample_split(seed, xy, (s, k), self.splits, tally)
    }

    /// [`Pass::sample`] with `splits` continuations.
    fn sample_split(
        &self,
        seed: u64,
        (x, y): (u32, u32),
        (s, k): (u32, u32),
        splits: u32,
        tally: &mut Tally,
    ) -> Radiance {
        let index = u64::from(y) * u64::from(self.camera.width) + u64::from(x);
        let mut sampler = Sampler::new(seed, index, u64::from(s));
        let u = if self.settings.jitter {
            sampler.next_2d()
        } else {
            Vec2::splat(0.5)
        };
        let offset = if s < k * k { stratum(s, k, u) } else { u };
        let pixel = Vec2::new(x as f32, y as f32) + offset;
        let ray = Ray::new(self.camera.position, self.rays.direction(pixel));
        let sample = SampleState {
            sampler: &mut sampler,
            tally,
            splits,
        };
        self.integrator.radiance(self.scene, &ray, sample)
    }

    /// The mean of `n` camera samples of pixel (`x`, `y`) (stratified on the largest square
    /// grid that fits, the rest uniform), and the contrast of their luminances. Non-finite
    /// samples are counted in `non_finite` and left out.
    fn pixel(
        &self,
        x: u32,
        y: u32,
        (first, n): (Option<u32>, u32),
        tally: &mut Tally,
        non_finite: &mut u64,
    ) -> (Radiance, f32) {
        // A run that continues a sequence places its samples by the sampler's own points.
        let k = if first.is_some() { 0 } else { n.isqrt() };
        let first = first.unwrap_or(0);
        let mut sum = Radiance::ZERO;
        let mut finite = 0u32;
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for s in first..first.saturating_add(n) {
            let l = self.sample(self.settings.seed, (x, y), s, k, tally);
            if l.is_finite() {
                sum += l;
                finite += 1;
                let y = luminance(l.total()).max(0.0);
                lo = lo.min(y);
                hi = hi.max(y);
            } else {
                *non_finite += 1;
            }
        }
        let mean = if finite > 0 {
            sum * (1.0 / finite as f32)
        } else {
            Radiance::ZERO
        };
        // A finite sum of finite samples can still overflow to infinity.
        if mean.is_finite() {
            (mean, if finite > 1 { contrast(lo, hi) } else { 0.0 })
        } else {
            *non_finite += u64::from(finite);
            (Radiance::ZERO, 0.0)
        }
    }

    /// Renders the pixels of tile (`x0`, `y0`) with `n(x, y)` samples each (those with 0 are
    /// left zero), from sample `first` of each pixel's sequence when given
    /// ([`SampleBudget::continuing`]).
    fn tile(
        &self,
        (x0, y0): (u32, u32),
        first: Option<u32>,
        n: impl Fn(u32, u32) -> u32,
    ) -> TileResult {
        let tile = self.settings.tile_size.max(1);
        let (w, h) = (
            tile.min(self.camera.width - x0),
            tile.min(self.camera.height - y0),
        );
        let mut pixels = Vec::with_capacity((w * h) as usize);
        let mut spread = Vec::with_capacity((w * h) as usize);
        let mut tally = Tally::default();
        let mut non_finite = 0;
        let mut samples = 0;
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                let n = n(x, y);
                let (p, c) = if n > 0 {
                    samples += u64::from(n);
                    self.pixel(x, y, (first, n), &mut tally, &mut non_finite)
                } else {
                    (Radiance::ZERO, 0.0)
                };
                pixels.push(p);
                spread.push(c);
            }
        }
        TileResult {
            x0,
            y0,
            w,
            pixels,
            spread,
            tally,
            non_finite,
            samples,
        }
    }
}

/// Which pixels adaptive sampling refines, given the first pass's image `first`: those whose
/// own samples' contrast, or whose mean's contrast with a 4-neighbour's mean, exceeds
/// `threshold`; row-major.
fn refine_mask(first: &[Rgb], spread: &[f32], width: usize, threshold: f32) -> Vec<bool> {
    let lum: Vec<f32> = first.iter().map(|p| luminance(*p).max(0.0)).collect();
    let height = lum.len() / width.max(1);
    (0..lum.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let differs = |j: usize| contrast(lum[i].min(lum[j]), lum[i].max(lum[j])) > threshold;
            spread[i] > threshold
                || (x > 0 && differs(i - 1))
                || (x + 1 < width && differs(i + 1))
                || (y > 0 && differs(i - width))
                || (y + 1 < height && differs(i + width))
        })
        .collect()
}

/// Renders `scene` as seen by `camera` (its resolution sets the image size) with `integrator`.
/// Runs on the current rayon pool; the result does not depend on its thread count.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    progress: &RenderProgress,
) -> RenderOutput {
    render_with(scene, camera, integrator, settings, None, progress)
}

/// [`render`] with each pixel's camera samples from `budget` (whose size must be the
/// camera's) instead of [`RenderSettings::samples_per_pixel`]; adaptive sampling does not
/// apply. A pixel given `n` samples gets exactly the estimate [`render`] gives it at `n`
/// samples per pixel; the light tracing pass, if any, traces as many light paths as the
/// budget has samples. `None` when the sizes differ.
pub fn render_budgeted(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: &SampleBudget,
    progress: &RenderProgress,
) -> Option<RenderOutput> {
    (budget.size() == (camera.width, camera.height))
        .then(|| render_with(scene, camera, integrator, settings, Some(budget), progress))
}

/// The square tiles of a `width` x `height` render with tiles of `tile` pixels (at least 1),
/// by their top-left corners in row-major order: the render loop's unit of work, and what
/// [`render_share`] splits among processes.
pub fn tile_origins(width: u32, height: u32, tile: u32) -> Vec<(u32, u32)> {
    let tile = tile.max(1);
    (0..height.div_ceil(tile))
        .flat_map(|ty| (0..width.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
        .collect()
}

/// The tiles one of several processes renders ([`render_share`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TileShare {
    /// Indices into [`tile_origins`] of the render's size and tile edge.
    pub tiles: std::ops::Range<usize>,
    /// Which run of the light tracing pass's chunks this share traces, `(i, n)`: the i-th
    /// (from 0) of `n` equal runs. A light path's splats land on any pixel, so the pass is
    /// split by its paths, not by tiles; every share of a split render takes one run.
    pub light: (u32, u32),
}

/// One share's run of the light tracing pass: its splats in path order.
#[derive(Debug, Clone)]
pub struct LightShare {
    /// Splats of the share's paths, in path order.
    pub splats: Vec<Splat>,
    /// Light paths of the whole pass (each share's splats are divided by it).
    pub paths: u64,
}

/// What one share of a render computed.
#[derive(Debug, Clone)]
pub struct ShareOutput {
    /// The camera pass, full size: the share's tiles hold exactly what [`render`] computes
    /// there before it adds the light tracing pass; every other pixel is zero.
    pub layers: LayerImages,
    /// The share's run of the light tracing pass, when the integrator has one;
    /// [`light_image`] over every share's, in share order, gives the pass's image.
    pub light: Option<LightShare>,
    /// What this share measured (its own samples, rays and time).
    pub stats: RenderStats,
}

/// Renders the tiles of `share` alone (see [`render`]): each pixel's value is bit for bit
/// what [`render`] gives it, because every random stream is keyed by (seed, pixel, sample).
/// `None` with adaptive sampling, whose refinement of a pixel depends on its neighbours' first
/// pass and so on the whole image.
pub fn render_share(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    share: &TileShare,
    progress: &RenderProgress,
) -> Option<ShareOutput> {
    if settings
        .adaptive
        .is_some_and(|a| a.base.max(1) < settings.samples_per_pixel)
    {
        return None;
    }
    let (out, light) = render_core(
        scene,
        camera,
        integrator,
        settings,
        None,
        Some(share),
        progress,
    );
    Some(ShareOutput {
        layers: out.layers,
        light,
        stats: out.stats,
    })
}

/// The light tracing pass's image from the splats of its shares (in share order: the order of
/// their chunks) and its number of paths: the sum [`render`] takes, bit for bit.
pub fn light_image<'a>(
    width: u32,
    height: u32,
    paths: u64,
    shares: impl IntoIterator<Item = &'a [Splat]>,
) -> LayerImages {
    let mut layers = LayerImages::new(width, height);
    let mut non_finite = 0;
    for splats in shares {
        add_splats(&mut layers, splats, &mut non_finite);
    }
    finish_splats(&mut layers, paths, &mut non_finite);
    layers
}

/// Adds the light tracing pass `light` to the camera pass `layers`, pixel by pixel: the one
/// sum [`render`] and the assembly of a split render both take, so both give the same bits.
pub fn add_light(layers: &mut LayerImages, light: &LayerImages) {
    for (img, add) in layers.images.iter_mut().zip(&light.images) {
        for (p, a) in img.pixels_mut().iter_mut().zip(add.pixels()) {
            *p += *a;
        }
    }
}

fn render_with(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: Option<&SampleBudget>,
    progress: &RenderProgress,
) -> RenderOutput {
    render_core(scene, camera, integrator, settings, budget, None, progress).0
}

/// The render loop; with a `share`, only its tiles and its run of the light tracing pass,
/// whose splats are returned apart instead of added.
fn render_core(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    budget: Option<&SampleBudget>,
    share: Option<&TileShare>,
    progress: &RenderProgress,
) -> (RenderOutput, Option<LightShare>) {
    let start = Instant::now();
    let (width, height) = (camera.width, camera.height);
    let spp = match budget {
        Some(b) => b
            .total()
            .div_ceil(u64::from(width) * u64::from(height))
            .max(1) as u32,
        None => settings.samples_per_pixel.max(1),
    };
    let tile = settings.tile_size.max(1);
    let pixels = u64::from(width) * u64::from(height);
    let light = integrator.light_tracer();
    let adaptive = settings
        .adaptive
        .map(|a| AdaptiveSampling {
            base: a.base.clamp(1, spp),
            ..a
        })
        .filter(|a| a.base < spp && budget.is_none());
    let all_tiles = tile_origins(width, height, tile);
    let tiles = match share {
        Some(s) => &all_tiles[s.tiles.start.min(all_tiles.len())..s.tiles.end.min(all_tiles.len())],
        None => &all_tiles[..],
    };
    let share_pixels: u64 = tiles
        .iter()
        .map(|&(x, y)| u64::from(tile.min(width - x)) * u64::from(tile.min(height - y)))
        .sum();
    let passes = 1 + u64::from(adaptive.is_some());
    progress.start(passes * share_pixels + u64::from(light.is_some()) * pixels);

    let mut pass = Pass {
        scene,
        camera,
        rays: camera.rays(),
        integrator,
        settings,
        splits: 1,
    };
    let mut split_plan = None;
    match integrator.path_splits() {
        None => {}
        Some(PathSplits::Fixed(n)) => pass.splits = n.max(1),
        Some(PathSplits::Planned) => {
            let sample = |seed, xy, s, k, splits, tally: &mut Tally| {
                pass.sample_split(seed, xy, (s, k), splits, tally)
            };
            let average = match budget {
                Some(b) => b.total() as f64 / pixels as f64,
                None => f64::from(spp),
            };
            let plan = crate::split_plan::plan(camera, &sample, settings.seed, average);
            pass.splits = plan.splits;
            split_plan = Some(plan);
        }
    }
    let pass = pass;
    let run = |n: &(dyn Fn(u32, u32) -> u32 + Sync)| -> Vec<TileResult> {
        tiles
            .par_iter()
            .map(|&origin| {
                let r = pass.tile(origin, budget.and_then(SampleBudget::first), n);
                progress.add_done(r.pixels.len() as u64);
                r
            })
            .collect()
    };

    let mut layers = LayerImages::new(width, height);
    let mut tally = Tally::default();
    let mut non_finite = 0;
    let mut samples = 0;
    let mut spread = vec![0.0f32; pixels as usize];
    let mut gather = |results: Vec<TileResult>,
                      layers: &mut LayerImages,
                      spread: &mut [f32],
                      keep: &dyn Fn(usize) -> bool| {
        for t in &results {
            tally.add(t.tally);
            non_finite += t.non_finite;
            samples += t.samples;
            for (i, p) in t.pixels.iter().enumerate() {
                let (x, y) = (t.x0 + i as u32 % t.w, t.y0 + i as u32 / t.w);
                let at = y as usize * width as usize + x as usize;
                if !keep(at) {
                    continue;
                }
                spread[at] = t.spread[i];
                for (img, v) in layers.images.iter_mut().zip(p.layers) {
                    img.pixels_mut()[at] = v;
                }
            }
        }
    };
    let first = match (budget, adaptive) {
        (Some(b), _) => run(&|x, y| b.samples(x, y)),
        (None, Some(a)) => run(&|_, _| a.base),
        (None, None) => run(&|_, _| spp),
    };
    gather(first, &mut layers, &mut spread, &|_| true);
    let mut refined_pixels = 0;
    if let Some(a) = adaptive {
        let first_image = layers.composite();
        let refine = refine_mask(first_image.pixels(), &spread, width as usize, a.contrast);
        refined_pixels = refine.iter().filter(|&&r| r).count() as u64;
        let at = |x: u32, y: u32| y as usize * width as usize + x as usize;
        let second = run(&|x, y| if refine[at(x, y)] { spp } else { 0 });
        gather(second, &mut layers, &mut spread, &|i| refine[i]);
    }
    let mut light_paths = 0;
    let mut apart = None;
    // A run continuing a sequence traces light paths of its own: the same seed would repeat
    // the earlier runs' paths.
    let light_seed = match budget.and_then(SampleBudget::first) {
        Some(f) if f > 0 => twopass_brdf::random::mix64(
            settings.seed ^ u64::from(f).wrapping_mul(0x9e37_79b9_7f4a_7c15),
        ),
        _ => settings.seed,
    };
    let mut light_plan = None;
    if let Some(tracer) = light {
        let samples = match budget {
            Some(b) => b.total(),
            None => u64::from(spp) * pixels,
        };
        let sample = |seed, xy, s, k, tally: &mut Tally| pass.sample(seed, xy, s, k, tally);
        let (per_sample, plan) = crate::light_plan::per_sample(
            (scene, camera),
            &sample,
            tracer,
            settings.seed,
            samples as f64 / pixels as f64,
        );
        light_plan = plan;
        let paths = LightTracer::paths_for_samples(samples, per_sample);
        if let Some(share) = share {
            let chunks = light_chunks(paths);
            let (i, n) = (u64::from(share.light.0), u64::from(share.light.1.max(1)));
            let run = chunks * i / n..chunks * (i + 1) / n;
            let (splats, t) =
                tracer.trace_share(scene, camera, paths, settings.seed, run, progress, pixels);
            tally.add(t);
            light_paths = paths;
            apart = Some(LightShare { splats, paths });
        } else {
            let lit = tracer.trace(scene, camera, paths, light_seed, progress, pixels);
            add_light(&mut layers, &lit.layers);
            tally.add(lit.tally);
            non_finite += lit.non_finite;
            light_paths = lit.paths;
        }
    }
    debug_assert!(
        layers
            .images
            .iter()
            .all(|i| i.pixels().iter().all(|p: &Rgb| p.is_finite()))
    );
    let out = RenderOutput {
        layers,
        stats: RenderStats {
            method: integrator.name(),
            width,
            height,
            samples_per_pixel: spp,
            samples,
            refined_pixels,
            non_finite,
            rays: tally.rays,
            shadow_rays: tally.shadow_rays,
            light_paths,
            light_plan,
            splits: pass.splits,
            split_plan,
            elapsed: start.elapsed(),
        },
    };
    (out, apart)
}
