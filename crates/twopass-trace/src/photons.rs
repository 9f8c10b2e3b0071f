//! A caustic photon map (Jensen 1996): light that left an emitter and reached a diffuse
//! surface through mirrors and glass (L S+ D), stored where it landed and estimated at any
//! point from the nearest photons.
//!
//! The gathered hybrid needs it at the diffuse points the camera sees through mirrors and
//! glass. There the light tracer cannot connect (its connection to the eye would pass through
//! the delta surface), and the gather rays find a small emitter through a delta path only by
//! chance: a few rays of a pixel carry the whole caustic, and the pixel is a firefly. The
//! photon map trades that noise for a blur over the photons' neighbourhood, which stays far
//! below the element mesh's (its radius is capped at half the radiosity pass's default
//! element edge) and shrinks as photons are added.
//!
//! **Estimator.** Photon i carries flux Phi_i = beta_i / N, W (beta_i: its path's throughput,
//! the light tracer's [`LightTracer`] first segment times the delta bounces' flux weights; N:
//! the photons traced). The irradiance at x is E = sum_{i<k} Phi_i / (pi r_k^2) over the k
//! nearest photons on the same side of the same surface orientation (stored normal within
//! 60 degrees of x's), r_k the distance to the k-th (or the radius cap, when fewer lie within
//! it); the reflected radiance is rho / pi E. The k-th photon is left out of the sum because it
//! sits on the disc's edge by construction (the estimate is then unbiased for a uniform
//! density).
//!
//! **Determinism.** Photon i draws from the stream keyed by (seed, i); photons are traced in
//! fixed chunks and kept in path order, so the map, and every estimate from it, does not depend
//! on the thread count.

use std::num::NonZero;

use glam::Vec3;
use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use rayon::prelude::*;
use smart_default::SmartDefault;
use twopass_brdf::Rgb;
use twopass_brdf::frame::Frame;
use twopass_scene::Scene;

use crate::counters::Tally;
use crate::light_tracing::{CausticScope, LightTracer, LightTracingSettings, survives_roulette};
use crate::sampler::Sampler;

/// The default radius cap ([`PhotonSettings::max_radius`]) is the scene's bounding-box
/// diagonal over this: half the radiosity pass's default element edge (diagonal / 24), so the
/// photons never blur a caustic more than the element mesh would.
pub const RADIUS_PER_DIAGONAL: f32 = 48.0;

/// Photons per parallel job; jobs are collected in order.
const CHUNK: u64 = 4096;
/// Mixed into the seed so that photons never share a stream with the light tracer's paths.
const PHOTON_SEED_MIX: u64 = 0x7068_6f74_6f6e_6d61;
/// Cosine of the widest angle between a photon's surface normal and the query point's for the
/// photon to count: photons on the other side of a thin wall, or on a face meeting the query's
/// at a corner, light another surface.
const SAME_SURFACE_COS: f32 = 0.5;

/// How many caustic photons to trace and how to estimate from them.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct PhotonSettings {
    /// Photon paths traced toward the mirrors and glass (each stores at most one photon).
    #[default(1 << 18)]
    pub paths: u64,
    /// Photons an estimate uses (k).
    #[default(64)]
    pub nearest: usize,
    /// Largest radius an estimate gathers photons over, scene units; `None`: the scene's
    /// bounding-box diagonal over [`RADIUS_PER_DIAGONAL`].
    #[default(None)]
    pub max_radius: Option<f32>,
    /// Most delta bounces before a photon is stored (deeper paths are dropped).
    #[default(64)]
    pub max_depth: u32,
    /// Seed of the photons' streams.
    #[default(0)]
    pub seed: u64,
}

/// One stored photon.
#[derive(Debug, Clone, Copy)]
struct Photon {
    /// Flux Phi_i, W (already divided by the number of paths).
    flux: Rgb,
    /// Geometric normal of the surface it landed on (front side).
    normal: Vec3,
}

/// A photon where it landed: its position (scene units) and the photon.
type Landing = ([f32; 3], Photon);

/// The caustic photons of one scene, and a k-d tree over their positions.
pub struct CausticPhotons {
    tree: ImmutableKdTree<f32, u32, 3, 32>,
    photons: Vec<Photon>,
    /// Photons per estimate.
    nearest: NonZero<usize>,
    /// Squared radius cap, scene units squared.
    max_radius2: f32,
    /// Rays traced to build the map.
    tally: Tally,
}

impl std::fmt::Debug for CausticPhotons {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CausticPhotons")
            .field("photons", &self.photons.len())
            .field("nearest", &self.nearest)
            .field("max_radius2", &self.max_radius2)
            .finish_non_exhaustive()
    }
}

impl CausticPhotons {
    /// Traces `settings.paths` photon paths of `scene` toward its mirrors and glass and keeps
    /// each one's first landing on the front of a diffusely reflecting surface after at least
    /// one delta bounce. `None` when the scene has no emitter or no mirror or glass, or no
    /// photon landed (then no such light exists to estimate).
    pub fn build(scene: &Scene, settings: PhotonSettings) -> Option<Self> {
        let tracer = LightTracer::new(
            scene,
            LightTracingSettings {
                max_depth: settings.max_depth,
                ..LightTracingSettings::new(CausticScope::FirstDiffuse)
            },
        )?;
        let paths = settings.paths.max(1);
        let seed = settings.seed ^ PHOTON_SEED_MIX;
        let chunks: Vec<(Vec<Landing>, Tally)> = (0..paths.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut out = Vec::new();
                let mut tally = Tally::default();
                for i in c * CHUNK..((c + 1) * CHUNK).min(paths) {
                    let mut sampler = Sampler::new(seed, i, 0);
                    if let Some(p) = trace_photon(scene, &tracer, &mut sampler, &mut tally) {
                        out.push(p);
                    }
                }
                (out, tally)
            })
            .collect();
        let mut tally = Tally::default();
        let mut positions = Vec::new();
        let mut photons = Vec::new();
        let scale = 1.0 / paths as f32;
        for (chunk, t) in chunks {
            tally.add(t);
            for (position, mut photon) in chunk {
                photon.flux *= scale;
                positions.push(position);
                photons.push(photon);
            }
        }
        if photons.is_empty() {
            return None;
        }
        let max_radius = settings
            .max_radius
            .unwrap_or(scene.bounds.diagonal() / RADIUS_PER_DIAGONAL)
            .max(f32::MIN_POSITIVE);
        Some(Self {
            tree: ImmutableKdTree::new_from_slice(&positions),
            photons,
            nearest: NonZero::new(settings.nearest.max(2)).unwrap_or(NonZero::<usize>::MIN),
            max_radius2: max_radius * max_radius,
            tally,
        })
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// Whether no photon is stored (never, for a map [`CausticPhotons::build`] returned).
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Rays traced to build the map.
    pub fn tally(&self) -> Tally {
        self.tally
    }

    /// Caustic irradiance E, W/m^2 per channel, at `position` on a surface of geometric normal
    /// `normal` (front side): zero where no photon lies within the radius cap.
    pub fn irradiance(&self, position: Vec3, normal: Vec3) -> Rgb {
        let found = self.tree.nearest_n_within::<SquaredEuclidean>(
            &position.to_array(),
            self.max_radius2,
            self.nearest,
            true,
        );
        // The disc's radius: the k-th photon's distance when k were found (that photon left
        // out), else the cap.
        let (inside, r2) = if found.len() == self.nearest.get() {
            let last = found.len() - 1;
            (&found[..last], found[last].distance)
        } else {
            (&found[..], self.max_radius2)
        };
        if r2 <= 0.0 || !r2.is_finite() {
            return Rgb::ZERO;
        }
        let mut sum = Rgb::ZERO;
        for n in inside {
            let p = &self.photons[n.item as usize];
            if p.normal.dot(normal) >= SAME_SURFACE_COS {
                sum += p.flux;
            }
        }
        sum / (std::f32::consts::PI * r2)
    }
}

/// One photon path: the emitter's first segment toward the specular targets, then delta
/// bounces (flux weights, Russian roulette as the light tracer's) until the first surface
/// without a delta lobe. Returns the photon there when it lands on the front of a surface that
/// reflects diffusely after at least one delta bounce.
fn trace_photon(
    scene: &Scene,
    tracer: &LightTracer,
    sampler: &mut Sampler,
    tally: &mut Tally,
) -> Option<Landing> {
    let settings = tracer.settings();
    let (mut hit, mut dir, start) = tracer.emit(scene, sampler, tally)?;
    let mut beta = start;
    let mut bounces = 0u32;
    while let Some(h) = hit {
        let material = &scene.materials[h.material as usize].material;
        let Some(lobe) = material.delta() else {
            if bounces == 0 || !h.front_face || !material.reflects_diffusely() {
                return None;
            }
            let photon = Photon {
                flux: beta,
                normal: h.point.normal,
            };
            return Some((h.point.position.to_array(), photon));
        };
        if bounces >= settings.max_depth {
            return None;
        }
        let frame = Frame::from_normal(h.shading_normal);
        let b = lobe.sample_flux(frame.to_local(-dir), sampler.next_2d())?;
        beta *= b.weight;
        dir = frame.to_world(b.wi).normalize();
        bounces += 1;
        if bounces >= settings.roulette_depth && !survives_roulette(&mut beta, start, sampler) {
            return None;
        }
        tally.rays += 1;
        hit = scene.intersect_from(&h.point, dir);
    }
    None
}
