//! 8-wide BVH nodes decoded from obvhs's compressed CWBVH (f32 boxes once at build time), the
//! eight-box slab test, and the traversal: ordered front to back with distance culling for
//! closest hits, early exit for occlusion.

use glam::{Vec3, Vec4};
use obvhs::cwbvh::{CwBvh, node::CwBvhNode};
use obvhs::faststack::FastStack;

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
pub(super) const MAX_INVERSE: f32 = 1e20;

/// Depth of the traversal stack kept on the call stack; a tree that could need more (checked
/// at build time, [`WideBvh::stack_need`]) traverses with a heap stack of the exact size.
const INLINE_STACK: usize = 64;

/// `XOR_PERMUTE[o][m]` moves bit `c` of `m` to bit `c ^ o`. obvhs's builder places a node's
/// children in slots such that, for a ray whose octant is `o` (bit 2 set for x >= 0, bit 1
/// for y, bit 0 for z), descending `slot ^ o` is roughly front to back.
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

/// One 8-wide node: its children's boxes decoded from obvhs's 8-bit quantized planes to f32
/// once at build time (rounded outward, so every decoded box contains the quantized one), and
/// what each child is: an inner node, a leaf (one triangle packet), or empty.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    /// `bounds[4 * axis + 2 * side + half]`: lane `j` is child `4 * half + j`; side 0 is the
    /// box minimum, 1 the maximum. Empty children are empty boxes (min +inf, max -inf).
    pub(super) bounds: [Vec4; 12],
    /// Per child: its node index (inner) or its packet index (leaf); 0 when empty.
    pub(super) child: [u32; 8],
    /// Per child, four bits from bit `4 * child`: the leaf's lanes in its packet.
    pub(super) lanes: u32,
    /// Bit `c` set when child `c` is an inner node.
    pub(super) inner: u8,
    /// Bit `c` set when child `c` is a leaf.
    pub(super) leaf: u8,
}

impl WideNode {
    /// Decodes obvhs node `n`; `packet_of(slot)` is the packet that holds the leaf starting at
    /// primitive slot `slot` (every leaf has its own packet).
    fn decode(n: &CwBvhNode, packet_of: impl Fn(u32) -> u32) -> Self {
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
        let mut node = Self {
            bounds,
            child: [0; 8],
            lanes: 0,
            inner: n.imask,
            leaf: 0,
        };
        for (c, &meta) in n.child_meta.iter().enumerate() {
            if n.imask & (1 << c) != 0 {
                // Inner children are stored from `child_base_idx` in slot order.
                let before = (u32::from(n.imask) & ((1 << c) - 1)).count_ones();
                node.child[c] = n.child_base_idx + before;
            } else if meta != 0 {
                // A leaf: its primitives are slots `offset..offset + count` after the base,
                // the count in unary in the top three bits.
                let offset = u32::from(meta & 0x1f);
                let count = (meta >> 5).count_ones();
                node.child[c] = packet_of(n.primitive_base_idx + offset);
                node.lanes |= ((1 << count) - 1) << (4 * c);
                node.leaf |= 1 << c;
            }
        }
        node
    }

    /// The children hit by `ray` within `[0, t_max]` (bit `c` for child `c`) and each child's
    /// entry distance.
    #[inline(always)]
    fn intersect(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        let b = &self.bounds;
        let t_max = Vec4::splat(t_max);
        let mut mask = 0u32;
        let mut near = [Vec4::ZERO; 2];
        for (half, near) in near.iter_mut().enumerate() {
            let slab = |axis: usize| {
                let n = b[4 * axis + ray.near[axis] + half];
                let f = b[4 * axis + (2 - ray.near[axis]) + half];
                (
                    (n - ray.origin[axis]) * ray.inv[axis],
                    (f - ray.origin[axis]) * ray.inv[axis],
                )
            };
            let (nx, fx) = slab(0);
            let (ny, fy) = slab(1);
            let (nz, fz) = slab(2);
            let t_near = nx.max(ny).max(nz.max(Vec4::ZERO));
            let t_far = fx.min(fy).min(fz.min(t_max));
            mask |= t_near.cmple(t_far).bitmask() << (4 * half);
            *near = t_near;
        }
        let mut entry = [0.0; 8];
        near[0].write_to_slice(&mut entry[..4]);
        near[1].write_to_slice(&mut entry[4..]);
        (mask, entry)
    }
}

/// The decoded tree: node 0 is the root.
pub(super) struct WideBvh {
    pub(super) nodes: Vec<WideNode>,
    /// The most entries the traversal stack can hold at once: over every path from the root,
    /// the sum of the inner children pushed beside the one descended into.
    stack_need: usize,
}

impl WideBvh {
    /// Decodes obvhs's tree; `packet_of` as in [`WideNode::decode`].
    pub(super) fn new(bvh: &CwBvh, packet_of: impl Fn(u32) -> u32) -> Self {
        let nodes: Vec<WideNode> = bvh
            .nodes
            .iter()
            .map(|n| WideNode::decode(n, &packet_of))
            .collect();
        // Children come after their parents in obvhs's order, so one backward sweep sees every
        // child's need before its parent's.
        let mut need = vec![0usize; nodes.len()];
        for (i, n) in nodes.iter().enumerate().rev() {
            let inner = (0..8).filter(|c| n.inner & (1 << c) != 0);
            let deepest = inner
                .map(|c| {
                    let child = n.child[c] as usize;
                    assert!(child > i, "CWBVH child stored before its parent");
                    need[child]
                })
                .max()
                .unwrap_or(0);
            need[i] = (n.inner.count_ones() as usize).saturating_sub(1) + deepest;
        }
        Self {
            stack_need: need.first().copied().unwrap_or(0),
            nodes,
        }
    }

    /// Visits the leaves `ray` reaches within `t_max`, calling `leaf(packet, lanes, t_max)`;
    /// the call may shorten `t_max` (a closer hit), and returns `true` to stop the walk. With
    /// `ordered`, inner children are visited nearest first and a pushed child is skipped once
    /// `t_max` is below its entry distance (closest hit); without, in obvhs's octant order
    /// (any hit: no distances to sort or compare).
    #[inline(always)]
    pub(super) fn walk(
        &self,
        ray: &NodeRay,
        t_max: &mut f32,
        ordered: bool,
        mut leaf: impl FnMut(usize, u32, &mut f32) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        obvhs::fast_stack!((u32, f32), (INLINE_STACK), self.stack_need, stack, {
            self.walk_with(&mut stack, ray, t_max, ordered, &mut leaf)
        });
    }

    /// Visits, in no particular order, the leaves of every node whose box `overlap` keeps
    /// (it returns the kept children of a node, bit `c` for child `c`), calling
    /// `leaf(packet, lanes)` until it returns `true`; returns whether one did.
    pub(super) fn any_leaf(
        &self,
        overlap: impl Fn(&WideNode) -> u32,
        mut leaf: impl FnMut(usize, u32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        obvhs::fast_stack!(u32, (INLINE_STACK), self.stack_need + 1, stack, {
            stack.push(0);
            while let Some(node) = stack.pop() {
                let n = &self.nodes[node as usize];
                let kept = overlap(n);
                let mut leaves = kept & u32::from(n.leaf);
                while leaves != 0 {
                    let c = leaves.trailing_zeros() as usize;
                    leaves &= leaves - 1;
                    if leaf(n.child[c] as usize, (n.lanes >> (4 * c)) & 0xf) {
                        return true;
                    }
                }
                let mut inner = kept & u32::from(n.inner);
                while inner != 0 {
                    stack.push(n.child[inner.trailing_zeros() as usize]);
                    inner &= inner - 1;
                }
            }
            false
        })
    }

    #[inline(always)]
    fn walk_with(
        &self,
        stack: &mut impl FastStack<(u32, f32)>,
        ray: &NodeRay,
        t_max: &mut f32,
        ordered: bool,
        leaf: &mut impl FnMut(usize, u32, &mut f32) -> bool,
    ) {
        let mut node = 0u32;
        loop {
            let n = &self.nodes[node as usize];
            let (hit, near) = n.intersect(ray, *t_max);
            let mut leaves = hit & u32::from(n.leaf);
            while leaves != 0 {
                let c = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                if leaf(n.child[c] as usize, (n.lanes >> (4 * c)) & 0xf, t_max) {
                    return;
                }
            }
            let mut inner = hit & u32::from(n.inner);
            let next = match inner.count_ones() {
                0 => None,
                1 => Some(n.child[inner.trailing_zeros() as usize]),
                _ if !ordered => {
                    // obvhs's order: descending `slot ^ octant`; push the rest so that the
                    // next in that order is popped first.
                    let o = ray.octant;
                    let mut order = u32::from(XOR_PERMUTE[o][inner as usize]);
                    let first = 31 - order.leading_zeros();
                    order &= !(1 << first);
                    while order != 0 {
                        let b = order.trailing_zeros();
                        order &= order - 1;
                        stack.push((n.child[(b as usize) ^ o], 0.0));
                    }
                    Some(n.child[first as usize ^ o])
                }
                _ => {
                    // Push the hit children farthest first, then descend into the nearest.
                    let mut found = [(0u32, 0.0f32); 8];
                    let mut k = 0;
                    while inner != 0 {
                        let c = inner.trailing_zeros() as usize;
                        inner &= inner - 1;
                        let t = near[c];
                        // Insertion by distance, nearest last.
                        let mut j = k;
                        while j > 0 && found[j - 1].1 < t {
                            found[j] = found[j - 1];
                            j -= 1;
                        }
                        found[j] = (n.child[c], t);
                        k += 1;
                    }
                    for &entry in &found[..k - 1] {
                        stack.push(entry);
                    }
                    Some(found[k - 1].0)
                }
            };
            node = match next {
                Some(child) => child,
                None => loop {
                    let Some((child, t)) = stack.pop() else {
                        return;
                    };
                    if t <= *t_max {
                        break child;
                    }
                },
            };
        }
    }
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
    /// The direction's octant as obvhs orders children by: bit 2 set for x >= 0, bit 1 for
    /// y, bit 0 for z.
    pub(super) octant: usize,
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
            octant: usize::from(inv[0] >= 0.0) << 2
                | usize::from(inv[1] >= 0.0) << 1
                | usize::from(inv[2] >= 0.0),
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
            let w = WideNode::decode(n, |_| 0);
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
