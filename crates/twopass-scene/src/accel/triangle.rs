//! The watertight ray-triangle test (Woop, Benthin & Wald 2013, as in pbrt-v4) with a
//! conservative bound on `t`, one triangle at a time, and the degenerate-triangle check.

use glam::{DVec3, Vec3, Vec3A, Vec3Swizzles};

use super::ray::gamma;

/// A triangle stored by axis for the watertight test: `axes[a]` holds coordinate `a` of
/// vertices 0, 1 and 2 (lanes x, y, z). The test then permutes the axes of all three vertices
/// at once by picking rows, instead of indexing every vertex with the ray's permutation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct AxisTriangle {
    pub(super) axes: [Vec3A; 3],
}

impl AxisTriangle {
    pub(super) fn new(v: [Vec3A; 3]) -> Self {
        Self {
            axes: [
                Vec3A::new(v[0].x, v[1].x, v[2].x),
                Vec3A::new(v[0].y, v[1].y, v[2].y),
                Vec3A::new(v[0].z, v[1].z, v[2].z),
            ],
        }
    }
}

/// The ray in the watertight test's sheared space, computed once per query.
#[derive(Clone, Copy)]
pub(super) struct ShearedRay {
    /// Axis permutation: `k[2]` is the dominant direction axis.
    pub(super) k: [usize; 3],
    /// Origin coordinates in permuted order, each splatted over the three vertex lanes.
    pub(super) origin: [Vec3A; 3],
    /// Shear of x and y by z, and the scale of z, splatted.
    pub(super) shear: [Vec3A; 3],
}

impl ShearedRay {
    pub(super) fn new(origin: Vec3, dir: Vec3) -> Self {
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
        // Arrays, not `Vec3`'s index (a branch per component taken by a variable index).
        let (dir, origin) = (dir.to_array(), origin.to_array());
        let d = Vec3::new(dir[kx], dir[ky], dir[kz]);
        Self {
            k: [kx, ky, kz],
            origin: [
                Vec3A::splat(origin[kx]),
                Vec3A::splat(origin[ky]),
                Vec3A::splat(origin[kz]),
            ],
            shear: [
                Vec3A::splat(-d.x / d.z),
                Vec3A::splat(-d.y / d.z),
                Vec3A::splat(1.0 / d.z),
            ],
        }
    }

    /// Watertight intersection; returns `(t, [b0, b1, b2])` for hits with 0 < t < `t_max`.
    ///
    /// Lane `i` of `px`, `py`, `pz` is vertex `i` in the ray's sheared space; every lane sees
    /// exactly the operations of the scalar formulation (no fused multiply-add), so the edge
    /// functions of a shared edge are bit-identical for both triangles.
    #[inline(always)]
    pub(super) fn intersect(&self, tri: &AxisTriangle, t_max: f32) -> Option<(f32, [f32; 3])> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let pz = tri.axes[kz] - self.origin[2];
        let px = (tri.axes[kx] - self.origin[0]) + sx * pz;
        let py = (tri.axes[ky] - self.origin[1]) + sy * pz;
        // e_i = p_{i+1}.x * p_{i+2}.y - p_{i+1}.y * p_{i+2}.x, all three lanes at once.
        let mut e = px.yzx() * py.zxy() - py.yzx() * px.zxy();
        if e.cmpeq(Vec3A::ZERO).any() {
            // On an edge in f32: decide in f64 so neighbours agree.
            let f = |a: f32, b: f32, c: f32, d: f32| {
                (f64::from(a) * f64::from(b) - f64::from(c) * f64::from(d)) as f32
            };
            e = Vec3A::new(
                f(px.y, py.z, py.y, px.z),
                f(px.z, py.x, py.z, px.x),
                f(px.x, py.y, py.x, px.y),
            );
        }
        if e.cmplt(Vec3A::ZERO).any() && e.cmpgt(Vec3A::ZERO).any() {
            return None;
        }
        let det = e.x + e.y + e.z;
        if det == 0.0 {
            return None;
        }
        let pz = pz * sz;
        let ez = e * pz;
        let t_scaled = ez.x + ez.y + ez.z;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // Conservative bound: reject hits whose t cannot be told from 0.
        let max_z = pz.abs().max_element();
        let delta_z = gamma(3) * max_z;
        let max_x = px.abs().max_element();
        let max_y = py.abs().max_element();
        let delta_x = gamma(5) * (max_x + max_z);
        let delta_y = gamma(5) * (max_y + max_z);
        let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = e.abs().max_element();
        let delta_t =
            3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs();
        if t <= delta_t || t >= t_max || t.is_nan() {
            return None;
        }
        let b = e * inv_det;
        Some((t, [b.x, b.y, b.z]))
    }
}

/// Twice the area of a triangle and its unit normal in f64, `None` when degenerate: the cross
/// product is zero, not finite, or tiny against the edge lengths (the normal is then noise).
/// "Tiny" is a sine of the triangle's smallest angle (between its two longest edges) below f32
/// epsilon: such a needle cannot be resolved in f32 positions, and bisecting it, as the
/// radiosity mesher does, never ends.
pub(crate) fn triangle_normal(p: [Vec3; 3]) -> Option<(f64, DVec3)> {
    let (a, b) = ((p[1] - p[0]).as_dvec3(), (p[2] - p[0]).as_dvec3());
    let c = a.cross(b);
    let len = c.length();
    let mut edges = [a.length(), b.length(), (b - a).length()];
    edges.sort_by(f64::total_cmp);
    let scale = edges[1] * edges[2];
    if !(len.is_finite() && len > 0.0 && len > f64::from(f32::EPSILON) * scale) {
        return None;
    }
    Some((len, c / len))
}
