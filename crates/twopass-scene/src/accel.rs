//! Ray queries over an obvhs CWBVH: closest hit and any hit (occlusion), with a watertight
//! ray-triangle test (Woop, Benthin & Wald 2013, as in pbrt-v4) and conservative error bounds,
//! so rays through shared edges and vertices never slip between triangles and spawned rays can
//! be offset safely (see [`SurfacePoint::spawn_origin`]).

use std::time::{Duration, Instant};

use glam::{DVec3, UVec2, Vec3, Vec3A, Vec3Swizzles, Vec4};
use obvhs::{
    Boundable, BvhBuildParams,
    aabb::Aabb,
    cwbvh::{Traversal, builder::build_cwbvh, node::CwBvhNode},
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

/// A triangle stored by axis for the watertight test: `axes[a]` holds coordinate `a` of
/// vertices 0, 1 and 2 (lanes x, y, z). The test then permutes the axes of all three vertices
/// at once by picking rows, instead of indexing every vertex with the ray's permutation.
#[derive(Clone, Copy, Debug, PartialEq)]
struct AxisTriangle {
    axes: [Vec3A; 3],
}

impl AxisTriangle {
    fn new(v: [Vec3A; 3]) -> Self {
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
struct ShearedRay {
    /// Axis permutation: `k[2]` is the dominant direction axis.
    k: [usize; 3],
    /// Origin coordinates in permuted order, each splatted over the three vertex lanes.
    origin: [Vec3A; 3],
    /// Shear of x and y by z, and the scale of z, splatted.
    shear: [Vec3A; 3],
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
    fn intersect(&self, tri: &AxisTriangle, t_max: f32) -> Option<(f32, [f32; 3])> {
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

/// Four triangles (four consecutive BVH slots) stored for a one-ray, four-triangle watertight
/// test: `v[axis][vertex]` holds that coordinate of that vertex for the four triangles (lanes).
/// Lanes past the last slot are zero and never enabled.
#[derive(Clone, Copy, Debug)]
struct TriPacket {
    v: [[Vec4; 3]; 3],
}

impl TriPacket {
    fn new(tris: &[[Vec3A; 3]]) -> Self {
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
        }
    }
}

/// The hits of one [`TriPacket`] test: per lane, `t` and the three edge functions and
/// `1 / det` to form barycentrics from, and the lanes that hit.
struct PacketHits {
    t: Vec4,
    e: [Vec4; 3],
    inv_det: Vec4,
    mask: u32,
}

impl PacketHits {
    /// The lane with the smallest `t` among the hits (there must be one).
    fn nearest(&self) -> usize {
        let mut best = self.mask.trailing_zeros() as usize;
        let mut rest = self.mask & (self.mask - 1);
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            if self.t[lane] < self.t[best] {
                best = lane;
            }
            rest &= rest - 1;
        }
        best
    }

    /// Barycentrics of lane `lane`.
    fn barycentric(&self, lane: usize) -> [f32; 3] {
        self.e.map(|e| e[lane] * self.inv_det[lane])
    }
}

/// The ray splatted for [`TriPacket`] tests: the [`ShearedRay`] in four lanes.
struct PacketRay {
    k: [usize; 3],
    origin: [Vec4; 3],
    shear: [Vec4; 3],
}

impl PacketRay {
    fn new(r: &ShearedRay) -> Self {
        Self {
            k: r.k,
            origin: r.origin.map(|o| Vec4::splat(o.x)),
            shear: r.shear.map(|s| Vec4::splat(s.x)),
        }
    }

    /// [`ShearedRay::intersect`] on the enabled lanes (bits of `lanes`) of a packet: every lane
    /// goes through exactly the scalar test's operations in the same order (no fused
    /// multiply-add), so results agree bit for bit with it, watertightness included.
    #[inline(always)]
    fn intersect(&self, packet: &TriPacket, lanes: u32, t_max: f32) -> PacketHits {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let [ox, oy, oz] = self.origin;
        let (vx, vy, vz) = (&packet.v[kx], &packet.v[ky], &packet.v[kz]);
        let pz = [vz[0] - oz, vz[1] - oz, vz[2] - oz];
        let px = [0, 1, 2].map(|i| (vx[i] - ox) + sx * pz[i]);
        let py = [0, 1, 2].map(|i| (vy[i] - oy) + sy * pz[i]);
        let mut e = [
            px[1] * py[2] - py[1] * px[2],
            px[2] * py[0] - py[2] * px[0],
            px[0] * py[1] - py[0] * px[1],
        ];
        let zero = Vec4::ZERO;
        let on_edge = (e[0].cmpeq(zero) | e[1].cmpeq(zero) | e[2].cmpeq(zero)).bitmask() & lanes;
        if on_edge != 0 {
            // On an edge in f32: decide in f64 so neighbours agree (as the scalar test).
            let f = |a: f32, b: f32, c: f32, d: f32| {
                (f64::from(a) * f64::from(b) - f64::from(c) * f64::from(d)) as f32
            };
            let mut bits = on_edge;
            while bits != 0 {
                let l = bits.trailing_zeros() as usize;
                e[0][l] = f(px[1][l], py[2][l], py[1][l], px[2][l]);
                e[1][l] = f(px[2][l], py[0][l], py[2][l], px[0][l]);
                e[2][l] = f(px[0][l], py[1][l], py[0][l], px[1][l]);
                bits &= bits - 1;
            }
        }
        let neg = e[0].cmplt(zero) | e[1].cmplt(zero) | e[2].cmplt(zero);
        let pos = e[0].cmpgt(zero) | e[1].cmpgt(zero) | e[2].cmpgt(zero);
        let det = e[0] + e[1] + e[2];
        let pz = pz.map(|z| z * sz);
        let t_scaled = e[0] * pz[0] + e[1] * pz[1] + e[2] * pz[2];
        let t_max4 = Vec4::splat(t_max);
        let limit = t_max4 * det;
        let behind_neg = det.cmplt(zero) & (t_scaled.cmpge(zero) | t_scaled.cmplt(limit));
        let behind_pos = det.cmpgt(zero) & (t_scaled.cmple(zero) | t_scaled.cmpgt(limit));
        let miss = (neg & pos) | det.cmpeq(zero) | behind_neg | behind_pos;
        let mut mask = lanes & !miss.bitmask();
        let inv_det = Vec4::ONE / det;
        let t = t_scaled * inv_det;
        if mask != 0 {
            // Conservative bound: reject hits whose t cannot be told from 0.
            let max3 = |a: [Vec4; 3]| a[0].abs().max(a[1].abs()).max(a[2].abs());
            let max_z = max3(pz);
            let max_x = max3(px);
            let max_y = max3(py);
            let max_e = max3(e);
            let delta_z = Vec4::splat(gamma(3)) * max_z;
            let delta_x = Vec4::splat(gamma(5)) * (max_x + max_z);
            let delta_y = Vec4::splat(gamma(5)) * (max_y + max_z);
            let delta_e = Vec4::splat(2.0)
                * (Vec4::splat(gamma(2)) * max_x * max_y + delta_y * max_x + delta_x * max_y);
            let delta_t = Vec4::splat(3.0)
                * (Vec4::splat(gamma(3)) * max_e * max_z + delta_e * max_z + delta_z * max_e)
                * inv_det.abs();
            // t > delta_t and t < t_max, both false for NaN.
            mask &= (t.cmpgt(delta_t) & t.cmplt(t_max4)).bitmask();
        }
        PacketHits {
            t,
            e,
            inv_det,
            mask,
        }
    }
}

/// Takes the leaf's whole primitive group from the traversal (so it is tested at once, four
/// triangles at a time) and calls `f(packet, lanes)` for every packet holding one of its
/// slots, until `f` returns `true`.
#[inline(always)]
fn for_each_leaf_packet(state: &mut Traversal, f: impl FnMut(usize, u32) -> bool) {
    let group = state.primitive_group;
    let bits = group.y | (1 << (state.primitive_id - group.x));
    state.primitive_group.y = 0;
    for_each_packet(group.x, bits, f);
}

/// Calls `f(packet, lanes)` for every packet holding a slot of the primitive group
/// (`base`, `bits`): bit `i` of `bits` is slot `base + i`.
#[inline(always)]
fn for_each_packet(base: u32, bits: u32, mut f: impl FnMut(usize, u32) -> bool) {
    let mut rest = u64::from(bits) << (base % 4);
    let mut packet = (base / 4) as usize;
    while rest != 0 {
        let lanes = (rest & 0xf) as u32;
        if lanes != 0 && f(packet, lanes) {
            return;
        }
        rest >>= 4;
        packet += 1;
    }
}

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
const MAX_INVERSE: f32 = 1e20;

/// Relative padding of primitive bounds: a slab test can round a ray that passes exactly
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

/// One obvhs CWBVH node with its eight children's boxes decoded from the 8-bit quantized
/// planes to f32 once at build time (rounded outward, so every decoded box contains the
/// quantized one), so the traversal does not convert bytes to floats at every visit. The
/// field names `child_base_idx`, `primitive_base_idx` and `imask` are the ones obvhs's
/// `traverse!` macro reads; they are copied from the obvhs node unchanged.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct WideNode {
    /// `bounds[4 * axis + 2 * side + half]`: lane `j` is child `4 * half + j`; side 0 is the
    /// box minimum, 1 the maximum. Empty children are empty boxes (min +inf, max -inf).
    bounds: [Vec4; 12],
    /// What each child adds to obvhs's node hit mask when hit, if it is a leaf (zero for
    /// internal and empty children): its primitive count in unary, shifted to its first slot.
    /// Always below 2^24, so exact in f32, and the leaves' bits are disjoint: summing the hit
    /// lanes ORs them.
    leaf_bits: [Vec4; 2],
    /// Index of the first child node.
    child_base_idx: u32,
    /// Index of the first primitive slot.
    primitive_base_idx: u32,
    /// Bit `i` set when child `i` is an internal node.
    imask: u8,
}

/// `XOR_PERMUTE[o][m]` moves bit `c` of `m` to bit `c ^ o`: obvhs orders the internal children
/// of a node by slot XOR the ray's octant.
const XOR_PERMUTE: [[u8; 256]; 8] = {
    let mut table = [[0u8; 256]; 8];
    let mut o = 0;
    while o < 8 {
        let mut m = 0;
        while m < 256 {
            let mut out = 0u8;
            let mut c = 0;
            while c < 8 {
                if m & (1 << c) != 0 {
                    out |= 1 << (c ^ o);
                }
                c += 1;
            }
            table[o][m] = out;
            m += 1;
        }
        o += 1;
    }
    table
};

impl WideNode {
    fn decode(n: &CwBvhNode) -> Self {
        let ext = n.compute_extent();
        let mut bounds = [Vec4::ZERO; 12];
        let planes = [
            (&n.child_min_x, &n.child_max_x),
            (&n.child_min_y, &n.child_max_y),
            (&n.child_min_z, &n.child_max_z),
        ];
        for (axis, (lo, hi)) in planes.into_iter().enumerate() {
            let mut min = [f32::INFINITY; 8];
            let mut max = [f32::NEG_INFINITY; 8];
            for c in 0..8 {
                if n.child_meta[c] != 0 {
                    // q * 2^e is exact; the sum rounds once, then one more ulp outward.
                    min[c] = (n.p[axis] + f32::from(lo[c]) * ext[axis]).next_down();
                    max[c] = (n.p[axis] + f32::from(hi[c]) * ext[axis]).next_up();
                }
            }
            for half in 0..2 {
                let r = 4 * half..4 * half + 4;
                bounds[4 * axis + half] = Vec4::from_slice(&min[r.clone()]);
                bounds[4 * axis + 2 + half] = Vec4::from_slice(&max[r]);
            }
        }
        let mut leaf_bits = [0.0f32; 8];
        for (c, &meta) in n.child_meta.iter().enumerate() {
            let offset = u32::from(meta & 0x1f);
            if n.imask & (1 << c) != 0 {
                // obvhs numbers internal children by slot: 24 + slot.
                assert_eq!(offset, 24 + c as u32, "unexpected CWBVH child numbering");
            } else {
                let bits = u32::from(meta >> 5) << offset;
                assert!(bits < 1 << 24, "leaf primitive slots beyond 24");
                leaf_bits[c] = bits as f32;
            }
        }
        Self {
            bounds,
            leaf_bits: [
                Vec4::from_slice(&leaf_bits[..4]),
                Vec4::from_slice(&leaf_bits[4..]),
            ],
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            imask: n.imask,
        }
    }

    /// The children hit by `ray` within `[0, t_max]`, encoded as obvhs's node hit mask: the
    /// high byte holds internal children by traversal priority, the low 24 bits the primitive
    /// slots (relative to `primitive_base_idx`) of the hit leaves.
    #[inline(always)]
    fn intersect(&self, ray: &NodeRay, t_max: f32, oct_inv4: u32) -> u32 {
        let b = &self.bounds;
        let t_max = Vec4::splat(t_max);
        let mut mask = 0u32;
        let mut leaves = Vec4::ZERO;
        for half in 0..2 {
            let slab = |axis: usize| {
                let near = b[4 * axis + ray.near[axis] + half];
                let far = b[4 * axis + (2 - ray.near[axis]) + half];
                (
                    (near - ray.origin[axis]) * ray.inv[axis],
                    (far - ray.origin[axis]) * ray.inv[axis],
                )
            };
            let (nx, fx) = slab(0);
            let (ny, fy) = slab(1);
            let (nz, fz) = slab(2);
            let t_near = nx.max(ny).max(nz.max(Vec4::ZERO));
            let t_far = fx.min(fy).min(fz.min(t_max));
            let hit = t_near.cmple(t_far);
            mask |= hit.bitmask() << (4 * half);
            leaves += Vec4::select(hit, self.leaf_bits[half], Vec4::ZERO);
        }
        // obvhs's hit mask: hit internal children in the high byte, at bit 24 + (slot XOR
        // octant); hit leaves' primitive slots in the low 24 bits.
        let inner = XOR_PERMUTE[(oct_inv4 & 7) as usize][(mask & u32::from(self.imask)) as usize];
        (u32::from(inner) << 24) | leaves.element_sum() as u32
    }
}

/// The decoded nodes, named as obvhs's `traverse!` macro expects (`.nodes[i]`).
struct WideBvh {
    nodes: Vec<WideNode>,
}

/// The ray as the node test sees it: origin and inverse direction splatted per axis, and for
/// each axis which side of a box the ray enters first. Negative zeros in the direction become
/// positive and inverses are clamped to [`MAX_INVERSE`], so no slab ever forms 0 * inf; the
/// entry side is chosen from the sign of the inverse itself, so near and far always agree
/// with it (a mismatch would cull every box).
struct NodeRay {
    origin: [Vec4; 3],
    inv: [Vec4; 3],
    /// 0 when the ray enters through the box minimum on this axis, 2 through the maximum.
    near: [usize; 3],
    /// The direction as obvhs orders children by (its octant only).
    direction: Vec3A,
}

impl NodeRay {
    fn new(origin: Vec3, direction: Vec3) -> Self {
        let d = direction + Vec3::ZERO;
        let inv = |x: f32| {
            let i = 1.0 / x;
            if i.abs() > MAX_INVERSE {
                MAX_INVERSE.copysign(x)
            } else {
                i
            }
        };
        let inv = [inv(d.x), inv(d.y), inv(d.z)];
        Self {
            origin: [
                Vec4::splat(origin.x),
                Vec4::splat(origin.y),
                Vec4::splat(origin.z),
            ],
            inv: inv.map(Vec4::splat),
            near: inv.map(|i| if i < 0.0 { 2 } else { 0 }),
            direction: Vec3A::new(inv[0], inv[1], inv[2]),
        }
    }

    /// A fresh obvhs traversal state for this ray, starting at the root.
    fn traversal(&self) -> Traversal {
        // obvhs's ray_get_octant_inv4: one bit per axis with a non-negative direction.
        let d = self.direction;
        let oct_inv4 = (if d.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if d.z < 0.0 { 0 } else { 0x0101_0101 });
        Traversal {
            stack: Default::default(),
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4,
            traversal_direction: d,
            primitive_id: 0,
            hitmask: 0,
        }
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
    /// Positions of the triangle's vertices 0, 1, 2 (the mesh's, bit for bit), from the
    /// accelerator's copy that the test just read, so the caller need not fetch them again.
    pub corners: [Vec3; 3],
}

/// A CWBVH over the scene's triangles with the queries every pass uses.
pub struct Accel {
    /// The obvhs CWBVH's nodes, decoded for the node test.
    bvh: WideBvh,
    /// Triangles in BVH slot order, four to a packet (slot `s` is lane `s % 4` of packet
    /// `s / 4`).
    packets: Vec<TriPacket>,
    /// BVH slot -> scene triangle index.
    ids: Vec<u32>,
    build_time: Duration,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.ids.len())
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
        let cwbvh = build_cwbvh(&boxes, params, &mut Duration::default());
        let bvh = WideBvh {
            nodes: cwbvh.nodes.iter().map(WideNode::decode).collect(),
        };
        let ids = cwbvh.primitive_indices;
        let slots: Vec<[Vec3A; 3]> = ids.iter().map(|&i| corners[i as usize]).collect();
        let packets = slots.chunks(4).map(TriPacket::new).collect();
        Self {
            bvh,
            packets,
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
        if self.ids.is_empty() {
            return None;
        }
        let sheared = PacketRay::new(&ShearedRay::new(origin, direction));
        let ray = NodeRay::new(origin, direction);
        // Packet, lane, barycentrics of the nearest hit so far; its t is `t_max`.
        let mut best: Option<(usize, usize, [f32; 3])> = None;
        let mut t_max = t_max;
        let mut state = ray.traversal();
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node.intersect(&ray, t_max, state.oct_inv4),
            {
                for_each_leaf_packet(&mut state, |p, lanes| {
                    let hits = sheared.intersect(&self.packets[p], lanes, t_max);
                    if hits.mask != 0 {
                        let lane = hits.nearest();
                        t_max = hits.t[lane];
                        best = Some((p, lane, hits.barycentric(lane)));
                    }
                    false
                });
            }
        );
        let (p, lane, barycentric) = best?;
        let v = &self.packets[p].v;
        Some(TriangleHit {
            triangle: self.ids[4 * p + lane],
            t: t_max,
            barycentric,
            corners: [0, 1, 2].map(|i| Vec3::new(v[0][i][lane], v[1][i][lane], v[2][i][lane])),
        })
    }

    /// Whether anything is hit with `0 < t < t_max`; stops at the first hit found.
    pub fn any_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        if self.ids.is_empty() {
            return false;
        }
        let sheared = PacketRay::new(&ShearedRay::new(origin, direction));
        let ray = NodeRay::new(origin, direction);
        let mut state = ray.traversal();
        let mut node;
        let mut hit = false;
        'search: {
            obvhs::traverse!(
                self.bvh,
                node,
                state,
                node.intersect(&ray, t_max, state.oct_inv4),
                {
                    for_each_leaf_packet(&mut state, |p, lanes| {
                        hit = sheared.intersect(&self.packets[p], lanes, t_max).mask != 0;
                        hit
                    });
                    if hit {
                        break 'search;
                    }
                }
            );
        }
        hit
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
            let corners = t.map(|k| positions[k as usize]);
            let v = AxisTriangle::new(corners.map(Vec3A::from));
            let limit = best.map_or(t_max, |b| b.t);
            if let Some((t, barycentric)) = sheared.intersect(&v, limit) {
                best = Some(TriangleHit {
                    triangle: i as u32,
                    t,
                    barycentric,
                    corners,
                });
            }
        }
        best
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles forming the unit square in the plane z = 0.
    fn square() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn hits_very_close_to_the_origin_with_long_directions() {
        let (p, t) = square();
        let accel = Accel::build(&p, &t);
        // 1e-3 units away along a direction of length 1000: t = 1e-6.
        let origin = Vec3::new(0.3, 0.6, 1e-3);
        let dir = Vec3::new(0.0, 0.0, -1000.0);
        let hit = accel.closest(origin, dir, f32::INFINITY).expect("hit");
        assert_eq!(hit.triangle, 1);
        assert!((hit.t - 1e-6).abs() < 1e-9);
        assert!(accel.any_hit(origin, dir, 1.0));
        assert!(!accel.any_hit(origin, dir, 0.5e-6));
    }

    #[test]
    fn axis_aligned_rays_with_negative_zeros_hit() {
        let (p, t) = square();
        let accel = Accel::build(&p, &t);
        for (o, d) in [
            (Vec3::new(0.25, 0.5, 2.0), -Vec3::Z),
            (Vec3::new(0.25, 0.5, -2.0), Vec3::new(-0.0, -0.0, 1.0)),
            // Exactly through the shared diagonal.
            (Vec3::new(0.5, 0.5, 2.0), -Vec3::Z),
        ] {
            let hit = accel.closest(o, d, f32::INFINITY).expect("hit");
            assert!((hit.t - 2.0).abs() < 1e-6);
            assert!(accel.any_hit(o, d, f32::INFINITY));
            let b = hit.barycentric;
            assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn decoded_boxes_contain_the_quantized_ones() {
        let positions: Vec<Vec3> = (0..300)
            .map(|i| {
                let f = i as f32;
                Vec3::new((f * 0.37).sin() * 10.0, (f * 0.11).cos() * 7.0, f * 0.05)
            })
            .collect();
        let tris: Vec<[u32; 3]> = (0..298).map(|i| [i, i + 1, i + 2]).collect();
        let corners: Vec<Padded> = tris
            .iter()
            .map(|t| {
                let v = t.map(|i| Vec3A::from(positions[i as usize]));
                Padded {
                    aabb: Aabb {
                        min: v[0].min(v[1]).min(v[2]),
                        max: v[0].max(v[1]).max(v[2]),
                    },
                }
            })
            .collect();
        let bvh = build_cwbvh(
            &corners,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        for n in &bvh.nodes {
            let w = WideNode::decode(n);
            for c in 0..8 {
                if n.child_meta[c] == 0 {
                    continue;
                }
                let q = n.child_aabb(c);
                let (half, lane) = (c / 4, c % 4);
                for axis in 0..3 {
                    assert!(w.bounds[4 * axis + half][lane] <= q.min[axis]);
                    assert!(w.bounds[4 * axis + 2 + half][lane] >= q.max[axis]);
                }
            }
        }
    }
}
