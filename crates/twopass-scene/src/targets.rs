//! Where light must be aimed to go through mirrors and glass: the bounding spheres of a scene's
//! delta objects (mirror, smooth conductor, smooth dielectric) and directions drawn from the
//! cones they subtend. The radiosity pass's specular transfer and the tracer's light tracing
//! both start paths this way: a ray whose direction lies outside every cone cannot reach a
//! specular surface first, so it needs not be cast.
//!
//! Units: positions and radii in scene units (f64), densities per steradian.

use glam::{DVec3, Vec2};

use crate::scene::Scene;

/// A bounding sphere of a specular object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// Centre, scene units.
    pub center: DVec3,
    /// Radius, scene units (a hair larger than the object's farthest vertex, so the cone holds
    /// the object's surface whatever the rounding).
    pub radius: f64,
}

/// The bounding spheres of every object of a scene whose material has a delta lobe.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpecularTargets {
    /// One per specular object, in object order.
    pub targets: Vec<Target>,
}

/// Objects of `scene` whose material has a delta lobe (mirror, conductor, dielectric), in
/// object order.
pub fn specular_objects(scene: &Scene) -> Vec<usize> {
    (0..scene.objects.len())
        .filter(|&o| {
            scene.materials[scene.objects[o].material as usize]
                .material
                .delta()
                .is_some()
        })
        .collect()
}

impl SpecularTargets {
    /// The targets of `scene` (none when nothing in it is specular).
    pub fn new(scene: &Scene) -> Self {
        let targets = specular_objects(scene)
            .into_iter()
            .map(|o| {
                let tris = scene.objects[o].triangles.clone();
                let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
                for t in tris.clone() {
                    for c in scene.mesh.corners(t) {
                        lo = lo.min(c.as_dvec3());
                        hi = hi.max(c.as_dvec3());
                    }
                }
                let center = (lo + hi) * 0.5;
                let radius = tris
                    .flat_map(|t| scene.mesh.corners(t))
                    .map(|c| (c.as_dvec3() - center).length())
                    .fold(0.0, f64::max);
                Target {
                    object: o as u32,
                    center,
                    radius: radius * (1.0 + 1e-6) + 1e-9 * center.length(),
                }
            })
            .collect();
        Self { targets }
    }

    /// Whether the scene has no specular object.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty()
    }

    /// The cone target `t` subtends from `x`: its unit axis and the cosine of its half angle
    /// (-1, the whole sphere of directions, from inside the bounding sphere).
    fn cone(t: &Target, x: DVec3) -> (DVec3, f64) {
        let d = t.center - x;
        let dist = d.length();
        if dist <= t.radius {
            (DVec3::Z, -1.0)
        } else {
            (d / dist, (1.0 - (t.radius / dist).powi(2)).max(0.0).sqrt())
        }
    }

    /// A unit direction toward the targets from `x` for `u` in [0, 1)^2, and its density
    /// (1/sr) under the mixture of the targets' cones, each chosen with probability
    /// proportional to its solid angle. The first coordinate picks the cone and its remainder
    /// becomes the cone's polar coordinate, so a stratified `u` stays stratified. `None` when
    /// there is no target.
    pub fn direction(&self, x: DVec3, u: Vec2) -> Option<(DVec3, f64)> {
        use std::f64::consts::PI;
        let solid = |cos_max: f64| 2.0 * PI * (1.0 - cos_max);
        let total: f64 = self.targets.iter().map(|t| solid(Self::cone(t, x).1)).sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = f64::from(u.x) * total;
        let mut acc = 0.0;
        let mut picked = (DVec3::Z, -1.0, 0.5);
        for (j, t) in self.targets.iter().enumerate() {
            let (axis, cos_max) = Self::cone(t, x);
            let w = solid(cos_max);
            if target < acc + w || j + 1 == self.targets.len() {
                let ux = ((target - acc) / w).clamp(0.0, 1.0 - 1e-12);
                picked = (axis, cos_max, ux);
                break;
            }
            acc += w;
        }
        let (axis, cos_max, ux) = picked;
        let cos_t = 1.0 - ux * (1.0 - cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * f64::from(u.y);
        let (s, t) = axis.any_orthonormal_pair();
        let dir = (s * (sin_t * phi.cos()) + t * (sin_t * phi.sin()) + axis * cos_t).normalize();
        Some((dir, self.pdf(x, dir, total)))
    }

    /// A point where a parallel beam travelling along unit `direction` crosses toward the
    /// targets, for `u` in [0, 1)^2, and its density per unit area of the plane perpendicular
    /// to `direction` (1 / scene units squared): each target's bounding sphere casts a disc
    /// of its radius across the beam; a disc is chosen with probability proportional to its
    /// area and the point drawn uniformly in it (concentric map, so a stratified `u` stays
    /// stratified). The point lies in the plane through the chosen centre; where discs
    /// overlap the density counts each disc holding the point. A ray through the point along
    /// `direction` that misses every disc cannot reach a specular surface, so light from a
    /// directional lamp needs no other ray. `None` when there is no target.
    pub fn parallel(&self, direction: DVec3, u: Vec2) -> Option<(DVec3, f64)> {
        use std::f64::consts::PI;
        let total: f64 = self.targets.iter().map(|t| PI * t.radius * t.radius).sum();
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = f64::from(u.x) * total;
        let mut acc = 0.0;
        let mut picked = (self.targets[0], 0.5);
        for (j, t) in self.targets.iter().enumerate() {
            let w = PI * t.radius * t.radius;
            if target < acc + w || j + 1 == self.targets.len() {
                picked = (*t, ((target - acc) / w).clamp(0.0, 1.0 - 1e-12));
                break;
            }
            acc += w;
        }
        let (t, ux) = picked;
        let (a, b) = direction.any_orthonormal_pair();
        let (r, phi) = (ux.sqrt() * t.radius, 2.0 * PI * f64::from(u.y));
        let point = t.center + a * (r * phi.cos()) + b * (r * phi.sin());
        let holding = self
            .targets
            .iter()
            .filter(|o| {
                let d = point - o.center;
                (d - direction * d.dot(direction)).length_squared() <= o.radius * o.radius
            })
            .count()
            .max(1);
        Some((point, holding as f64 / total))
    }

    /// Density (1/sr) of [`SpecularTargets::direction`] from `x` toward unit `dir`, given the
    /// cones' total solid angle `total`: each cone holding the direction adds its probability
    /// over its solid angle, (solid / total) / solid = 1 / total.
    fn pdf(&self, x: DVec3, dir: DVec3, total: f64) -> f64 {
        let holding = self
            .targets
            .iter()
            .filter(|t| {
                let (axis, cos_max) = Self::cone(t, x);
                dir.dot(axis) >= cos_max
            })
            .count()
            .max(1);
        holding as f64 / total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn targets(list: &[(DVec3, f64)]) -> SpecularTargets {
        SpecularTargets {
            targets: list
                .iter()
                .enumerate()
                .map(|(i, &(center, radius))| Target {
                    object: i as u32,
                    center,
                    radius,
                })
                .collect(),
        }
    }

    /// The density integrates to 1 over the sphere of directions (Monte Carlo with uniform
    /// directions), and every drawn direction lies in a cone: two overlapping cones.
    #[test]
    fn density_is_normalised_over_overlapping_cones() {
        let t = targets(&[
            (DVec3::new(0.0, 0.0, 5.0), 1.0),
            (DVec3::new(0.8, 0.0, 5.0), 1.5),
        ]);
        let x = DVec3::ZERO;
        let (_, p0) = t.direction(x, Vec2::new(0.3, 0.7)).unwrap();
        let total: f64 = t
            .targets
            .iter()
            .map(|tg| 2.0 * std::f64::consts::PI * (1.0 - SpecularTargets::cone(tg, x).1))
            .sum();
        let n = 400_000;
        let mut integral = 0.0;
        let mut state = 0x1234_5678_u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / (1u64 << 53) as f64
        };
        for _ in 0..n {
            let z = 1.0 - 2.0 * next();
            let phi = 2.0 * std::f64::consts::PI * next();
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            let inside = t.targets.iter().any(|tg| {
                let (axis, c) = SpecularTargets::cone(tg, x);
                d.dot(axis) >= c
            });
            if inside {
                integral += t.pdf(x, d, total);
            }
        }
        integral *= 4.0 * std::f64::consts::PI / f64::from(n);
        assert!((integral - 1.0).abs() < 0.02, "integral {integral}");
        assert!(p0 > 0.0);
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0 + 0.02);
            let (d, _) = t.direction(x, u).unwrap();
            assert!(t.targets.iter().any(|tg| {
                let (axis, c) = SpecularTargets::cone(tg, x);
                d.dot(axis) >= c - 1e-9
            }));
        }
    }

    /// The beam's density integrates to 1 over the plane across it (Monte Carlo over a square
    /// holding both discs), and every drawn point lies in a disc: two overlapping spheres.
    #[test]
    fn parallel_density_is_normalised_over_overlapping_discs() {
        let t = targets(&[
            (DVec3::new(0.0, 0.0, 5.0), 1.0),
            (DVec3::new(0.8, 0.3, 2.0), 1.5),
        ]);
        let dir = DVec3::new(0.0, 0.0, -1.0);
        let density = |p: DVec3| {
            let total: f64 = t
                .targets
                .iter()
                .map(|o| std::f64::consts::PI * o.radius * o.radius)
                .sum();
            let holding = t
                .targets
                .iter()
                .filter(|o| {
                    let d = p - o.center;
                    d.x * d.x + d.y * d.y <= o.radius * o.radius
                })
                .count();
            holding as f64 / total
        };
        let (n, side) = (400, 5.0);
        let mut integral = 0.0;
        for i in 0..n {
            for j in 0..n {
                let p = DVec3::new(
                    -2.5 + side * (f64::from(i) + 0.5) / f64::from(n),
                    -2.5 + side * (f64::from(j) + 0.5) / f64::from(n),
                    0.0,
                );
                integral += density(p);
            }
        }
        integral *= (side / f64::from(n)).powi(2);
        assert!((integral - 1.0).abs() < 0.01, "integral {integral}");
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0 + 0.02);
            let (p, pdf) = t.parallel(dir, u).unwrap();
            let flat = DVec3::new(p.x, p.y, 0.0);
            assert!((pdf - density(flat)).abs() < 1e-12, "{pdf} at {p}");
            assert!(pdf > 0.0);
        }
    }

    #[test]
    fn no_targets_no_direction() {
        assert!(
            SpecularTargets::default()
                .direction(DVec3::ZERO, Vec2::splat(0.5))
                .is_none()
        );
    }
}
