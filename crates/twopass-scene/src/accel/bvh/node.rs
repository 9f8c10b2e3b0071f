//! The 8-wide node: its eight child boxes (f32, built by `collapse.rs`), the ray as the node
//! test sees it ([`NodeRay`]), the eight-box slab test (one eight-lane vector per plane) and
//! the choice of the child to descend into.

use glam::{Vec3, Vec4};
use wide::f32x8;

use crate::accel::arena::{Arena, Block32};
use crate::accel::prefetch::prefetch;

/// Blocks of one [`Node8`] (256 bytes: four cache lines when it starts on a line).
pub(crate) const NODE_BLOCKS: usize = 8;

const _: () = assert!(std::mem::size_of::<Node8>() == 32 * NODE_BLOCKS);
const _: () = assert!(std::mem::align_of::<Node8>() <= std::mem::align_of::<Block32>());

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
pub(crate) const MAX_INVERSE: f32 = 1e20;

/// Factor on a box's exit distance (and on `t_max` where an entry distance is compared with
/// it), so that rounding never culls a box the ray meets. The slab distances `(p - origin) *
/// inverse` are each within `gamma(3)` of their exact values, relative (pbrt-v4's
/// `Bounds3::IntersectP` scales by `1 + 2 * gamma(3)`, 3 `f32::EPSILON`); this is 16, which
/// also covers a hit's `t` (a closest-hit walk's `t_max`) a few ulps short of the exact entry
/// of a box holding a triangle hit at that same point. Relative, the slack holds for any
/// scene size and any distance of the ray's origin, and it never turns a negative exit (a box
/// behind the origin, such as that of the surface a ray leaves) positive. The walks' tests
/// (`accel::tests`, the workspace's `accel` suite) fail with 1.0 and pass from
/// `1 + 2 * f32::EPSILON`.
pub(crate) const FAR_SLACK: f32 = 1.0 + 16.0 * f32::EPSILON;

/// `XOR_PERMUTE[o][m]` moves bit `c` of `m` to bit `c ^ o`. The builder places a node's
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

/// One 8-wide node: its children's boxes (the binary tree's boxes, exact unions of the
/// triangles' boxes) and what each child is: an inner node, a leaf (lanes of one triangle
/// quad), or empty. In the built tree (`Bvh8`) children are named by where they start in its
/// arena (in [`Block32`]s); while building, by their index in the builder's node and quad
/// lists.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct Node8 {
    /// `bounds[4 * axis + 2 * side + half]`: lane `j` is child `4 * half + j`; side 0 is the
    /// box minimum, 1 the maximum. Empty children are empty boxes (min +inf, max -inf).
    pub(crate) bounds: [Vec4; 12],
    /// Per child: where its node (inner) or its quad (leaf) starts; 0 when empty.
    pub(crate) child: [u32; 8],
    /// Per child, four bits from bit `4 * child`: the leaf's lanes in its quad (leaves of
    /// one node may share a quad, each holding other lanes of it).
    pub(crate) lanes: u32,
    /// Bit `c` set when child `c` is an inner node.
    pub(crate) inner: u8,
    /// Bit `c` set when child `c` is a leaf.
    pub(crate) leaf: u8,
    /// Up to 256 bytes (four cache lines, eight arena blocks), spelled out so that a node has
    /// no padding bytes (it can be copied as plain bytes).
    _unused: [u8; 26],
}

impl Node8 {
    /// A node with no children.
    pub(crate) const EMPTY: Self = Self {
        bounds: [
            Vec4::INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::NEG_INFINITY,
        ],
        child: [0; 8],
        lanes: 0,
        inner: 0,
        leaf: 0,
        _unused: [0; 26],
    };

    /// Sets the children's boxes: `min[axis][c]` and `max[axis][c]` bound child `c` (an empty
    /// child's box is min +inf, max -inf).
    pub(crate) fn set_bounds(&mut self, min: &[[f32; 8]; 3], max: &[[f32; 8]; 3]) {
        for axis in 0..3 {
            for half in 0..2 {
                let r = 4 * half..4 * half + 4;
                self.bounds[4 * axis + half] = Vec4::from_slice(&min[axis][r.clone()]);
                self.bounds[4 * axis + 2 + half] = Vec4::from_slice(&max[axis][r]);
            }
        }
    }

    /// Of the inner children `inner` (hit by `ray`, entry distances `near`), the one to descend
    /// into; the others go to `push` (child, entry distance) so that the next to visit is
    /// pushed last. With `ordered`, nearest first; without (any hit: no distances to sort;
    /// pushed with distance 0), farthest first in the builder's octant order. A ray that
    /// leaves a surface, as every shadow ray does, enters the boxes of that surface's own
    /// leaves first, and they can hardly block it; from the far end (for a shadow ray, the
    /// light's), what blocks it is found before them.
    #[inline(always)]
    pub(super) fn descend(
        &self,
        mut inner: u32,
        near: &[f32; 8],
        ray: &NodeRay,
        ordered: bool,
        mut push: impl FnMut((u32, f32)),
    ) -> u32 {
        if inner.count_ones() == 1 {
            return self.child[inner.trailing_zeros() as usize];
        }
        if !ordered {
            // Descending `slot ^ octant` is front to back; that of the reversed direction's
            // octant back to front. Push the rest so that the next in that order is popped
            // first.
            let o = ray.octant ^ 7;
            let mut order = u32::from(XOR_PERMUTE[o][inner as usize]);
            let first = 31 - order.leading_zeros();
            order &= !(1 << first);
            while order != 0 {
                let b = order.trailing_zeros();
                order &= order - 1;
                push((self.child[(b as usize) ^ o], 0.0));
            }
            return self.child[first as usize ^ o];
        }
        if inner.count_ones() == 2 {
            // The commonest case after one: push the farther, descend into the nearer (at
            // equal distances the later slot, as the insertion below orders them). The `& 7`
            // only tells the compiler a slot is below 8, so it drops the bounds checks.
            let a = inner.trailing_zeros() as usize & 7;
            let b = (inner & (inner - 1)).trailing_zeros() as usize & 7;
            let (nearer, farther) = if near[b] <= near[a] { (b, a) } else { (a, b) };
            push((self.child[farther], near[farther]));
            return self.child[nearer];
        }
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
            found[j] = (self.child[c], t);
            k += 1;
        }
        for &entry in &found[..k - 1] {
            push(entry);
        }
        found[k - 1].0
    }

    /// Starts loading the node's four cache lines.
    #[inline(always)]
    pub(super) fn prefetch(&self) {
        prefetch(&self.bounds[0]);
        prefetch(&self.bounds[4]);
        prefetch(&self.bounds[8]);
        prefetch(&self.child);
    }

    /// The children hit by `ray` within `[0, t_max]` (bit `c` for child `c`) and each child's
    /// entry distance.
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        self.slab_test::<false>(ray, t_max)
    }

    /// [`Node8::intersect`] with both planes of each slab loaded from fixed places and
    /// ordered by `min` / `max` instead of picked by the ray's direction: more operations, but
    /// no load waits on the ray's data, which an interleaved walk reloads on every turn. The
    /// same answers for every child, but an empty one (its box min +inf, max -inf spans every
    /// distance here), which is neither inner nor leaf and so never visited.
    #[inline(always)]
    pub(super) fn intersect_both_planes(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        self.slab_test::<true>(ray, t_max)
    }

    /// The slab test of [`Node8::intersect`] (`BOTH_PLANES` false) and
    /// [`Node8::intersect_both_planes`] (true), on all eight children at once.
    #[inline(always)]
    fn slab_test<const BOTH_PLANES: bool>(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        // `planes[2 * axis + side]`: the eight children's box minima (side 0) or maxima (1)
        // on `axis`, child `c` in lane `c`.
        let planes: &[[f32; 8]; 6] = bytemuck::cast_ref(&self.bounds);
        let t = |axis: usize, side: usize| {
            (f32x8::new(planes[2 * axis + side]) - ray.origin[axis]) * ray.inv[axis]
        };
        let slab = |axis: usize| {
            if BOTH_PLANES {
                let (lo, hi) = (t(axis, 0), t(axis, 1));
                (lo.fast_min(hi), lo.fast_max(hi))
            } else {
                let near = ray.near[axis] & 1;
                (t(axis, near), t(axis, near ^ 1))
            }
        };
        slabs_hit([slab(0), slab(1), slab(2)], f32x8::splat(t_max))
    }
}

impl Arena {
    /// The node at block `at`.
    #[inline(always)]
    pub(crate) fn node(&self, at: u32) -> &Node8 {
        self.item::<Node8, NODE_BLOCKS>(at)
    }
}

/// The slab test's last step, for eight boxes against one ray or one box against eight rays:
/// each lane's entry and exit distances on the three axes (`slabs[axis]`, near then far)
/// clipped to `[0, t_max]`; the lanes hit (bit per lane) and each lane's entry distance.
#[inline(always)]
pub(super) fn slabs_hit(slabs: [(f32x8, f32x8); 3], t_max: f32x8) -> (u32, [f32; 8]) {
    let [(nx, fx), (ny, fy), (nz, fz)] = slabs;
    let t_near = nx.fast_max(ny).fast_max(nz.fast_max(f32x8::ZERO));
    let t_far = fx.fast_min(fy).fast_min(fz.fast_min(t_max)) * f32x8::splat(FAR_SLACK);
    (t_near.simd_le(t_far).to_bitmask(), t_near.to_array())
}

/// The ray as the node test sees it: origin and inverse direction splatted per axis, so that a
/// plane at `p` is met at `t = (p - origin) * inv`, within a few ulps of `t` itself whatever
/// the coordinates' size (the test allows for it with [`FAR_SLACK`]; the fused `p * inv -
/// origin * inv` would err by ulps of `origin * inv`, which a ray from far away makes larger
/// than the distances it compares), and for each axis which side of a box the ray enters
/// first. Negative zeros in the direction become positive and inverses are clamped to
/// [`MAX_INVERSE`], so no slab ever forms 0 * inf; the entry side is chosen from the sign of
/// the inverse itself, so near and far always agree with it (a mismatch would cull every box).
pub(crate) struct NodeRay {
    pub(crate) inv: [f32x8; 3],
    /// The origin per axis, splatted.
    pub(crate) origin: [f32x8; 3],
    /// 0 when the ray enters through the box minimum on this axis, 1 through the maximum.
    pub(crate) near: [usize; 3],
    /// The direction's octant as the builder orders children by: bit 2 set for x >= 0, bit 1 for
    /// y, bit 0 for z.
    pub(crate) octant: usize,
}

/// The inverse of a direction component `x` (a negative zero made positive first), clamped to
/// [`MAX_INVERSE`].
#[inline(always)]
pub(super) fn inverse(x: f32) -> f32 {
    let i = 1.0 / x;
    if i.abs() > MAX_INVERSE {
        MAX_INVERSE.copysign(x)
    } else {
        i
    }
}

impl NodeRay {
    pub(crate) fn new(origin: Vec3, direction: Vec3) -> Self {
        let d = direction + Vec3::ZERO;
        let inv = [inverse(d.x), inverse(d.y), inverse(d.z)];
        Self {
            inv: inv.map(f32x8::splat),
            origin: [
                f32x8::splat(origin.x),
                f32x8::splat(origin.y),
                f32x8::splat(origin.z),
            ],
            near: inv.map(|i| usize::from(i < 0.0)),
            octant: usize::from(inv[0] >= 0.0) << 2
                | usize::from(inv[1] >= 0.0) << 1
                | usize::from(inv[2] >= 0.0),
        }
    }
}
