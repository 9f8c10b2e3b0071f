//! Triangle quads, the BVH's leaves: up to four triangles stored for the watertight test on
//! all four at once (one ray, four lanes), bit for bit the operations of the scalar test in
//! `triangle.rs`, and on one triangle against up to eight rays at once (rays in lanes,
//! [`RayLanes`]), bit for bit the four-triangle test's.

use glam::{Vec3A, Vec4};
use wide::f32x8;

use super::arena::{Arena, Block32};
use super::prefetch::prefetch;
use super::ray::gamma;
use super::triangle::{ShearedRay, near_t};

/// Blocks of one [`TriangleQuad`] (160 bytes: three cache lines wherever it starts on a block).
pub(super) const QUAD_BLOCKS: usize = 5;

const _: () = assert!(std::mem::size_of::<TriangleQuad>() == 32 * QUAD_BLOCKS);
const _: () = assert!(std::mem::align_of::<TriangleQuad>() <= std::mem::align_of::<Block32>());

/// A triangle quad: up to four triangles (one BVH leaf, or several leaves of one node) stored
/// for a one-ray, four-triangle watertight test: `v[axis][vertex]` holds that coordinate of
/// that vertex for the four triangles (lanes), `ids[lane]` the scene index of the triangle.
/// Lanes past the leaf's triangles are zero, name no triangle (`u32::MAX`) and are never
/// enabled.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct TriangleQuad {
    pub(super) v: [[Vec4; 3]; 3],
    /// Scene triangle indices, beside the vertices: a hit's index is read from (or next to)
    /// the cache lines its test just loaded, not from a table of its own.
    pub(super) ids: [u32; 4],
}

impl TriangleQuad {
    /// The quad of triangles `ids` with corners `tris` (at most four).
    pub(super) fn new(tris: &[[Vec3A; 3]], ids: &[u32]) -> Self {
        let mut v = [[[0.0f32; 4]; 3]; 3];
        for (lane, t) in tris.iter().enumerate() {
            for (vertex, p) in t.iter().enumerate() {
                for axis in 0..3 {
                    v[axis][vertex][lane] = p[axis];
                }
            }
        }
        Self {
            v: v.map(|a| a.map(Vec4::from_array)),
            ids: [0, 1, 2, 3].map(|lane| ids.get(lane).copied().unwrap_or(u32::MAX)),
        }
    }

    /// Starts loading the quad's three cache lines (160 bytes from a 32-byte boundary).
    #[inline(always)]
    pub(super) fn prefetch(&self) {
        prefetch(&self.v[0][0]);
        prefetch(&self.v[1][1]);
        prefetch(&self.v[2][2]);
    }
}

impl Arena {
    /// The quad at block `at`.
    #[inline(always)]
    pub(super) fn quad(&self, at: u32) -> &TriangleQuad {
        self.item::<TriangleQuad, QUAD_BLOCKS>(at)
    }
}

/// Four-lane (`Vec4`) and eight-lane (`f32x8`) vectors, for the part of the watertight test
/// written once for both ([`solve`]): a ray against four triangles, or a triangle against
/// eight rays.
pub(super) trait Lanes:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    /// A lane-wise comparison's result.
    type Mask: Copy + std::ops::BitOr<Output = Self::Mask> + std::ops::BitAnd<Output = Self::Mask>;
    fn splat(x: f32) -> Self;
    fn abs(self) -> Self;
    fn max(self, other: Self) -> Self;
    fn lt(self, other: Self) -> Self::Mask;
    fn gt(self, other: Self) -> Self::Mask;
    fn le(self, other: Self) -> Self::Mask;
    fn ge(self, other: Self) -> Self::Mask;
    fn eq(self, other: Self) -> Self::Mask;
    /// Bit `i` set where lane `i` of `mask` is.
    fn bits(mask: Self::Mask) -> u32;
    /// Lane `i`.
    fn lane(self, i: usize) -> f32;
    /// `self` with lane `i` set to `x`.
    fn with_lane(self, i: usize, x: f32) -> Self;
}

/// [`Lanes`] for a vector type through its own functions: the mask type, the bitmask method,
/// and for each comparison the method that makes it.
macro_rules! lanes {
    ($t:ty, $mask:ty, $bits:ident, $($cmp:ident => $method:ident),*) => {
        impl Lanes for $t {
            type Mask = $mask;
            #[inline(always)]
            fn splat(x: f32) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            $(
                #[inline(always)]
                fn $cmp(self, other: Self) -> Self::Mask {
                    self.$method(other)
                }
            )*
            #[inline(always)]
            fn bits(mask: Self::Mask) -> u32 {
                mask.$bits()
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f32 {
                self.to_array()[i]
            }
            #[inline(always)]
            fn with_lane(self, i: usize, x: f32) -> Self {
                let mut a = self.to_array();
                a[i] = x;
                <$t>::from(a)
            }
        }
    };
}

lanes!(Vec4, glam::BVec4A, bitmask, lt => cmplt, gt => cmpgt, le => cmple, ge => cmpge, eq => cmpeq);
lanes!(f32x8, f32x8, to_bitmask, lt => simd_lt, gt => simd_gt, le => simd_le, ge => simd_ge, eq => simd_eq);

/// What a watertight test ([`solve`]) finds, per lane: `t`, the three edge functions and
/// `1 / det` to form barycentrics from, and the lanes that hit. Lanes are triangles of a
/// [`TriangleQuad`] for one ray ([`QuadHits`]) or rays for one triangle ([`LaneHits`]).
pub(super) struct Hits<L> {
    pub(super) t: L,
    pub(super) e: [L; 3],
    pub(super) inv_det: L,
    pub(super) mask: u32,
    /// Lanes whose `t` the f32 bound cannot tell from 0, for the caller to decide in f64
    /// ([`super::triangle::near_t`]); not in `mask`.
    pub(super) near: u32,
}

/// The hits of one ray against a [`TriangleQuad`]'s four triangles ([`QuadRay::intersect`]).
pub(super) type QuadHits = Hits<Vec4>;

/// The hits of up to eight rays against one triangle ([`RayLanes::intersect`]).
pub(super) type LaneHits = Hits<f32x8>;

impl<L: Lanes> Hits<L> {
    /// `t` of lane `lane`.
    pub(super) fn t_of(&self, lane: usize) -> f32 {
        self.t.lane(lane)
    }

    /// Barycentrics of lane `lane`.
    pub(super) fn barycentric(&self, lane: usize) -> [f32; 3] {
        self.e.map(|e| e.lane(lane) * self.inv_det.lane(lane))
    }

    /// Decides the lanes in `near` by `decide(lane)` (the hit's `t` in f64,
    /// [`super::triangle::near_t`], or `None`): a lane it gives a `t` becomes a hit at it.
    #[inline(always)]
    fn decide_near(&mut self, mut decide: impl FnMut(usize) -> Option<f32>) {
        while self.near != 0 {
            let l = self.near.trailing_zeros() as usize;
            self.near &= self.near - 1;
            if let Some(t) = decide(l) {
                self.t = self.t.with_lane(l, t);
                self.mask |= 1 << l;
            }
        }
    }
}

/// The watertight test's steps after the shear, lane by lane (Woop et al. 2013, as in
/// pbrt-v4): from each lane's sheared vertex coordinates `px`, `py` and unscaled `pz`, the
/// ray's z scale `sz` and bound `bound`, whether the enabled lanes (bits of `lanes`) hit with
/// `0 < t < bound`, and where. Every lane goes through the scalar test's operations in its
/// order (no fused multiply-add; an edge function of exactly 0 decided again in f64), so
/// four lanes and eight agree bit for bit with it and with each other.
#[inline(always)]
fn solve<L: Lanes>(px: [L; 3], py: [L; 3], pz: [L; 3], sz: L, bound: L, lanes: u32) -> Hits<L> {
    let mut e = [
        px[1] * py[2] - py[1] * px[2],
        px[2] * py[0] - py[2] * px[0],
        px[0] * py[1] - py[0] * px[1],
    ];
    let zero = L::splat(0.0);
    let on_edge = L::bits(e[0].eq(zero) | e[1].eq(zero) | e[2].eq(zero)) & lanes;
    if on_edge != 0 {
        // On an edge in f32: decide in f64 so neighbours agree (as the scalar test).
        let f = |a: f32, b: f32, c: f32, d: f32| {
            (f64::from(a) * f64::from(b) - f64::from(c) * f64::from(d)) as f32
        };
        let (x, y) = (
            |v: usize, l: usize| px[v].lane(l),
            |v: usize, l: usize| py[v].lane(l),
        );
        let mut bits = on_edge;
        while bits != 0 {
            let l = bits.trailing_zeros() as usize;
            e[0] = e[0].with_lane(l, f(x(1, l), y(2, l), y(1, l), x(2, l)));
            e[1] = e[1].with_lane(l, f(x(2, l), y(0, l), y(2, l), x(0, l)));
            e[2] = e[2].with_lane(l, f(x(0, l), y(1, l), y(0, l), x(1, l)));
            bits &= bits - 1;
        }
    }
    let neg = e[0].lt(zero) | e[1].lt(zero) | e[2].lt(zero);
    let pos = e[0].gt(zero) | e[1].gt(zero) | e[2].gt(zero);
    if lanes & !L::bits(neg & pos) == 0 {
        // Every enabled lane is missed on the edge functions alone (most tests): no
        // division, no distance.
        return Hits {
            t: zero,
            e,
            inv_det: zero,
            mask: 0,
            near: 0,
        };
    }
    let det = e[0] + e[1] + e[2];
    let pz = pz.map(|z| z * sz);
    let t_scaled = e[0] * pz[0] + e[1] * pz[1] + e[2] * pz[2];
    let limit = bound * det;
    let behind_neg = det.lt(zero) & (t_scaled.ge(zero) | t_scaled.lt(limit));
    let behind_pos = det.gt(zero) & (t_scaled.le(zero) | t_scaled.gt(limit));
    let miss = (neg & pos) | det.eq(zero) | behind_neg | behind_pos;
    let mut mask = lanes & !L::bits(miss);
    let inv_det = L::splat(1.0) / det;
    let t = t_scaled * inv_det;
    let mut near = 0;
    if mask != 0 {
        // Conservative bound: reject hits whose t cannot be told from 0; t > delta_t and
        // t < bound, both false for NaN. Lanes ahead of the origin but within the bound are
        // left to f64 ([`super::triangle::near_t`]).
        let delta_t = t_error(px, py, pz, e, inv_det);
        near = mask & L::bits(t.le(delta_t));
        mask &= L::bits(t.gt(delta_t) & t.lt(bound));
    }
    Hits {
        t,
        e,
        inv_det,
        mask,
        near,
    }
}

/// Per lane, the watertight test's conservative bound on the error of `t` (Woop et al. 2013,
/// as in pbrt-v4), from the sheared vertex coordinates `px`, `py`, the scaled `pz`, the edge
/// functions `e` and `1 / det`: a hit whose `t` is not above it cannot be told from 0. The
/// same operations in the same order for four and for eight lanes, so both tests' bounds
/// agree bit for bit.
#[inline(always)]
fn t_error<L: Lanes>(px: [L; 3], py: [L; 3], pz: [L; 3], e: [L; 3], inv_det: L) -> L {
    let max3 = |a: [L; 3]| a[0].abs().max(a[1].abs()).max(a[2].abs());
    let max_z = max3(pz);
    let max_x = max3(px);
    let max_y = max3(py);
    let max_e = max3(e);
    let delta_z = L::splat(gamma(3)) * max_z;
    let delta_x = L::splat(gamma(5)) * (max_x + max_z);
    let delta_y = L::splat(gamma(5)) * (max_y + max_z);
    let delta_e =
        L::splat(2.0) * (L::splat(gamma(2)) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    L::splat(3.0)
        * (L::splat(gamma(3)) * max_e * max_z + delta_e * max_z + delta_z * max_e)
        * inv_det.abs()
}

impl QuadHits {
    /// The lane with the smallest `t` among the hits (there must be one), and of lanes at
    /// equal `t` the one with the smallest triangle index (`ids`, the quad's), so that the
    /// answer does not depend on the order a walk meets triangles in.
    pub(super) fn nearest(&self, ids: &[u32; 4]) -> usize {
        // As an array: `Vec4`'s index by a variable lane is a jump table. The `& 3` only
        // tells the compiler a lane is below 4, so it drops the bounds checks.
        let t = self.t.to_array();
        let mut best = self.mask.trailing_zeros() as usize & 3;
        let mut rest = self.mask & (self.mask - 1);
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize & 3;
            if (t[lane], ids[lane]) < (t[best], ids[best]) {
                best = lane;
            }
            rest &= rest - 1;
        }
        best
    }
}

/// The ray splatted for [`TriangleQuad`] tests: the [`ShearedRay`] in four lanes.
pub(super) struct QuadRay {
    pub(super) k: [usize; 3],
    pub(super) origin: [Vec4; 3],
    pub(super) shear: [Vec4; 3],
}

impl QuadRay {
    pub(super) fn new(r: &ShearedRay) -> Self {
        Self {
            k: r.k,
            origin: r.origin.map(|o| Vec4::splat(o.x)),
            shear: r.shear.map(|s| Vec4::splat(s.x)),
        }
    }

    /// [`ShearedRay::intersect`] on the enabled lanes (bits of `lanes`) of a quad: every lane
    /// goes through exactly the scalar test's operations in the same order (no fused
    /// multiply-add), so results agree bit for bit with it, watertightness included.
    #[inline(always)]
    pub(super) fn intersect(&self, quad: &TriangleQuad, lanes: u32, t_max: f32) -> QuadHits {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let [ox, oy, oz] = self.origin;
        let (vx, vy, vz) = (&quad.v[kx], &quad.v[ky], &quad.v[kz]);
        let pz = [vz[0] - oz, vz[1] - oz, vz[2] - oz];
        let px = [0, 1, 2].map(|i| (vx[i] - ox) + sx * pz[i]);
        let py = [0, 1, 2].map(|i| (vy[i] - oy) + sy * pz[i]);
        let mut hits = solve(px, py, pz, sz, Vec4::splat(t_max), lanes);
        hits.decide_near(|l| {
            let v = [vx, vy, vz].map(|a| a.map(|c| c.to_array()[l]));
            near_t([ox.x, oy.x, oz.x], [sx.x, sy.x, sz.x], v, t_max)
        });
        hits
    }
}

/// Up to eight rays for a one-triangle, eight-ray watertight test (rays in lanes): each ray's
/// [`ShearedRay`] origin and shear in its lane, for rays that share one axis permutation. A
/// leaf that more than twice as many of a packet's rays reach as it holds triangles (on a
/// large room seen by a camera, mostly the walls' few large triangles, reached by all eight)
/// is tested this way, one triangle at a time, instead of once per ray.
pub(super) struct RayLanes {
    k: [usize; 3],
    origin: [f32x8; 3],
    shear: [f32x8; 3],
}

impl RayLanes {
    /// The rays `rays` in lanes (lane `i` ray `i`), or `None` when their axis permutations
    /// differ.
    pub(super) fn new(rays: &[QuadRay; 8]) -> Option<Self> {
        let k = rays[0].k;
        if rays.iter().any(|r| r.k != k) {
            return None;
        }
        let lanes = |f: &dyn Fn(&QuadRay) -> f32| f32x8::new(std::array::from_fn(|i| f(&rays[i])));
        Some(Self {
            k,
            origin: [0, 1, 2].map(|a| lanes(&|r| r.origin[a].x)),
            shear: [0, 1, 2].map(|a| lanes(&|r| r.shear[a].x)),
        })
    }

    /// [`QuadRay::intersect`] of triangle `tri` of `quad` against the rays in `lanes`
    /// (bits), each against its own bound (`bound`, lane by lane): every lane goes through
    /// exactly the operations that test applies to that ray and triangle, in the same order,
    /// so each answer agrees with it bit for bit.
    #[inline(always)]
    pub(super) fn intersect(
        &self,
        quad: &TriangleQuad,
        tri: usize,
        lanes: u32,
        bound: f32x8,
    ) -> LaneHits {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let [ox, oy, oz] = self.origin;
        let v = |axis: usize, vertex: usize| f32x8::splat(quad.v[axis][vertex][tri]);
        let pz = [0, 1, 2].map(|i| v(kz, i) - oz);
        let px = [0, 1, 2].map(|i| (v(kx, i) - ox) + sx * pz[i]);
        let py = [0, 1, 2].map(|i| (v(ky, i) - oy) + sy * pz[i]);
        let mut hits = solve(px, py, pz, sz, bound, lanes);
        hits.decide_near(|l| {
            let v = [kx, ky, kz].map(|a| quad.v[a].map(|c| c.to_array()[tri]));
            let lane = |x: [f32x8; 3]| x.map(|x| x.lane(l));
            near_t(lane(self.origin), lane(self.shear), v, bound.lane(l))
        });
        hits
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec3A};
    use wide::f32x8;

    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    use super::{QuadRay, RayLanes, TriangleQuad};
    use crate::accel::triangle::ShearedRay;

    /// Each triangle of a quad against eight rays in lanes gives, ray by ray, the very bits
    /// of the four-triangle test for that ray (hit or miss, `t`, barycentrics): on a grid of
    /// triangles sharing edges and vertices, with rays aimed at its vertices and edge
    /// midpoints (decided in f64 on the edge) and at random points, from one eye and from
    /// scattered origins, with no bound, a bound at the hit's own distance and a few ulps
    /// around it, at 1e-4, 1 and 1e5 units.
    #[test]
    fn rays_in_lanes_agree_with_the_four_triangle_test() {
        let mut r = Pcg64Mcg::seed_from_u64(91);
        let mut on_edge = 0;
        let mut hits = 0;
        for scale in [1e-4f32, 1.0, 1e5] {
            // A 4 x 4 grid of squares in the plane z = 0.3 (two triangles each), slightly
            // tilted so that no coordinate is special.
            let corner = |x: f32, y: f32| Vec3A::new(x, y, 0.3 + 0.01 * x - 0.02 * y) * scale;
            let mut tris = Vec::new();
            for y in 0..4 {
                for x in 0..4 {
                    let (x, y) = (x as f32 * 0.25, y as f32 * 0.25);
                    let [a, b, c, d] = [
                        corner(x, y),
                        corner(x + 0.25, y),
                        corner(x + 0.25, y + 0.25),
                        corner(x, y + 0.25),
                    ];
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                }
            }
            let quads: Vec<TriangleQuad> = tris
                .chunks(4)
                .enumerate()
                .map(|(i, t)| {
                    TriangleQuad::new(t, &[0, 1, 2, 3].map(|l| (4 * i + l) as u32)[..t.len()])
                })
                .collect();
            let vertices: Vec<Vec3A> = tris.iter().flatten().copied().collect();
            for round in 0..200 {
                let eye = Vec3::new(0.5, 0.5, 2.0) * scale;
                let rays: [(Vec3, Vec3); 8] = std::array::from_fn(|i| {
                    let origin = if round % 2 == 0 {
                        eye
                    } else {
                        eye + Vec3::new(
                            r.random::<f32>() - 0.5,
                            r.random::<f32>() - 0.5,
                            r.random::<f32>(),
                        ) * 0.2
                            * scale
                    };
                    let target: Vec3 = match (i + round) % 3 {
                        // A vertex, the midpoint of an edge, a random point.
                        0 => vertices[(r.random::<u64>() % vertices.len() as u64) as usize].into(),
                        1 => {
                            let t = &tris[(r.random::<u64>() % tris.len() as u64) as usize];
                            ((t[0] + t[1]) * 0.5).into()
                        }
                        _ => (corner(r.random::<f32>(), r.random::<f32>())).into(),
                    };
                    (origin, target - origin)
                });
                let one: [QuadRay; 8] = rays.map(|(o, d)| QuadRay::new(&ShearedRay::new(o, d)));
                let Some(in_lanes) = RayLanes::new(&one) else {
                    continue;
                };
                for quad in &quads {
                    for tri in 0..4 {
                        let first = one
                            .each_ref()
                            .map(|ray| ray.intersect(quad, 1 << tri, f32::INFINITY));
                        let t_hit = first
                            .each_ref()
                            .map(|h| if h.mask != 0 { h.t_of(tri) } else { 1.0 });
                        for bound in [
                            t_hit.map(|_| f32::INFINITY),
                            t_hit,
                            t_hit.map(f32::next_up),
                            t_hit.map(f32::next_down),
                            t_hit.map(|t| t.next_up().next_up().next_up().next_up()),
                        ] {
                            let lanes = in_lanes.intersect(quad, tri, 0xff, f32x8::new(bound));
                            for (i, ray) in one.iter().enumerate() {
                                let h = ray.intersect(quad, 1 << tri, bound[i]);
                                let hit = h.mask != 0;
                                assert_eq!(hit, lanes.mask & (1 << i) != 0, "ray {i} tri {tri}");
                                if hit {
                                    hits += 1;
                                    assert_eq!(h.t_of(tri).to_bits(), lanes.t_of(i).to_bits());
                                    let b = h.barycentric(tri).map(f32::to_bits);
                                    assert_eq!(b, lanes.barycentric(i).map(f32::to_bits));
                                    if lanes.e.iter().any(|e| e.as_array()[i] == 0.0) {
                                        on_edge += 1;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        // The edge cases were met: hits through a shared edge or vertex (an edge function
        // exactly zero), and many hits in all.
        assert!(on_edge > 1000, "{on_edge} hits on an edge");
        assert!(hits > 10_000, "{hits} hits");
    }

    /// Hits a millionth of a wall's size from the ray's origin, which the f32 bound cannot
    /// tell from it and f64 decides (`near_t`), are the same bits in the one-triangle, the
    /// four-triangle and the eight-ray tests: eight oblique rays from 1e-6 of a unit square's
    /// size above it, every one a hit, at 1e-4, 1 and 1e5 units.
    #[test]
    fn hits_decided_in_f64_agree_in_every_test() {
        use crate::accel::triangle::AxisTriangle;
        let mut r = Pcg64Mcg::seed_from_u64(7);
        for scale in [1e-4f32, 1.0, 1e5] {
            let c = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
                .map(|[x, y]| Vec3A::new(x, y, 0.0) * scale);
            let tris = [[c[0], c[1], c[2]], [c[0], c[2], c[3]]];
            let quad = TriangleQuad::new(&tris, &[0, 1]);
            for _ in 0..100 {
                let rays: [(Vec3, Vec3); 8] = std::array::from_fn(|_| {
                    let o = Vec3::new(
                        0.1 + 0.8 * r.random::<f32>(),
                        0.1 + 0.8 * r.random::<f32>(),
                        1e-6,
                    ) * scale;
                    // Oblique, x the dominant axis: the shear then carries the square's
                    // whole size into the f32 bound.
                    let d = Vec3::new(
                        0.6 + 0.3 * r.random::<f32>(),
                        0.4 * (r.random::<f32>() - 0.5),
                        -0.5,
                    );
                    (o, d)
                });
                let sheared = rays.map(|(o, d)| ShearedRay::new(o, d));
                let one: [QuadRay; 8] = sheared.map(|s| QuadRay::new(&s));
                let in_lanes = RayLanes::new(&one).expect("one axis permutation");
                for (tri, corners) in tris.iter().enumerate() {
                    let lanes = in_lanes.intersect(&quad, tri, 0xff, f32x8::splat(f32::INFINITY));
                    for (i, ray) in one.iter().enumerate() {
                        let h = ray.intersect(&quad, 1 << tri, f32::INFINITY);
                        let scalar =
                            sheared[i].intersect(&AxisTriangle::new(*corners), f32::INFINITY);
                        assert_eq!(h.mask != 0, lanes.mask & (1 << i) != 0);
                        assert_eq!(h.mask != 0, scalar.is_some());
                        if let Some((t, b)) = scalar {
                            assert_eq!(t.to_bits(), h.t_of(tri).to_bits());
                            assert_eq!(t.to_bits(), lanes.t_of(i).to_bits());
                            assert_eq!(b.map(f32::to_bits), lanes.barycentric(i).map(f32::to_bits));
                        }
                    }
                }
                // Each ray hits one of the two triangles (or both, on their shared edge).
                for (i, ray) in one.iter().enumerate() {
                    let h = ray.intersect(&quad, 0b11, f32::INFINITY);
                    assert!(h.mask != 0, "ray {i}: {:?} missed at {scale}", rays[i]);
                    let expected = 1e-6 * scale / 0.5;
                    let t = h.t_of(h.nearest(&quad.ids));
                    assert!(
                        (t - expected).abs() < 0.05 * expected,
                        "{t} against {expected}"
                    );
                }
            }
        }
    }
}
