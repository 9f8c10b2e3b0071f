//! Rays, points on surfaces, and leaving a surface safely: pbrt-v4's floating-point error
//! bounds and origin offsetting, so no caller of the ray queries carries an epsilon.

use glam::Vec3;

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
        let po = self.position + offset;
        // Then at least one more float along each axis the offset moves (branch-free, where
        // pbrt steps to the next float per axis): |x| * EPSILON is at least the spacing of
        // floats at x (and the smallest normal float covers x = 0), so the rounded sum lands
        // on or beyond the next float.
        let up = Vec3::select(offset.cmpgt(Vec3::ZERO), Vec3::ONE, Vec3::ZERO);
        let down = Vec3::select(offset.cmplt(Vec3::ZERO), Vec3::ONE, Vec3::ZERO);
        po + (up - down) * (po.abs() * f32::EPSILON + Vec3::splat(f32::MIN_POSITIVE))
    }
}

/// Shadow rays stop this fraction short of their target, so the target surface itself does not
/// occlude (pbrt's `ShadowEpsilon`, relative to the segment length).
pub(crate) const SHADOW_EPSILON: f32 = 1e-4;
