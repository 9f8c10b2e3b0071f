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
        let t = if t <= delta_t {
            // Ahead of the origin, but within the f32 bound of it: decided in f64.
            let v = [kx, ky, kz].map(|a| tri.axes[a].to_array());
            near_t(self.origin.map(|o| o.x), self.shear.map(|s| s.x), v, t_max)?
        } else if t < t_max {
            t
        } else {
            // Beyond `t_max`, or NaN.
            return None;
        };
        let b = e * inv_det;
        Some((t, [b.x, b.y, b.z]))
    }
}

/// A hit the f32 test finds ahead of the ray's origin but cannot tell from `t = 0` (`t`
/// within its error bound), decided again in f64: `t` when the ray meets the triangle's plane
/// farther than a surface point's own rounding from its origin, and before `t_max`.
///
/// The f32 bound grows with the triangle's size, not with the gap: a 1 x 1 wall cannot be
/// told from a ray's origin within about 3e-6 along the ray, so the light a panel 1e-6 from
/// it shoots into it passed through. In f64 the distance is exact to about 1e-15 of the
/// coordinates; a hit nearer than twice a surface point's error bound (`gamma(7)` of its
/// coordinates, [`super::SurfacePoint::on_triangle`]) stays refused, since a point spawned on
/// a neighbouring surface may lie that far behind it. The edge decisions are the f32 test's,
/// so watertightness is unchanged.
///
/// `origin` and `shear` are the sheared ray's in the permuted axes (the shear `(sx, sy, sz)`
/// defines the direction `(-sx, -sy, 1) / sz`), `v[axis][vertex]` the triangle in the same
/// axes.
#[cold]
#[inline(never)]
pub(super) fn near_t(
    origin: [f32; 3],
    shear: [f32; 3],
    v: [[f32; 3]; 3],
    t_max: f32,
) -> Option<f32> {
    let p = [0, 1, 2].map(|i| {
        DVec3::new(
            f64::from(v[0][i]) - f64::from(origin[0]),
            f64::from(v[1][i]) - f64::from(origin[1]),
            f64::from(v[2][i]) - f64::from(origin[2]),
        )
    });
    let d = DVec3::new(-f64::from(shear[0]), -f64::from(shear[1]), 1.0);
    let (a, b) = (p[1] - p[0], p[2] - p[0]);
    let n = a.cross(b);
    let (num, den) = (n.dot(p[0]), n.dot(d));
    // s: the advance along the dominant axis, of the sign of the ray's direction on it, so
    // that |s| is a lower bound of the distance along the ray and t = s * sz.
    let s = num / den;
    let t = s * f64::from(shear[2]);
    if !(t.is_finite() && t > 0.0) {
        return None;
    }
    // A generous bound on the f64 rounding of the differences, the cross product and the
    // dot products (a few units in the last place of each term's magnitude).
    let scale = a.abs().element_sum() * b.abs().element_sum();
    let error =
        16.0 * f64::EPSILON * scale * (p[0].abs().element_sum() + s.abs() * d.abs().element_sum())
            / den.abs();
    let reach = origin.iter().fold(0.0f32, |m, o| m.max(o.abs()));
    let own = 2.0 * f64::from(gamma(7)) * f64::from(reach);
    if s.abs() - error <= own {
        return None;
    }
    let t = t as f32;
    (t > 0.0 && t < t_max).then_some(t)
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
