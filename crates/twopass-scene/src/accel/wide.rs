//! obvhs's compressed 8-wide CWBVH nodes, decoded to f32 boxes once at build time, the
//! eight-box slab test that produces obvhs's node hit mask, and the ray as that test sees it.

use glam::{UVec2, Vec3, Vec3A, Vec4};
use obvhs::cwbvh::{Traversal, node::CwBvhNode};

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
pub(super) const MAX_INVERSE: f32 = 1e20;

/// One obvhs CWBVH node with its eight children's boxes decoded from the 8-bit quantized
/// planes to f32 once at build time (rounded outward, so every decoded box contains the
/// quantized one), so the traversal does not convert bytes to floats at every visit. The
/// field names `child_base_idx`, `primitive_base_idx` and `imask` are the ones obvhs's
/// `traverse!` macro reads; they are copied from the obvhs node unchanged.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    /// `bounds[4 * axis + 2 * side + half]`: lane `j` is child `4 * half + j`; side 0 is the
    /// box minimum, 1 the maximum. Empty children are empty boxes (min +inf, max -inf).
    pub(super) bounds: [Vec4; 12],
    /// What each child adds to obvhs's node hit mask when hit, if it is a leaf (zero for
    /// internal and empty children): its primitive count in unary, shifted to its first slot.
    /// Always below 2^24, so exact in f32, and the leaves' bits are disjoint: summing the hit
    /// lanes ORs them.
    pub(super) leaf_bits: [Vec4; 2],
    /// Index of the first child node.
    pub(super) child_base_idx: u32,
    /// Index of the first primitive slot.
    pub(super) primitive_base_idx: u32,
    /// Bit `i` set when child `i` is an internal node.
    pub(super) imask: u8,
}

/// `XOR_PERMUTE[o][m]` moves bit `c` of `m` to bit `c ^ o`: obvhs orders the internal children
/// of a node by slot XOR the ray's octant.
pub(super) const XOR_PERMUTE: [[u8; 256]; 8] = {
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
    pub(super) fn decode(n: &CwBvhNode) -> Self {
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
    pub(super) fn intersect(&self, ray: &NodeRay, t_max: f32, oct_inv4: u32) -> u32 {
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
pub(super) struct WideBvh {
    pub(super) nodes: Vec<WideNode>,
}

/// The ray as the node test sees it: origin and inverse direction splatted per axis, and for
/// each axis which side of a box the ray enters first. Negative zeros in the direction become
/// positive and inverses are clamped to [`MAX_INVERSE`], so no slab ever forms 0 * inf; the
/// entry side is chosen from the sign of the inverse itself, so near and far always agree
/// with it (a mismatch would cull every box).
pub(super) struct NodeRay {
    pub(super) origin: [Vec4; 3],
    pub(super) inv: [Vec4; 3],
    /// 0 when the ray enters through the box minimum on this axis, 2 through the maximum.
    pub(super) near: [usize; 3],
    /// The direction as obvhs orders children by (its octant only).
    pub(super) direction: Vec3A,
}

impl NodeRay {
    pub(super) fn new(origin: Vec3, direction: Vec3) -> Self {
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
    pub(super) fn traversal(&self) -> Traversal {
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

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use glam::{Vec3, Vec3A};
    use obvhs::{BvhBuildParams, aabb::Aabb, cwbvh::builder::build_cwbvh};

    use super::WideNode;
    use crate::accel::Padded;

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
