//! Sampling the emitters: a point on one emitter by area, keeping a 2-D stratification
//! ([`Lights`]); one emitter among all by power ([`EmitterChoice`]); and one area emitter
//! among all by its importance at a shading point ([`Lights::choice_at`], [`PointChoice`]),
//! for the shadow rays of the Whitted core ([`crate::integrator::direct_light`]).
//!
//! **Importance at a point** (Conty Estevez & Kulla 2018; pbrt-v4's `LightBounds::Importance`).
//! A scene with many emitters (strip lights, a lit ceiling of panels) lights each point mostly
//! from a few near ones. Shadow rays spread by power alone, or a grid per emitter, spend most of
//! their rays on emitters that give the point little. Each area emitter is bounded once by a
//! sphere around its surface and a cone around its normals; at a point x the importance is
//!
//! `Phi / pi * cos(theta_e') * cos(theta_x') / d^2`
//!
//! with `Phi` the emitter's power (mean over the channels), d the distance from x to the
//! sphere's centre (at least its radius), `theta_x'` the smallest angle the sphere leaves
//! between x's shading normal and a direction into it, and `theta_e'` the smallest angle
//! between an emitter normal of the cone and a direction from the sphere toward x: the
//! irradiance a small emitter there would give. It is zero only where no point of the emitter
//! can light x (the whole sphere below x's geometric or shading tangent plane, or x behind
//! every normal of the cone), so sampling in proportion to it is unbiased. Occlusion is not
//! seen: an emitter behind a wall keeps its importance. The cost is one evaluation per emitter
//! and point, which `grid`^2 shadow rays share; the path tracer, with one light sample per
//! vertex, picks by power instead (there the evaluations cost about what the better choice
//! saves on the chrome room's 17 strips).

use glam::{DVec3, Vec3};
use smallvec::SmallVec;
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
    /// Per emitter: its bounds, for its importance at a point.
    bounds: Vec<EmitterBounds>,
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
                        acc += f64::from(scene.mesh.area(t));
                        acc
                    })
                    .collect();
                (tris.start, cdf)
            })
            .collect();
        Self {
            emitters,
            bounds: emitter_bounds(scene),
        }
    }

    /// The area emitters' probabilities at a shading point at `x` with unit geometric normal
    /// `geometric` and unit shading normal `shading`, in proportion to their importance there
    /// (module docs); empty when no emitter can light the point's front.
    pub fn choice_at(&self, x: Vec3, geometric: Vec3, shading: Vec3) -> PointChoice {
        PointChoice::new(
            self.bounds
                .iter()
                .map(|b| b.importance(x, geometric, shading)),
        )
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

/// The mean of a colour's three channels, clamped at zero (a NaN gives zero).
fn mean(c: DVec3) -> f64 {
    ((c.x + c.y + c.z) / 3.0).max(0.0)
}

/// What bounds one area emitter's light anywhere (pbrt-v4's `LightBounds`): a sphere around
/// its surface, a cone around its front normals and its power.
#[derive(Debug, Clone, Copy)]
struct EmitterBounds {
    /// Centre of the bounding sphere (the centre of the emitter's bounding box), scene units.
    centre: Vec3,
    /// Radius of the bounding sphere, scene units.
    radius: f32,
    /// Unit axis of the normal cone (any unit vector when the cone is the whole sphere).
    axis: Vec3,
    /// Cosine and sine of the cone's half-angle: every triangle's geometric normal is within
    /// it of `axis` (cosine -1 for the whole sphere).
    cos_cone: f32,
    sin_cone: f32,
    /// The emitted power's channel mean over pi, W/sr in scene units: a small emitter's
    /// irradiance at unit distance, seen head-on and facing the point.
    intensity: f64,
}

/// The bounds of every area emitter of `scene`, in `Scene::emitters` order.
fn emitter_bounds(scene: &Scene) -> Vec<EmitterBounds> {
    let mesh = &scene.mesh;
    scene
        .emitters
        .iter()
        .map(|e| {
            let tris = scene.objects[e.object as usize].triangles.clone();
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            let mut normal_sum = DVec3::ZERO;
            for t in tris.clone() {
                for p in mesh.corners(t) {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                normal_sum += mesh.geometric_normal(t).as_dvec3() * f64::from(mesh.area(t));
            }
            let axis = normal_sum.normalize_or_zero().as_vec3();
            let cos_cone = if axis == Vec3::ZERO {
                -1.0
            } else {
                tris.map(|t| mesh.geometric_normal(t).dot(axis))
                    .fold(1.0f32, f32::min)
                    // Rounding must not narrow the cone below a normal it holds.
                    .next_down()
                    .max(-1.0)
            };
            let axis = if axis == Vec3::ZERO { Vec3::Z } else { axis };
            EmitterBounds {
                centre: 0.5 * (lo + hi),
                radius: 0.5 * (hi - lo).length() * (1.0 + 4.0 * f32::EPSILON),
                axis,
                cos_cone,
                sin_cone: (1.0 - cos_cone * cos_cone).max(0.0).sqrt(),
                intensity: mean(e.power.as_dvec3()) / std::f64::consts::PI,
            }
        })
        .collect()
}

/// cos(max(0, a - b)) from the cosines and sines of the angles a and b in [0, pi].
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin from cos, for an angle in [0, pi].
fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

impl EmitterBounds {
    /// The emitter's importance at a point at `x` with unit normals `geometric` and `shading`
    /// (module docs), W/m^2 in scene units; zero only where no point of the emitter can light
    /// the point's front.
    fn importance(&self, x: Vec3, geometric: Vec3, shading: Vec3) -> f64 {
        let d = self.centre - x;
        let dist2 = d.length_squared();
        let r2 = self.radius * self.radius;
        if !(dist2 > r2 && dist2.is_finite()) {
            // x inside the sphere: every direction may reach the emitter.
            return self.intensity / f64::from(r2).max(f64::MIN_POSITIVE);
        }
        // The half-angle theta_b the sphere subtends at x.
        let inv_dist = dist2.sqrt().recip();
        let to_light = d * inv_dist;
        let sin_b = (self.radius * inv_dist).min(1.0);
        let cos_b = (1.0 - sin_b * sin_b).max(0.0).sqrt();
        // The receiver: the smallest angle between a normal and a direction into the sphere,
        // at most pi/2 for light to arrive: cos(max(0, theta - theta_b)) > 0.
        let reaches = |cos: f32| cos > 0.0 || cos_sub_clamped(sin_of(cos), cos, sin_b, cos_b) > 0.0;
        let cos_g = to_light.dot(geometric).clamp(-1.0, 1.0);
        let cos_s = to_light.dot(shading).clamp(-1.0, 1.0);
        if !reaches(cos_g) || !reaches(cos_s) {
            return 0.0;
        }
        let cos_x = cos_sub_clamped(sin_of(cos_s), cos_s, sin_b, cos_b);
        // The emitter: the smallest angle between a cone normal and a direction toward x,
        // theta_w less the cone's half-angle theta_o and theta_b.
        let cos_w = -to_light.dot(self.axis).clamp(-1.0, 1.0);
        let cos_e = if cos_w >= self.cos_cone {
            1.0
        } else {
            let sin_w = sin_of(cos_w);
            // theta_w - theta_o, in (0, pi]: its cosine and sine by the difference formulas.
            let c = cos_w * self.cos_cone + sin_w * self.sin_cone;
            let s = (sin_w * self.cos_cone - cos_w * self.sin_cone).max(0.0);
            cos_sub_clamped(s, c, sin_b, cos_b)
        };
        if cos_e <= 0.0 {
            return 0.0;
        }
        self.intensity * f64::from(cos_e * cos_x) / f64::from(dist2)
    }
}

/// The lights' probabilities at one shading point, in proportion to their importance there
/// ([`Lights::choice_at`]). Kept inline (no allocation) for up to 32 lights.
#[derive(Debug, Clone)]
pub struct PointChoice {
    /// Cumulative importance, f64 (the last entry is the total).
    cdf: SmallVec<[f64; 32]>,
    /// The last light with a non-zero importance (rounding of u * total up to the total
    /// lands there).
    last: usize,
}

impl PointChoice {
    /// The choice among lights of the given importances (non-negative; NaN counts as zero).
    fn new(importances: impl Iterator<Item = f64>) -> Self {
        let mut acc = 0.0;
        let mut last = 0;
        let cdf = importances
            .enumerate()
            .map(|(i, w)| {
                if w > 0.0 && w.is_finite() {
                    acc += w;
                    last = i;
                }
                acc
            })
            .collect();
        Self { cdf, last }
    }

    /// The total importance (W/m^2 in scene units).
    fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Whether no light can reach the point (every importance zero).
    pub fn is_empty(&self) -> bool {
        !(self.total() > 0.0 && self.total().is_finite())
    }

    /// The light for `u` uniform in [0, 1), its probability, and `u`'s remainder within the
    /// light's share, uniform in [0, 1) again (so a stratified `u` stays stratified on the
    /// light). Only for a choice that is not empty ([`Self::is_empty`]).
    pub fn pick(&self, u: f32) -> (usize, f32, f32) {
        let total = self.total();
        let target = f64::from(u) * total;
        let mut i = self.cdf.partition_point(|&c| c <= target);
        if i > self.last {
            i = self.last;
        }
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let width = self.cdf[i] - lo;
        let rest = ((target - lo) / width).clamp(0.0, 1.0 - f64::from(f32::EPSILON) / 2.0);
        (i, (width / total) as f32, rest as f32)
    }

    /// The probability of light `i`.
    pub fn probability(&self, i: usize) -> f32 {
        let total = self.total();
        if self.is_empty() || i >= self.cdf.len() {
            return 0.0;
        }
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        ((self.cdf[i] - lo) / total) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twopass_brdf::random::Pcg32 as Rng;

    /// A random unit vector from two uniform numbers.
    fn direction(rng: &mut Rng) -> Vec3 {
        let z = 2.0 * rng.next_f32() - 1.0;
        let phi = std::f32::consts::TAU * rng.next_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    #[test]
    fn an_emitter_gets_importance_zero_only_where_none_of_its_points_can_light_the_point() {
        // Random triangles (one emitter each) and random receivers: wherever a point of the
        // emitter can send light to the receiver's front (in front of the emitter, above both
        // of the receiver's tangent planes), the importance must be positive, or the choice
        // would never sample light that arrives (a bias); where it is zero, no such point.
        let mut rng = Rng::new(7, 0);
        let (mut zero, mut lit) = (0, 0);
        for _ in 0..20_000 {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
            let corners = [0; 3].map(|_| c + direction(&mut rng) * (0.05 + rng.next_f32()));
            let normal = (corners[1] - corners[0])
                .cross(corners[2] - corners[0])
                .normalize();
            let (lo, hi) = (
                corners[0].min(corners[1]).min(corners[2]),
                corners[0].max(corners[1]).max(corners[2]),
            );
            let bounds = EmitterBounds {
                centre: 0.5 * (lo + hi),
                radius: 0.5 * (hi - lo).length() * (1.0 + 4.0 * f32::EPSILON),
                axis: normal,
                cos_cone: 1.0f32.next_down(),
                sin_cone: sin_of(1.0f32.next_down()),
                intensity: 1.0,
            };
            let x = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            let geometric = direction(&mut rng);
            // A shading normal within 30 degrees of the geometric one.
            let shading = (geometric + 0.5 * direction(&mut rng)).normalize();
            let importance = bounds.importance(x, geometric, shading);
            let reaches = (0..64).any(|_| {
                let (a, b) = (rng.next_f32(), rng.next_f32());
                let s = a.sqrt();
                let y =
                    corners[0] * (1.0 - s) + corners[1] * (s * (1.0 - b)) + corners[2] * (s * b);
                let wi = (y - x).normalize();
                wi.dot(geometric) > 1e-3 && wi.dot(shading) > 1e-3 && -wi.dot(normal) > 1e-3
            });
            if reaches {
                assert!(
                    importance > 0.0,
                    "a lit point got importance 0: x {x}, n {geometric}, emitter {corners:?}"
                );
                lit += 1;
            }
            if importance == 0.0 {
                zero += 1;
            }
        }
        // Both cases occur often enough for the test to mean something.
        assert!(lit > 3000 && zero > 3000, "lit {lit}, zero {zero}");
    }

    #[test]
    fn a_point_choice_picks_in_proportion_and_never_an_emitter_of_importance_zero() {
        let weights = [0.0, 2.0, 0.0, 1.0, 5.0, 0.0];
        let choice = PointChoice::new(weights.iter().copied());
        assert!(!choice.is_empty());
        let n = 80_000;
        let mut counts = [0u32; 6];
        let mut rests = [0.0f64; 6];
        for i in 0..n {
            // Stratified u, the last one as close to 1 as f32 goes.
            let u = ((i as f32 + 0.5) / n as f32).min(1.0f32.next_down());
            let (e, p, rest) = choice.pick(u);
            assert!((p - (weights[e] / 8.0) as f32).abs() < 1e-6);
            assert_eq!(p, choice.probability(e));
            assert!((0.0..1.0).contains(&rest));
            counts[e] += 1;
            rests[e] += f64::from(rest);
        }
        let (e, _, _) = choice.pick(1.0f32.next_down());
        assert_eq!(
            e, 4,
            "u just under 1 lands on the last emitter that has importance"
        );
        for (e, &w) in weights.iter().enumerate() {
            let share = f64::from(counts[e]) / f64::from(n);
            assert!((share - w / 8.0).abs() < 1e-3, "emitter {e}: {share}");
            if counts[e] > 0 {
                // The remainder is uniform on the emitter: mean 1/2.
                assert!((rests[e] / f64::from(counts[e]) - 0.5).abs() < 1e-3);
            }
        }
        assert!(PointChoice::new([0.0, f64::NAN].into_iter()).is_empty());
        assert!(PointChoice::new(std::iter::empty()).is_empty());
    }
}
