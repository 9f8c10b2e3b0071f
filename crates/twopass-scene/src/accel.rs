//! Ray queries over an obvhs CWBVH: closest hit and any hit (occlusion), with a watertight
//! ray-triangle test (Woop, Benthin & Wald 2013, as in pbrt-v4) and conservative error bounds,
//! so rays through shared edges and vertices never slip between triangles and spawned rays can
//! be offset safely (see [`SurfacePoint::spawn_origin`]).

use std::time::{Duration, Instant};

use glam::{DVec3, Vec3, Vec3A};
use obvhs::{
    Boundable, BvhBuildParams,
    aabb::Aabb,
    cwbvh::{CwBvh, builder::build_cwbvh},
    ray::{Ray as BvhRay, RayHit},
};

/// `gamma(n)` of Higham / pbrt: a bound on the relative error of n chained f32 operations.
pub(crate) const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// A ray `origin + t * direction`, `t` in (0, `t_max`]; `t` is in multiples of |direction|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin, scene units.
    pub origin: Vec3,
    /// Direction (any non-zero length; unit length makes `t` a distance).
    pub direction: Vec3,
    /// Largest accepted `t`.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            t_max: f32::INFINITY,
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.direction * t
    }
}

/// A point on a scene triangle with what is needed to leave it safely: its geometric normal
/// and a conservative bound on the floating-point error of its position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position, scene units.
    pub position: Vec3,
    /// Unit geometric normal of the triangle (front side by winding).
    pub normal: Vec3,
    /// Absolute error bound of `position` per axis, scene units.
    pub error: Vec3,
    /// Index of the scene triangle.
    pub triangle: u32,
}

impl SurfacePoint {
    /// The point on triangle `(p0, p1, p2)` at barycentrics `(b0, b1, b2)`, with its error bound.
    pub fn on_triangle(p: [Vec3; 3], b: [f32; 3], normal: Vec3, triangle: u32) -> Self {
        let position = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
        let error = ((p[0] * b[0]).abs() + (p[1] * b[1]).abs() + (p[2] * b[2]).abs()) * gamma(7);
        Self {
            position,
            normal,
            error,
            triangle,
        }
    }

    /// The origin for a ray leaving this point toward `direction`: moved off the surface along
    /// the normal by the position's error bound, then rounded away, so the ray cannot hit this
    /// surface again (pbrt-v4's `OffsetRayOrigin`).
    pub fn spawn_origin(&self, direction: Vec3) -> Vec3 {
        let d = self.normal.abs().dot(self.error);
        let mut offset = self.normal * d;
        if direction.dot(self.normal) < 0.0 {
            offset = -offset;
        }
        let mut po = self.position + offset;
        for i in 0..3 {
            if offset[i] > 0.0 {
                po[i] = po[i].next_up();
            } else if offset[i] < 0.0 {
                po[i] = po[i].next_down();
            }
        }
        po
    }
}

/// Shadow rays stop this fraction short of their target, so the target surface itself does not
/// occlude (pbrt's `ShadowEpsilon`, relative to the segment length).
pub(crate) const SHADOW_EPSILON: f32 = 1e-4;

/// The ray in the watertight test's sheared space, computed once per query.
#[derive(Clone, Copy)]
struct ShearedRay {
    origin: Vec3A,
    k: [usize; 3],
    shear: Vec3A,
}

impl ShearedRay {
    fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = Vec3A::new(dir[kx], dir[ky], dir[kz]);
        Self {
            origin: origin.into(),
            k: [kx, ky, kz],
            shear: Vec3A::new(-d.x / d.z, -d.y / d.z, 1.0 / d.z),
        }
    }

    /// Watertight intersection; returns `(t, [b0, b1, b2])` for hits with 0 < t < `t_max`.
    #[inline]
    fn intersect(&self, v: &[Vec3A; 3], t_max: f32) -> Option<(f32, [f32; 3])> {
        let [kx, ky, kz] = self.k;
        let perm = |p: Vec3A| {
            let q = p - self.origin;
            Vec3A::new(q[kx], q[ky], q[kz])
        };
        let (mut p0, mut p1, mut p2) = (perm(v[0]), perm(v[1]), perm(v[2]));
        let s = self.shear;
        p0.x += s.x * p0.z;
        p0.y += s.y * p0.z;
        p1.x += s.x * p1.z;
        p1.y += s.y * p1.z;
        p2.x += s.x * p2.z;
        p2.y += s.y * p2.z;
        let mut e0 = p1.x * p2.y - p1.y * p2.x;
        let mut e1 = p2.x * p0.y - p2.y * p0.x;
        let mut e2 = p0.x * p1.y - p0.y * p1.x;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            // On an edge in f32: decide in f64 so neighbours agree.
            let f = |a: f32, b: f32, c: f32, d: f32| {
                (f64::from(a) * f64::from(b) - f64::from(c) * f64::from(d)) as f32
            };
            e0 = f(p1.x, p2.y, p1.y, p2.x);
            e1 = f(p2.x, p0.y, p2.y, p0.x);
            e2 = f(p0.x, p1.y, p0.y, p1.x);
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return None;
        }
        p0.z *= s.z;
        p1.z *= s.z;
        p2.z *= s.z;
        let t_scaled = e0 * p0.z + e1 * p1.z + e2 * p2.z;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // Conservative bound: reject hits whose t cannot be told from 0.
        let max_z = p0.z.abs().max(p1.z.abs()).max(p2.z.abs());
        let delta_z = gamma(3) * max_z;
        let max_x = p0.x.abs().max(p1.x.abs()).max(p2.x.abs());
        let max_y = p0.y.abs().max(p1.y.abs()).max(p2.y.abs());
        let delta_x = gamma(5) * (max_x + max_z);
        let delta_y = gamma(5) * (max_y + max_z);
        let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        let delta_t =
            3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs();
        if t <= delta_t || t >= t_max || t.is_nan() {
            return None;
        }
        Some((t, [e0 * inv_det, e1 * inv_det, e2 * inv_det]))
    }
}

/// obvhs's node test ignores boxes that end before t = 1e-4 in units of the ray direction.
/// Directions handed to obvhs are scaled by this exact power of two (and t by its inverse), so
/// that cut-off becomes 1e-4 / 65536 of a direction length: hits that close to the origin are
/// still found. Power-of-two scaling is exact, so nothing else changes.
const T_SCALE: f32 = 65536.0;
const DIR_SCALE: f32 = 1.0 / T_SCALE;

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
const MAX_INVERSE: f32 = 1e20;

/// Relative padding of primitive bounds: obvhs's slab test can round a ray that passes exactly
/// through a box's corner or edge (a triangle vertex on the box face) to a miss. Boxes grow by
/// this fraction of the scene's extent, far above the few ulps of rounding.
const BOX_PADDING: f32 = 1e-5;

/// A triangle as the BVH builder sees it: its bounds, padded.
struct Padded {
    aabb: Aabb,
}

impl Boundable for Padded {
    fn aabb(&self) -> Aabb {
        self.aabb
    }
}

/// The ray as obvhs traverses it: direction scaled by [`DIR_SCALE`] and the exact inverse
/// direction (obvhs's own constructor clamps components below f32::EPSILON, which would cull
/// boxes wrongly for the scaled direction). Negative zeros become positive: the node test
/// orders each slab by `direction < 0` while a -0.0 component has a negative inverse, and the
/// mismatch culls every box (an axis-aligned ray such as `-Vec3::Z` would hit nothing).
fn bvh_ray(origin: Vec3, direction: Vec3, t_max: f32) -> BvhRay {
    let d = Vec3A::from(direction) * DIR_SCALE + Vec3A::ZERO;
    let inv = |x: f32| {
        let i = 1.0 / x;
        if i.abs() > MAX_INVERSE {
            MAX_INVERSE.copysign(x)
        } else {
            i
        }
    };
    BvhRay {
        origin: origin.into(),
        direction: d,
        inv_direction: Vec3A::new(inv(d.x), inv(d.y), inv(d.z)),
        tmin: 0.0,
        tmax: t_max * T_SCALE,
    }
}

/// The result of a closest-hit query: which triangle, where along the ray, barycentrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Scene triangle index.
    pub triangle: u32,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2 (sum 1).
    pub barycentric: [f32; 3],
}

/// A CWBVH over the scene's triangles with the queries every pass uses.
pub struct Accel {
    bvh: CwBvh,
    /// Triangle vertices in BVH slot order.
    tris: Vec<[Vec3A; 3]>,
    /// BVH slot -> scene triangle index.
    ids: Vec<u32>,
    build_time: Duration,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.tris.len())
            .field("nodes", &self.bvh.nodes.len())
            .field("build_time", &self.build_time)
            .finish()
    }
}

impl Accel {
    /// Builds the BVH over `triangles` (vertex indices into `positions`) with obvhs's
    /// `medium_build` preset. Triangles must be valid (finite, non-degenerate), as the loader
    /// guarantees; an empty list gives an accelerator that hits nothing.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        Self::build_with(positions, triangles, BvhBuildParams::medium_build())
    }

    /// Builds the BVH with explicit obvhs build parameters.
    pub fn build_with(positions: &[Vec3], triangles: &[[u32; 3]], params: BvhBuildParams) -> Self {
        let start = Instant::now();
        let corners: Vec<[Vec3A; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| Vec3A::from(positions[i as usize])))
            .collect();
        let (lo, hi) = corners.iter().flatten().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let extent = if corners.is_empty() {
            0.0
        } else {
            (hi - lo).length() + lo.abs().max(hi.abs()).max_element()
        };
        let pad = Vec3A::splat(BOX_PADDING * extent);
        let boxes: Vec<Padded> = corners
            .iter()
            .map(|c| Padded {
                aabb: Aabb {
                    min: c[0].min(c[1]).min(c[2]) - pad,
                    max: c[0].max(c[1]).max(c[2]) + pad,
                },
            })
            .collect();
        let bvh = build_cwbvh(&boxes, params, &mut Duration::default());
        let ids = bvh.primitive_indices.clone();
        let tris = ids.iter().map(|&i| corners[i as usize]).collect();
        Self {
            bvh,
            tris,
            ids,
            build_time: start.elapsed(),
        }
    }

    /// Wall-clock time the build took, including the BVH-order copy of the triangles.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Number of BVH nodes (8-wide).
    pub fn node_count(&self) -> usize {
        self.bvh.nodes.len()
    }

    /// The closest hit with `0 < t < t_max`, if any.
    pub fn closest(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<TriangleHit> {
        if self.tris.is_empty() {
            return None;
        }
        let sheared = ShearedRay::new(origin, direction);
        let mut hit = RayHit::none();
        let found =
            self.bvh
                .ray_traverse(bvh_ray(origin, direction, t_max), &mut hit, |r, slot| {
                    sheared
                        .intersect(&self.tris[slot], r.tmax * DIR_SCALE)
                        .map_or(f32::INFINITY, |(t, _)| t * T_SCALE)
                });
        if !found {
            return None;
        }
        let slot = hit.primitive_id as usize;
        // Barycentrics of the winner only (cheaper than computing them for every candidate).
        let (t, barycentric) = sheared.intersect(&self.tris[slot], f32::INFINITY)?;
        Some(TriangleHit {
            triangle: self.ids[slot],
            t,
            barycentric,
        })
    }

    /// Whether anything is hit with `0 < t < t_max`; stops at the first hit found.
    pub fn any_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let sheared = ShearedRay::new(origin, direction);
        !self
            .bvh
            .ray_traverse_miss(bvh_ray(origin, direction, t_max), |r, slot| {
                sheared
                    .intersect(&self.tris[slot], r.tmax * DIR_SCALE)
                    .map_or(f32::INFINITY, |(t, _)| t * T_SCALE)
            })
    }

    /// Reference answer by testing every triangle, O(n): the oracle for BVH tests.
    pub fn closest_brute_force(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let sheared = ShearedRay::new(origin, direction);
        let mut best: Option<TriangleHit> = None;
        for (i, t) in triangles.iter().enumerate() {
            let v = t.map(|k| Vec3A::from(positions[k as usize]));
            let limit = best.map_or(t_max, |b| b.t);
            if let Some((t, barycentric)) = sheared.intersect(&v, limit) {
                best = Some(TriangleHit {
                    triangle: i as u32,
                    t,
                    barycentric,
                });
            }
        }
        best
    }
}

/// Twice the area of a triangle and its unit normal in f64, `None` when degenerate: the cross
/// product is zero, not finite, or tiny against the edge lengths (the normal is then noise).
pub(crate) fn triangle_normal(p: [Vec3; 3]) -> Option<(f64, DVec3)> {
    let (a, b) = ((p[1] - p[0]).as_dvec3(), (p[2] - p[0]).as_dvec3());
    let c = a.cross(b);
    let len = c.length();
    let scale = a.length() * b.length();
    if !(len.is_finite() && len > 0.0 && len > f64::from(f32::EPSILON) * scale) {
        return None;
    }
    Some((len, c / len))
}
