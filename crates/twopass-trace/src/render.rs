//! The one render loop (ARCHITECTURE.md, "Architecture invariants"; pbrt's
//! `ImageTileIntegrator`): square tiles rendered in parallel with rayon, one random stream per
//! (seed, pixel, sample) so the image is bit-identical for any thread count, stratified
//! supersampling within each pixel (box filter), progress through an atomic counter that another
//! thread may read, and non-finite samples counted and dropped, never written to a layer.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::Vec2;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_scene::{Camera, Ray, Scene};

use crate::film::{LayerImages, Radiance};
use crate::integrator::{Integrator, SampleState, Tally};
use crate::sampler::{Sampler, stratum};

/// Sampling settings of a render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderSettings {
    /// Camera samples per pixel (at least 1). The first floor(sqrt(n))^2 are stratified on a
    /// square grid over the pixel, the rest uniform over it.
    pub samples_per_pixel: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Jitter the camera samples within their strata (`false`: stratum centres, and the pixel
    /// centre for the unstratified rest: regular supersampling, exactly reproducible geometry).
    pub jitter: bool,
    /// Tile edge, pixels (at least 1): the unit of parallel work and of progress.
    pub tile_size: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            samples_per_pixel: 16,
            seed: 0,
            jitter: true,
            tile_size: 16,
        }
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
    /// Camera samples taken.
    pub samples: u64,
    /// Samples with a NaN or infinite value in any layer: counted, left out of their pixel's
    /// mean (which is over the finite samples only), never written.
    pub non_finite: u64,
    /// Closest-hit rays traced (camera rays included).
    pub rays: u64,
    /// Shadow rays traced (with the light tracing pass's connections to the camera).
    pub shadow_rays: u64,
    /// Light paths of the integrator's light tracing pass (0 without one).
    pub light_paths: u64,
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
    tally: Tally,
    non_finite: u64,
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
    let start = Instant::now();
    let (width, height) = (camera.width, camera.height);
    let spp = settings.samples_per_pixel.max(1);
    let k = spp.isqrt();
    let tile = settings.tile_size.max(1);
    let pixels = u64::from(width) * u64::from(height);
    let light = integrator.light_tracer();
    progress.done.store(0, Ordering::Relaxed);
    progress.total.store(
        if light.is_some() { 2 * pixels } else { pixels },
        Ordering::Relaxed,
    );

    let tiles: Vec<(u32, u32)> = (0..height.div_ceil(tile))
        .flat_map(|ty| (0..width.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
        .collect();

    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let (w, h) = (tile.min(width - x0), tile.min(height - y0));
            let mut pixels = Vec::with_capacity((w * h) as usize);
            let mut tally = Tally::default();
            let mut non_finite = 0;
            for y in y0..y0 + h {
                for x in x0..x0 + w {
                    let index = u64::from(y) * u64::from(width) + u64::from(x);
                    let mut sum = Radiance::ZERO;
                    let mut finite = 0u32;
                    for s in 0..spp {
                        let mut sampler = Sampler::new(settings.seed, index, u64::from(s));
                        let u = if settings.jitter {
                            sampler.next_2d()
                        } else {
                            Vec2::splat(0.5)
                        };
                        let offset = if s < k * k { stratum(s, k, u) } else { u };
                        let pixel = Vec2::new(x as f32, y as f32) + offset;
                        let ray = Ray::new(camera.position, camera.direction(pixel));
                        let mut t = Tally::default();
                        let sample = SampleState {
                            sampler: &mut sampler,
                            tally: &mut t,
                        };
                        let l = integrator.radiance(scene, &ray, sample);
                        tally.add(t);
                        if l.is_finite() {
                            sum += l;
                            finite += 1;
                        } else {
                            non_finite += 1;
                        }
                    }
                    let mean = if finite > 0 {
                        sum * (1.0 / finite as f32)
                    } else {
                        Radiance::ZERO
                    };
                    // A finite sum of finite samples can still overflow to infinity.
                    pixels.push(if mean.is_finite() {
                        mean
                    } else {
                        non_finite += u64::from(finite);
                        Radiance::ZERO
                    });
                }
            }
            progress.done.fetch_add(u64::from(w * h), Ordering::Relaxed);
            TileResult {
                x0,
                y0,
                w,
                pixels,
                tally,
                non_finite,
            }
        })
        .collect();

    let mut layers = LayerImages::new(width, height);
    let mut tally = Tally::default();
    let mut non_finite = 0;
    for t in &results {
        tally.add(t.tally);
        non_finite += t.non_finite;
        for (i, p) in t.pixels.iter().enumerate() {
            let (x, y) = (t.x0 + i as u32 % t.w, t.y0 + i as u32 / t.w);
            let at = y as usize * width as usize + x as usize;
            for (img, v) in layers.images.iter_mut().zip(p.layers) {
                img.pixels_mut()[at] = v;
            }
        }
    }
    let mut light_paths = 0;
    if let Some(tracer) = light {
        let paths = tracer.paths_for(camera, spp);
        let lit = tracer.trace(scene, camera, paths, settings.seed, progress, pixels);
        for (img, add) in layers.images.iter_mut().zip(&lit.layers.images) {
            for (p, a) in img.pixels_mut().iter_mut().zip(add.pixels()) {
                *p += *a;
            }
        }
        tally.add(lit.tally);
        non_finite += lit.non_finite;
        light_paths = lit.paths;
    }
    debug_assert!(
        layers
            .images
            .iter()
            .all(|i| i.pixels().iter().all(|p: &Rgb| p.is_finite()))
    );
    RenderOutput {
        layers,
        stats: RenderStats {
            method: integrator.name(),
            width,
            height,
            samples_per_pixel: spp,
            samples: u64::from(width) * u64::from(height) * u64::from(spp),
            non_finite,
            rays: tally.rays,
            shadow_rays: tally.shadow_rays,
            light_paths,
            elapsed: start.elapsed(),
        },
    }
}
