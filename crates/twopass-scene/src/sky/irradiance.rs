//! The sky's irradiance at a surface point by stratified sampling with shadow rays (the
//! radiosity solvers' per-vertex source term, the final gather's direct part): the sun over
//! its cone and the dome by [`Sky::sample_dome`], each on a jittered grid. The random numbers
//! come from a stream keyed by the caller, so the result does not depend on the threads.

use glam::{Vec2, Vec3};
use twopass_brdf::Rgb;
use twopass_brdf::random::{SplitMix64, hash};

use crate::accel::{SHADOW_EPSILON, SurfacePoint};
use crate::scene::Scene;

/// Samples per axis of the sky's stratified grids for the radiosity solvers (grid^2 rays for
/// the sun, as many for the dome, per element vertex).
pub const SKY_GRID: u32 = 8;

impl Scene {
    /// Whether a ray from surface point `from` in unit direction `dir` escapes the scene
    /// (reaches the sky): nothing blocks it without end.
    pub fn sky_visible(&self, from: &SurfacePoint, dir: Vec3) -> bool {
        let o = from.spawn_origin(dir);
        !self
            .accel()
            .any_hit(o, dir, f32::INFINITY * (1.0 - SHADOW_EPSILON))
    }

    /// The irradiance (W per scene unit squared per channel) the sky's sun would send to the
    /// front of surface point `at` (receiving normal `normal`, unit) as a directional lamp
    /// at the disc's centre: L_sun times its solid angle times the cosine, one shadow ray
    /// (counted in `rays`). A deterministic stand-in for the disc where an estimate's noise
    /// would mislead (the hierarchical solver's refinement oracle); zero without a sun.
    pub fn sun_centre_irradiance(&self, at: &SurfacePoint, normal: Vec3, rays: &mut u64) -> Rgb {
        let Some(sun) = self.sky.as_ref().and_then(|s| s.sun) else {
            return Rgb::ZERO;
        };
        let cos = sun.direction.dot(normal);
        if cos <= 0.0 || sun.direction.dot(at.normal) <= 0.0 {
            return Rgb::ZERO;
        }
        *rays += 1;
        if self.sky_visible(at, sun.direction) {
            sun.radiance * (sun.solid_angle() * cos)
        } else {
            Rgb::ZERO
        }
    }

    /// The irradiance (W per scene unit squared per channel) the sky and its sun send to the
    /// front of surface point `at` whose receiving normal is `normal` (unit), shadows
    /// included: `grid` x `grid` stratified directions over the sun's cone and as many for
    /// the dome, each with a shadow ray, mean of L cos / pdf. `key` seeds the jitter (the
    /// same key, the same estimate). Zero without a sky; counts its shadow rays in `rays`.
    pub fn sky_irradiance(
        &self,
        at: &SurfacePoint,
        normal: Vec3,
        key: u64,
        grid: u32,
        rays: &mut u64,
    ) -> Rgb {
        let Some(sky) = &self.sky else {
            return Rgb::ZERO;
        };
        let k = grid.max(1);
        let n = k * k;
        let mut rng = SplitMix64::new(hash(key));
        let next2 = |i: u32, rng: &mut SplitMix64| {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let (a, b) = (i % k, i / k);
            (Vec2::new(a as f32 + u.x, b as f32 + u.y) / k as f32)
                .min(Vec2::splat(1.0 - f32::EPSILON / 2.0))
        };
        let mut sun = Rgb::ZERO;
        if sky.sun.is_some() {
            for i in 0..n {
                let u = next2(i, &mut rng);
                let Some((dir, pdf)) = sky.sample_sun(u) else {
                    break;
                };
                let cos = dir.dot(normal);
                let l = sky.sun_radiance(dir);
                if cos <= 0.0 || dir.dot(at.normal) <= 0.0 || l == Rgb::ZERO {
                    continue;
                }
                *rays += 1;
                if self.sky_visible(at, dir) {
                    sun += l * (cos / pdf);
                }
            }
        }
        let mut dome = Rgb::ZERO;
        for i in 0..n {
            let u = next2(i, &mut rng);
            let pick = rng.next_f32();
            let Some((dir, pdf)) = sky.sample_dome(at.position, normal, u, pick) else {
                continue;
            };
            let cos = dir.dot(normal);
            let l = sky.dome_radiance(dir);
            if cos <= 0.0 || dir.dot(at.normal) <= 0.0 || l == Rgb::ZERO {
                continue;
            }
            *rays += 1;
            if self.sky_visible(at, dir) {
                dome += l * (cos / pdf);
            }
        }
        (sun + dome) / n as f32
    }
}
