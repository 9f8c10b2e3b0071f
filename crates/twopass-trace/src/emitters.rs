//! Sampling the emitters: a point on one emitter by area, keeping a 2-D stratification
//! ([`Lights`]), and one emitter among all by power ([`EmitterChoice`]).

use twopass_scene::{Scene, SurfacePoint};

/// Area sampling of the emitters that keeps a 2-D stratification: the first coordinate picks a
/// triangle by area and its remainder becomes the first coordinate within that triangle, so a
/// jittered grid over [0, 1)^2 becomes a stratified set of points over the emitter's whole area.
/// (`Emitter::sample` takes three numbers and discards the remainder, which would leave the
/// triangle choice and the position within it correlated or unstratified.)
#[derive(Debug, Clone)]
pub struct Lights {
    /// Per emitter: its first triangle and the cumulative areas of its triangles (scene units
    /// squared, f64; the last entry is the emitter's area).
    emitters: Vec<(u32, Vec<f64>)>,
}

impl Lights {
    /// The sampling tables of `scene`'s emitters.
    pub fn new(scene: &Scene) -> Self {
        let emitters = scene
            .emitters
            .iter()
            .map(|e| {
                let tris = scene.objects[e.object as usize].triangles.clone();
                let mut acc = 0.0;
                let cdf = tris
                    .clone()
                    .map(|t| {
                        acc += f64::from(scene.mesh.areas[t as usize]);
                        acc
                    })
                    .collect();
                (tris.start, cdf)
            })
            .collect();
        Self { emitters }
    }

    /// A point of emitter `emitter` (index into `Scene::emitters`), uniform by area (density
    /// 1 / area) for `u` uniform in [0, 1)^2, stratified when `u` is.
    pub fn sample(&self, scene: &Scene, emitter: usize, u: glam::Vec2) -> SurfacePoint {
        let (first, cdf) = &self.emitters[emitter];
        let total = cdf.last().copied().unwrap_or(0.0);
        let target = f64::from(u.x) * total;
        let i = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
        let width = cdf[i] - lo;
        let fx = if width > 0.0 {
            ((target - lo) / width).clamp(0.0, 1.0 - f64::from(f32::EPSILON) / 2.0) as f32
        } else {
            0.5
        };
        scene
            .mesh
            .sample_triangle(*first + i as u32, glam::Vec2::new(fx, u.y))
    }
}

/// A light [`EmitterChoice`] picked: an area emitter or a lamp.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Light {
    /// Index into `Scene::emitters`.
    Area(usize),
    /// Index into `Scene::lamps`.
    Lamp(usize),
}

/// Which light a path samples, among the area emitters and the lamps: each with probability
/// proportional to its mean emitted power over the three channels (a lamp's
/// [`Lamp::power`](twopass_scene::Lamp::power); uniform when nothing emits power).
#[derive(Debug, Clone)]
pub struct EmitterChoice {
    /// Cumulative probabilities over the area emitters, then the lamps; last = 1.
    cdf: Vec<f32>,
    /// Probability of each, in the same order.
    probability: Vec<f32>,
    /// How many area emitters come first.
    areas: usize,
}

impl EmitterChoice {
    /// The choice among `scene`'s emitters and lamps.
    pub fn new(scene: &Scene) -> Self {
        let mean = |p: twopass_brdf::Rgb| f64::from((p.x + p.y + p.z) / 3.0).max(0.0);
        let weights: Vec<f64> = scene
            .emitters
            .iter()
            .map(|e| mean(e.power))
            .chain(
                scene
                    .lamps
                    .iter()
                    .map(|l| mean(l.power(scene.bounds.diagonal()))),
            )
            .collect();
        let total: f64 = weights.iter().sum();
        let n = weights.len();
        let probability: Vec<f32> = weights
            .iter()
            .map(|&w| {
                if total > 0.0 {
                    (w / total) as f32
                } else {
                    1.0 / n as f32
                }
            })
            .collect();
        let mut acc = 0.0_f32;
        let mut cdf: Vec<f32> = probability
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self {
            cdf,
            probability,
            areas: scene.emitters.len(),
        }
    }

    /// Whether there is nothing to choose (no emitter, no lamp).
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// The light for `u` uniform in [0, 1); the scene must have one ([`Self::is_empty`]).
    pub fn pick(&self, u: f32) -> Light {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        if i < self.areas {
            Light::Area(i)
        } else {
            Light::Lamp(i - self.areas)
        }
    }

    /// Probability of picking area emitter `e` (index into `Scene::emitters`).
    pub fn probability(&self, e: usize) -> f32 {
        self.probability[e]
    }

    /// Probability of picking `light`.
    pub fn probability_of(&self, light: Light) -> f32 {
        match light {
            Light::Area(e) => self.probability[e],
            Light::Lamp(l) => self.probability[self.areas + l],
        }
    }
}
