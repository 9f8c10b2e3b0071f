//! The sky's light through the specular surfaces (L S+ D from the sky): a window of glass, a
//! mirror under the open sky. The solvers take the sky's direct light with shadow rays, which
//! stop at a mirror or a pane, so what reaches a surface through them is shot here as from a
//! directional lamp, direction by direction: parallel beams from outside the scene's bounds
//! across the discs the specular objects' bounding spheres cast
//! ([`SpecularTargets::parallel`](twopass_scene::SpecularTargets::parallel)), for the sun over
//! its disc and for the dome over the sphere (a uniform sky) or the hemisphere above the
//! horizon (daylight: [`Sky::sample_dome_emission`](twopass_scene::Sky::sample_dome_emission)).
//!
//! Weights: a beam from the directions dw around w carries L(w) dw per unit area across it,
//! so a ray through a point of density p_A (per unit area across the beam) in a direction of
//! density p_w carries L(w) / (p_w p_A n). The sun's rays are stratified over the disc's
//! points (its directions differ by a fraction of a degree), the dome's over the directions.

use glam::{DVec3, Vec2};
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::{SplitMix64, hash};
use twopass_scene::{Ray, Scene};

use super::{Deposit, Specular, stratum};

/// Mixed into the key of the sky's rays (apart from the lamps').
const SKY_KEY: u64 = 0x5c1e_0000_0000_0000;

impl Specular {
    /// The sky's light through the specular surfaces (module docs). The sky gets the rays its
    /// power ([`Sky::power`](twopass_scene::Sky::power)) earns against `emitted` (the scene's
    /// whole emitted luminance power, W; `Specular::rays_for`), split between the sun and the
    /// dome by their radiance integrals. Returns the deposits in ray order and the rays cast;
    /// the same `key` gives the same deposits on any number of threads.
    pub(super) fn shoot_sky(&self, scene: &Scene, emitted: f64, key: u64) -> (Vec<Deposit>, u64) {
        let Some(sky) = &scene.sky else {
            return (Vec::new(), 0);
        };
        let diagonal = scene.bounds.diagonal();
        // The radiance integrals over the directions (W/m^2, luminance).
        let (dome, sun) = sky.integrals();
        let (dome, sun) = (
            luminance_f64(dome.as_dvec3()),
            luminance_f64(sun.as_dvec3()),
        );
        let total = dome + sun;
        if !(total.is_finite() && total > 0.0) {
            return (Vec::new(), 0);
        }
        let power = luminance_f64(sky.power(diagonal).as_dvec3());
        let back = f64::from(diagonal) * 2.0;
        let mut deposits = Vec::new();
        let mut cast = 0;
        for (part, share) in [(0_u64, sun / total), (1, dome / total)] {
            if share <= 0.0 {
                continue;
            }
            let n = self.rays_for(power * share, emitted);
            let k = n.isqrt();
            let part_key = hash(key ^ SKY_KEY ^ part);
            let results: Vec<(Option<Deposit>, u64)> = (0..n)
                .into_par_iter()
                .with_min_len(64)
                .map(|i| {
                    let mut rng = SplitMix64::new(hash(part_key ^ u64::from(i)));
                    let u = Vec2::new(rng.next_f32(), rng.next_f32());
                    let v = Vec2::new(rng.next_f32(), rng.next_f32());
                    let u = if i < k * k { stratum(i, k, u) } else { u };
                    // Toward the sky (w), its radiance and density; the disc point's sample.
                    let (w, radiance, pdf, at) = if part == 0 {
                        let Some((w, pdf)) = sky.sample_sun(v) else {
                            return (None, 0);
                        };
                        (w, sky.sun_radiance(w), f64::from(pdf), u)
                    } else {
                        let (w, pdf) = sky.sample_dome_emission(u);
                        (w, sky.dome_radiance(w), f64::from(pdf), v)
                    };
                    let travel = -w.as_dvec3().normalize();
                    let Some((point, density)) = self.targets.parallel(travel, at) else {
                        return (None, 0);
                    };
                    let weight = radiance.as_dvec3() / (pdf * density * f64::from(n));
                    if weight.is_nan() || weight.max_element() <= 0.0 {
                        return (None, 0);
                    }
                    let ray = Ray::new((point - travel * back).as_vec3(), travel.as_vec3());
                    let first = scene.intersect(&ray);
                    // All of it is emission: what a refraction focuses, the hybrids' light
                    // tracers count per pixel (their light paths start at the sky too).
                    self.follow(scene, first, ray.direction, weight, DVec3::ONE, &mut rng)
                })
                .collect();
            for (d, r) in results {
                deposits.extend(d);
                cast += r;
            }
        }
        (deposits, cast)
    }
}
