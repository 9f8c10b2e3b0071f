//! Shaft culling (Haines & Wallace 1991) for the visibility between a point and a triangle:
//! the segments from the point to every point of the triangle fill a tetrahedron, so when no
//! scene triangle can reach into that tetrahedron (the BVH, walked with the tetrahedron, finds
//! none) every such segment is unblocked, and no shadow ray needs to be cast. The same test
//! with the convex hull of two triangles clears every segment between them at once: one test
//! per pair of patches instead of one per receiving vertex.
//!
//! The test is conservative: a triangle is a candidate blocker unless it is clearly outside
//! the tetrahedron (all three corners beyond one of its face planes, or its bounds outside the
//! tetrahedron's), behind the receiver's own plane (when the whole shooter is in front of it),
//! or cannot cross a segment (every corner of the shaft on one side of the triangle's
//! plane, as for the receiver's and the shooter's own surfaces). "Clearly" is a tolerance of
//! [`SHAFT_TOLERANCE`] of the coordinates' size, above the offsets the shadow rays themselves
//! leave their surfaces by.

use glam::{Vec3, Vec4};

use super::bvh::Node8;
use super::quad::TriangleQuad;

/// Relative tolerance of the shaft test (of the largest coordinate of the tetrahedron): the
/// tetrahedron's faces move out by this much, and a triangle must be this far from the
/// tetrahedron's corners on both sides of its plane to count as crossing. Shadow rays leave
/// and reach surfaces offset by `gamma(7)` (about 4e-7) of the coordinates, well inside it.
pub const SHAFT_TOLERANCE: f32 = 2e-6;

/// A convex region given by its corners and bounding planes, set up for box and triangle
/// tests: the tetrahedron of an apex and a base triangle (`Shaft<5, 4>`, [`Shaft::new`]), or
/// the convex hull of two triangles (`Shaft<22, 6>`, [`Shaft::hull`]).
pub(super) struct Shaft<const PLANES: usize, const CORNERS: usize> {
    /// Outward face planes `(n, d)`, moved out by the tolerance: `n . p + d > 0` is outside;
    /// the first `count` are used. A face of a flat tetrahedron has no plane and culls
    /// nothing.
    planes: [(Vec3, f32); PLANES],
    count: usize,
    /// Bounds of the corners, grown by the tolerance.
    lo: Vec3,
    hi: Vec3,
    corners: [Vec3; CORNERS],
    /// The tolerance in scene units.
    eps: f32,
}

/// The tolerance of a shaft with these corners, scene units: [`SHAFT_TOLERANCE`] of the
/// largest coordinate.
fn tolerance(corners: &[Vec3]) -> f32 {
    let scale = corners
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0f32, f32::max);
    SHAFT_TOLERANCE * scale
}

/// Bounds of `corners`, grown by `eps`.
fn bounds(corners: &[Vec3], eps: f32) -> (Vec3, Vec3) {
    let (lo, hi) = corners.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (lo - eps, hi + eps)
}

/// The plane through `p` with unit normal `-n` moved in by `eps`: outside it is what lies
/// behind the plane of `p` and `n` or less than `eps` in front of it. Nothing there can block
/// a segment from that plane to a point more than `eps` in front of it.
fn in_front(p: Vec3, n: Vec3, eps: f32) -> (Vec3, f32) {
    (-n, n.dot(p) + eps)
}

impl Shaft<5, 4> {
    /// The tetrahedron of `apex` and `base`; with `apex_normal`, also the half-space in front
    /// of the plane through `apex` with that normal, when the whole base is in front of it
    /// (then every segment is, and whatever lies behind or in that plane cannot block one).
    pub(super) fn new(apex: Vec3, apex_normal: Option<Vec3>, base: [Vec3; 3]) -> Self {
        let corners = [apex, base[0], base[1], base[2]];
        let eps = tolerance(&corners);
        let mut planes = [(Vec3::ZERO, 0.0); 5];
        let mut count = 0;
        let mut push = |plane: (Vec3, f32)| {
            planes[count] = plane;
            count += 1;
        };
        // Face opposite corner `o`, through the other three. In f32: a plane's rounding
        // (a few ulps of the coordinates) is far inside the tolerance it is moved out by.
        for o in 0..4 {
            let [p, q, r] = [(o + 1) % 4, (o + 2) % 4, (o + 3) % 4].map(|i| corners[i]);
            let n = (q - p).cross(r - p);
            let len = n.length();
            if !(len.is_finite() && len > 0.0) {
                continue;
            }
            let side = n.dot(corners[o] - p);
            if side.abs() <= eps * len {
                // The opposite corner is (nearly) in this face's plane: flat tetrahedron.
                continue;
            }
            let n = if side > 0.0 { -n / len } else { n / len };
            push((n, -n.dot(p) - eps));
        }
        if let Some(n) = apex_normal {
            let front = |p: Vec3| n.dot(p - apex) > eps;
            if base.iter().all(|&p| front(p)) {
                push(in_front(apex, n, eps));
            }
        }
        Self::from_parts(planes, count, corners, eps)
    }
}

impl Shaft<22, 6> {
    /// The convex hull of triangles `a` and `b` (unit geometric normals `na`, `nb`): its
    /// facets are the planes through three of the six corners with the other three behind
    /// (at most 20 candidates). When all of `b` is in front of `a`'s plane, nothing behind or
    /// in that plane counts (as for [`Shaft::new`]'s apex), and the same for `a` and `b`'s
    /// plane. `None` when the six corners lie in one plane: the hull is flat and cannot stand
    /// for the segments between them.
    pub(super) fn hull(a: [Vec3; 3], na: Vec3, b: [Vec3; 3], nb: Vec3) -> Option<Self> {
        let corners = [a[0], a[1], a[2], b[0], b[1], b[2]];
        let eps = tolerance(&corners);
        let mut planes = [(Vec3::ZERO, 0.0); 22];
        let mut count = 0;
        let mut solid = false;
        for i in 0..6 {
            for j in i + 1..6 {
                for k in j + 1..6 {
                    let p = corners[i];
                    let n = (corners[j] - p).cross(corners[k] - p);
                    let len = n.length();
                    if !(len.is_finite() && len > 0.0) {
                        continue;
                    }
                    let n = n / len;
                    let (lo, hi) = corners
                        .iter()
                        .map(|&q| n.dot(q - p))
                        .fold((0.0f32, 0.0f32), |(lo, hi), d| (lo.min(d), hi.max(d)));
                    solid |= lo < -eps || hi > eps;
                    // A facet: every corner behind it (up to the tolerance it moves out by).
                    let outward = if hi <= eps {
                        n
                    } else if lo >= -eps {
                        -n
                    } else {
                        continue;
                    };
                    let d = -outward.dot(p) - eps;
                    let same = planes[..count].iter().any(|&(m, e): &(Vec3, f32)| {
                        m.dot(outward) > 1.0 - 1e-6 && (e - d).abs() <= eps
                    });
                    if !same {
                        planes[count] = (outward, d);
                        count += 1;
                    }
                }
            }
        }
        if !solid {
            return None;
        }
        for (own, n, other) in [(a, na, b), (b, nb, a)] {
            if other.iter().all(|&q| n.dot(q - own[0]) > eps) {
                planes[count] = in_front(own[0], n, eps);
                count += 1;
            }
        }
        Some(Self::from_parts(planes, count, corners, eps))
    }
}

impl<const PLANES: usize, const CORNERS: usize> Shaft<PLANES, CORNERS> {
    /// The shaft of the first `count` of `planes` and `corners`, with the corners' bounds, all
    /// grown by the tolerance `eps`.
    fn from_parts(
        planes: [(Vec3, f32); PLANES],
        count: usize,
        corners: [Vec3; CORNERS],
        eps: f32,
    ) -> Self {
        let (lo, hi) = bounds(&corners, eps);
        Self {
            planes,
            count,
            lo,
            hi,
            corners,
            eps,
        }
    }

    /// The children of `node` whose boxes may reach into the shaft (bit `c` for child `c`).
    #[inline(always)]
    pub(super) fn overlap(&self, node: &Node8) -> u32 {
        let b = &node.bounds;
        let mut mask = 0u32;
        for half in 0..2 {
            let min = |axis: usize| b[4 * axis + half];
            let max = |axis: usize| b[4 * axis + 2 + half];
            let (lo, hi) = (self.lo, self.hi);
            let mut inside = min(0).cmple(Vec4::splat(hi.x))
                & max(0).cmpge(Vec4::splat(lo.x))
                & min(1).cmple(Vec4::splat(hi.y))
                & max(1).cmpge(Vec4::splat(lo.y))
                & min(2).cmple(Vec4::splat(hi.z))
                & max(2).cmpge(Vec4::splat(lo.z));
            for &(n, d) in &self.planes[..self.count] {
                // The box corner least far along `n`: outside the plane, the box is too.
                let pick = |axis: usize| if n[axis] >= 0.0 { min(axis) } else { max(axis) };
                let dist = pick(0) * n.x + pick(1) * n.y + pick(2) * n.z + Vec4::splat(d);
                inside &= !dist.cmpgt(Vec4::ZERO);
            }
            mask |= inside.bitmask() << (4 * half);
        }
        mask
    }

    /// Whether any enabled lane (bits of `lanes`) of `quad` may block a segment inside the
    /// shaft.
    #[inline(always)]
    pub(super) fn may_block(&self, quad: &TriangleQuad, lanes: u32) -> bool {
        let v = &quad.v;
        let p = |vertex: usize| [v[0][vertex], v[1][vertex], v[2][vertex]];
        let (a, b, c) = (p(0), p(1), p(2));
        let zero = Vec4::ZERO;
        let mut keep = !0u32;
        // Bounds.
        let lo = [self.lo.x, self.lo.y, self.lo.z];
        let hi = [self.hi.x, self.hi.y, self.hi.z];
        for axis in 0..3 {
            let min = a[axis].min(b[axis]).min(c[axis]);
            let max = a[axis].max(b[axis]).max(c[axis]);
            keep &= (min.cmple(Vec4::splat(hi[axis])) & max.cmpge(Vec4::splat(lo[axis]))).bitmask();
        }
        // All three corners outside one face plane.
        for &(n, d) in &self.planes[..self.count] {
            let dist = |q: [Vec4; 3]| q[0] * n.x + q[1] * n.y + q[2] * n.z + Vec4::splat(d);
            let out = dist(a).cmpgt(zero) & dist(b).cmpgt(zero) & dist(c).cmpgt(zero);
            keep &= !out.bitmask();
        }
        // The shaft on one side of the triangle's plane: no segment crosses it.
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let tol = len * Vec4::splat(self.eps);
        let (mut above, mut below) = (0u32, 0u32);
        for q in &self.corners {
            let d = n[0] * (Vec4::splat(q.x) - a[0])
                + n[1] * (Vec4::splat(q.y) - a[1])
                + n[2] * (Vec4::splat(q.z) - a[2]);
            above |= d.cmpgt(tol).bitmask();
            below |= d.cmplt(-tol).bitmask();
        }
        keep &= above & below;
        keep & lanes != 0
    }
}
