//! The integrator boundary (ARCHITECTURE.md, "Architecture invariants"): one required method that
//! turns a camera ray into layered radiance, plus the shared pieces every integrator uses: the
//! shading context at a hit (local frame, one-sided surfaces) and direct lighting from the area
//! emitters with stratified shadow rays. Visibility and ray-origin offsetting belong to the scene
//! (`Scene::intersect_from`, `Scene::occluded_between`); nothing here holds an epsilon. Integrators
//! never spawn threads.

use glam::Vec3;
use twopass_brdf::frame::Frame;
use twopass_brdf::{Material, Rgb};
use twopass_scene::{Hit, Ray, Scene, SurfacePoint};

use crate::film::Radiance;
use crate::sampler::{Sampler, stratum};

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

/// What one camera sample carries through an integrator: its random stream and the count of
/// the rays it traces.
#[derive(Debug)]
pub struct SampleState<'a> {
    /// The sample's stream, keyed by (seed, pixel, sample).
    pub sampler: &'a mut Sampler,
    /// The rays traced for this sample so far.
    pub tally: &'a mut Tally,
}

/// A light transport method: radiance arriving along a camera ray.
///
/// Implementations are pure functions of their inputs and the sampler's stream: the render
/// loop ([`crate::render()`]) owns tiling, threads, seeding and progress.
pub trait Integrator: Sync {
    /// A short name for reports and file names (`whitted`, `radiosity`, `hybrid`,
    /// `hybrid-direct`, `reference`).
    fn name(&self) -> &'static str;

    /// Radiance (W/(m^2 sr) per channel) arriving at the camera along `ray` (unit direction),
    /// split into [`crate::Layer`]s; the sample's tally counts the rays it traces.
    fn radiance(&self, scene: &Scene, ray: &Ray, sample: SampleState<'_>) -> Radiance;

    /// The light tracing pass whose per-pixel result the render loop adds to this
    /// integrator's image (the caustics it leaves to light tracing), if any.
    fn light_tracer(&self) -> Option<&crate::light_tracing::LightTracer> {
        None
    }
}

/// What a shader needs at a hit: the material, the local shading frame and the outgoing
/// direction in it.
#[derive(Debug, Clone, Copy)]
pub struct Shading<'a> {
    /// The hit.
    pub hit: Hit,
    /// The hit surface's material.
    pub material: &'a Material,
    /// Local frame around the shading normal (on the geometric normal's side).
    pub frame: Frame,
    /// Direction toward the viewer (unit, local frame; z < 0 when seen from behind).
    pub wo: Vec3,
    /// Emitted radiance toward the viewer, W/(m^2 sr): the object's L_e on its front side,
    /// zero on its back (emitters are one-sided).
    pub emitted: Rgb,
}

impl<'a> Shading<'a> {
    /// The shading context of `hit`, reached by a ray of unit direction `direction`.
    pub fn new(scene: &'a Scene, hit: Hit, direction: Vec3) -> Self {
        let material = &scene.materials[hit.material as usize].material;
        let frame = Frame::from_normal(hit.shading_normal);
        let wo = frame.to_local(-direction);
        let emitted = if hit.front_face {
            scene.objects[hit.object as usize].emission
        } else {
            Rgb::ZERO
        };
        Self {
            hit,
            material,
            frame,
            wo,
            emitted,
        }
    }

    /// Whether the surface scatters light toward this side: opaque surfaces are one-sided
    /// (their back reflects nothing, as in the radiosity solution, whose receivers are
    /// one-sided); a smooth dielectric is seen from both sides.
    pub fn scatters(&self) -> bool {
        self.hit.front_face || self.is_dielectric()
    }

    /// Whether the material is a smooth dielectric (two-sided interface).
    pub fn is_dielectric(&self) -> bool {
        self.material.is_dielectric()
    }
}

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

/// Which emitter a path samples: each with probability proportional to its mean emitted power
/// over the three channels (uniform when nothing emits power).
#[derive(Debug, Clone)]
pub struct EmitterChoice {
    /// Cumulative probabilities, last = 1.
    cdf: Vec<f32>,
    /// Probability of each emitter.
    probability: Vec<f32>,
}

impl EmitterChoice {
    /// The choice among `scene`'s emitters.
    pub fn new(scene: &Scene) -> Self {
        let weights: Vec<f64> = scene
            .emitters
            .iter()
            .map(|e| f64::from((e.power.x + e.power.y + e.power.z) / 3.0).max(0.0))
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
        Self { cdf, probability }
    }

    /// The emitter (index into `Scene::emitters`) for `u` uniform in [0, 1); the scene must
    /// have one.
    pub fn pick(&self, u: f32) -> usize {
        self.cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1)
    }

    /// Probability of picking emitter `e`.
    pub fn probability(&self, e: usize) -> f32 {
        self.probability[e]
    }
}

/// Direct light from every emitter at a shading point, with `grid` x `grid` stratified shadow
/// rays per emitter, split into two parts by `brdf`, which returns two BRDF values (1/sr,
/// without the cosine) for a local incident direction. Returns the two reflected radiances,
/// W/(m^2 sr) per channel.
///
/// Estimator: for each emitter of area A and radiance L_e, the mean over its samples of
/// f L_e cos(theta_x) cos(theta_y) / d^2 * A, with points uniform by area (density 1/A) from a
/// jittered grid ([`Lights::sample`]): unbiased, stratified over the emitter's area. Light must
/// reach the front of the shading point's geometric surface and leave the front of the emitter.
pub fn direct_light(
    scene: &Scene,
    lights: &Lights,
    s: &Shading<'_>,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
    brdf: impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let mut out = [Rgb::ZERO; 2];
    if !s.hit.front_face {
        return out;
    }
    let k = grid.max(1);
    let n = k * k;
    let x = s.hit.point;
    for (e, emitter) in scene.emitters.iter().enumerate() {
        let mut sum = [Rgb::ZERO; 2];
        for i in 0..n {
            let y = lights.sample(scene, e, stratum(i, k, sampler.next_2d()));
            let d = y.position - x.position;
            let dist2 = d.length_squared();
            if dist2 <= 0.0 {
                continue;
            }
            let wi = d / dist2.sqrt();
            let cos_y = -wi.dot(y.normal);
            if cos_y <= 0.0 || wi.dot(x.normal) <= 0.0 {
                continue;
            }
            let wl = s.frame.to_local(wi);
            if wl.z <= 0.0 {
                continue;
            }
            let f = brdf(wl);
            if f[0].max_element() <= 0.0 && f[1].max_element() <= 0.0 {
                continue;
            }
            tally.shadow_rays += 1;
            if scene.occluded_between(&x, &y) {
                continue;
            }
            let g = wl.z * cos_y / dist2;
            sum[0] += f[0] * g;
            sum[1] += f[1] * g;
        }
        let scale = emitter.radiance * (emitter.area / n as f32);
        out[0] += sum[0] * scale;
        out[1] += sum[1] * scale;
    }
    out
}

/// The closest hit along a ray leaving the shading point in world direction `direction`,
/// counted in `tally`.
pub fn trace_from(
    scene: &Scene,
    s: &Shading<'_>,
    direction: Vec3,
    tally: &mut Tally,
) -> Option<Hit> {
    tally.rays += 1;
    scene.intersect_from(&s.hit.point, direction)
}
