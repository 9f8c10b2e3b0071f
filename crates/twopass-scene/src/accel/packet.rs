//! The watertight test on four triangles at once (one ray, four lanes), bit for bit the
//! operations of the scalar test in [`super::triangle`].

use glam::{Vec3A, Vec4};

use super::ray::gamma;
use super::table::prefetch;
use super::triangle::ShearedRay;

/// Up to four triangles (one BVH leaf) stored for a one-ray, four-triangle watertight
/// test: `v[axis][vertex]` holds that coordinate of that vertex for the four triangles (lanes),
/// `ids[lane]` the scene index of the triangle. Lanes past the leaf's triangles are zero, name
/// no triangle (`u32::MAX`) and are never enabled.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct TriPacket {
    pub(super) v: [[Vec4; 3]; 3],
    /// Scene triangle indices, beside the vertices: a hit's index is read from (or next to)
    /// the cache lines its test just loaded, not from a table of its own.
    pub(super) ids: [u32; 4],
}

impl TriPacket {
    /// The packet of triangles `ids` with corners `tris` (at most four).
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

    /// Starts loading the packet's three cache lines (160 bytes from a 32-byte boundary).
    #[inline(always)]
    pub(super) fn prefetch(&self) {
        prefetch(&self.v[0][0]);
        prefetch(&self.v[1][1]);
        prefetch(&self.v[2][2]);
    }
}

/// The hits of one [`TriPacket`] test: per lane, `t` and the three edge functions and
/// `1 / det` to form barycentrics from, and the lanes that hit.
pub(super) struct PacketHits {
    pub(super) t: Vec4,
    pub(super) e: [Vec4; 3],
    pub(super) inv_det: Vec4,
    pub(super) mask: u32,
}

impl PacketHits {
    /// The lane with the smallest `t` among the hits (there must be one), and of lanes at
    /// equal `t` the one with the smallest triangle index (`ids`, the packet's), so that the
    /// answer does not depend on the order a walk meets triangles in.
    pub(super) fn nearest(&self, ids: &[u32; 4]) -> usize {
        let mut best = self.mask.trailing_zeros() as usize;
        let mut rest = self.mask & (self.mask - 1);
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            if (self.t[lane], ids[lane]) < (self.t[best], ids[best]) {
                best = lane;
            }
            rest &= rest - 1;
        }
        best
    }

    /// Barycentrics of lane `lane`.
    pub(super) fn barycentric(&self, lane: usize) -> [f32; 3] {
        self.e.map(|e| e[lane] * self.inv_det[lane])
    }
}

/// The ray splatted for [`TriPacket`] tests: the [`ShearedRay`] in four lanes.
pub(super) struct PacketRay {
    pub(super) k: [usize; 3],
    pub(super) origin: [Vec4; 3],
    pub(super) shear: [Vec4; 3],
}

impl PacketRay {
    pub(super) fn new(r: &ShearedRay) -> Self {
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
    pub(super) fn intersect(&self, packet: &TriPacket, lanes: u32, t_max: f32) -> PacketHits {
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
        if lanes & !(neg & pos).bitmask() == 0 {
            // Every enabled lane is missed on the edge functions alone (most leaf tests): no
            // division, no distance.
            return PacketHits {
                t: zero,
                e,
                inv_det: zero,
                mask: 0,
            };
        }
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
