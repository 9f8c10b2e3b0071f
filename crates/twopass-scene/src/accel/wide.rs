//! 8-wide BVH nodes (f32 child boxes, built by [`collapse`](mod@super::collapse)), the
//! eight-box slab test (one eight-lane vector per plane), and the traversals: one ray ordered
//! front to back with distance culling for closest hits and early exit for occlusion, several
//! rays interleaved, and coherent rays as packets of eight.

use arrayvec::ArrayVec;
use glam::{Vec3, Vec4};
use obvhs::faststack::FastStack;
use wide::f32x8;

use super::packet::TriPacket;
use super::table::{Arena, NODE_UNITS, PACKET_UNITS, prefetch, write_units};

/// Largest inverse direction component: finite, so the slab test never forms 0 * inf.
pub(super) const MAX_INVERSE: f32 = 1e20;

/// Factor on a box's exit distance (and on `t_max` where an entry distance is compared with
/// it), so that rounding never culls a box the ray meets. The slab distances `(p - origin) *
/// inverse` are each within `gamma(3)` of their exact values, relative (pbrt-v4's
/// `Bounds3::IntersectP` scales by `1 + 2 * gamma(3)`, 3 `f32::EPSILON`); this is 16, which
/// also covers a hit's `t` (a closest-hit walk's `t_max`) a few ulps short of the exact entry
/// of a box holding a triangle hit at that same point. Relative, the slack holds for any
/// scene size and any distance of the ray's origin, and it never turns a negative exit (a box
/// behind the origin, such as that of the surface a ray leaves) positive. The walk's tests
/// (`accel::wide`, `accel::collapse`, the workspace's `accel` suite) fail with 1.0 and pass
/// from `1 + 2 * f32::EPSILON`.
pub(super) const FAR_SLACK: f32 = 1.0 + 16.0 * f32::EPSILON;

/// Depth of the traversal stack kept on the call stack; a tree that could need more (checked
/// at build time, [`WideBvh::stack_need`]) traverses with a heap stack of the exact size.
const INLINE_STACK: usize = 64;

/// The walk's stack on the call stack ([`INLINE_STACK`] entries), made for every ray and, unlike
/// obvhs's `StackStack` (an array filled with defaults first: a 520-byte `memset` per ray, 4 %
/// of a camera ray's instructions on the generated 1M room), not written before it is pushed to.
struct InlineStack<T>(ArrayVec<T, INLINE_STACK>);

impl<T> InlineStack<T> {
    fn new() -> Self {
        Self(ArrayVec::new())
    }
}

impl<T: Copy + Default> FastStack<T> for InlineStack<T> {
    /// Pushes `v`; the walks push at most the tree's stack need, which chose this stack only
    /// when it is at most [`INLINE_STACK`].
    #[inline(always)]
    fn push(&mut self, v: T) {
        self.0.push(v);
    }

    #[inline(always)]
    fn pop_fast(&mut self) -> T {
        self.0.pop().unwrap_or_default()
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        self.0.pop()
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    fn clear(&mut self) {
        self.0.clear();
    }
}

/// Runs `$body` with `$stack` a [`FastStack`] of `$ty` that holds `$need` entries: an
/// [`InlineStack`] when that fits, else a heap stack of exactly that size.
macro_rules! with_stack {
    ($ty:ty, $need:expr, $stack:ident, $body:block) => {{
        let need = $need;
        if need <= INLINE_STACK {
            let mut $stack = InlineStack::<$ty>::new();
            $body
        } else {
            let mut $stack = obvhs::faststack::HeapStack::<$ty>::new_with_capacity(need);
            $body
        }
    }};
}

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
/// triangles' boxes) and what each child is: an inner node, a leaf (one triangle packet), or empty.
/// In the built tree ([`WideBvh`]) children are named by where they start in its arena (in
/// [`Unit`](super::table::Unit)s); while building, by their index in the builder's node and
/// packet lists.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct WideNode {
    /// `bounds[4 * axis + 2 * side + half]`: lane `j` is child `4 * half + j`; side 0 is the
    /// box minimum, 1 the maximum. Empty children are empty boxes (min +inf, max -inf).
    pub(super) bounds: [Vec4; 12],
    /// Per child: where its node (inner) or its packet (leaf) starts; 0 when empty.
    pub(super) child: [u32; 8],
    /// Per child, four bits from bit `4 * child`: the leaf's lanes in its packet (leaves of
    /// one node may share a packet, each holding other lanes of it).
    pub(super) lanes: u32,
    /// Bit `c` set when child `c` is an inner node.
    pub(super) inner: u8,
    /// Bit `c` set when child `c` is a leaf.
    pub(super) leaf: u8,
    /// Up to 256 bytes (four cache lines, eight arena units), spelled out so that a node has
    /// no padding bytes (it can be copied as plain bytes).
    _unused: [u8; 26],
}

impl WideNode {
    /// A node with no children.
    pub(super) const EMPTY: Self = Self {
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
    pub(super) fn set_bounds(&mut self, min: &[[f32; 8]; 3], max: &[[f32; 8]; 3]) {
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
    /// light's), what blocks it is found before them. Occlusion rays from surfaces to the
    /// light on the generated 1M room: 1.18-1.23x faster than nearest first (in one process,
    /// 1.19 on 102k); a hierarchical solve, whose rays join surfaces at both ends, as fast.
    #[inline(always)]
    fn descend(
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
    fn prefetch(&self) {
        prefetch(&self.bounds[0]);
        prefetch(&self.bounds[4]);
        prefetch(&self.bounds[8]);
        prefetch(&self.child);
    }

    /// The children hit by `ray` within `[0, t_max]` (bit `c` for child `c`) and each child's
    /// entry distance.
    #[inline(always)]
    fn intersect(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        self.slab_test::<false>(ray, t_max)
    }

    /// [`WideNode::intersect`] with both planes of each slab loaded from fixed places and
    /// ordered by `min` / `max` instead of picked by the ray's direction: more operations, but
    /// no load waits on the ray's data, which an interleaved walk reloads on every turn. The
    /// same answers for every child, but an empty one (its box min +inf, max -inf spans every
    /// distance here), which is neither inner nor leaf and so never visited.
    #[inline(always)]
    fn intersect_both_planes(&self, ray: &NodeRay, t_max: f32) -> (u32, [f32; 8]) {
        self.slab_test::<true>(ray, t_max)
    }

    /// The slab test of [`WideNode::intersect`] (`BOTH_PLANES` false) and
    /// [`WideNode::intersect_both_planes`] (true), on all eight children at once.
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

/// The slab test's last step, for eight boxes against one ray or one box against eight rays:
/// each lane's entry and exit distances on the three axes (`slabs[axis]`, near then far)
/// clipped to `[0, t_max]`; the lanes hit (bit per lane) and each lane's entry distance.
#[inline(always)]
fn slabs_hit(slabs: [(f32x8, f32x8); 3], t_max: f32x8) -> (u32, [f32; 8]) {
    let [(nx, fx), (ny, fy), (nz, fz)] = slabs;
    let t_near = nx.fast_max(ny).fast_max(nz.fast_max(f32x8::ZERO));
    let t_far = fx.fast_min(fy).fast_min(fz.fast_min(t_max)) * f32x8::splat(FAR_SLACK);
    (t_near.simd_le(t_far).to_bitmask(), t_near.to_array())
}

/// The tree, laid out for the walk: the root at unit 0, then the rest of the top levels that
/// fit in [`HOT_BYTES`] level by level (units before `hot_end`), then the subtrees below them
/// depth first, each node followed by its leaves' packets (in slot order), then its inner
/// children's subtrees (in slot order). A node starts on an even unit (64 bytes: a cache
/// line, since the table starts on one).
pub(super) struct WideBvh {
    pub(super) arena: Arena,
    /// Number of nodes.
    pub(super) nodes: usize,
    /// Number of packets (leaves).
    pub(super) packets: usize,
    /// The most entries the traversal stack can hold at once: over every path from the root,
    /// the sum of the inner children pushed beside the one descended into.
    stack_need: usize,
    /// Nodes that start before this unit are the tree's top levels (at most [`HOT_BYTES`]),
    /// stored first.
    pub(super) hot_end: u32,
}

/// Size of the tree's top levels that are stored first and that an interleaved walk goes
/// through without switching rays, bytes (a part of a core's L2 cache).
pub(super) const HOT_BYTES: usize = 128 << 10;

impl WideBvh {
    /// The tree's memory (nodes and packets), bytes.
    pub(super) fn bytes(&self) -> usize {
        std::mem::size_of_val(self.arena.units())
    }

    /// The box around every triangle (min, max), from the root's children; `None` for an
    /// empty tree.
    pub(super) fn bounds(&self) -> Option<(Vec3, Vec3)> {
        if self.nodes == 0 {
            return None;
        }
        let b = &self.arena.node(0).bounds;
        // The smallest child minimum and the largest child maximum on `axis`, both halves.
        let (lo, hi) = (
            |axis: usize| b[4 * axis].min(b[4 * axis + 1]).min_element(),
            |axis: usize| b[4 * axis + 2].max(b[4 * axis + 3]).max_element(),
        );
        Some((
            Vec3::new(lo(0), lo(1), lo(2)),
            Vec3::new(hi(0), hi(1), hi(2)),
        ))
    }

    /// The tree of `nodes` (the root first, every node before its children; children named by
    /// their index in `nodes` or `packets`) and `packets`, its top levels stored first as far
    /// as they fit in `hot_bytes` ([`HOT_BYTES`] for the trees [`Accel`](super::Accel) builds;
    /// the tests vary it).
    pub(super) fn new(nodes: Vec<WideNode>, packets: &[TriPacket], hot_bytes: usize) -> Self {
        // Children come after their parents, so one backward sweep sees every
        // child's need before its parent's.
        let mut need = vec![0usize; nodes.len()];
        for (i, n) in nodes.iter().enumerate().rev() {
            let inner = (0..8).filter(|c| n.inner & (1 << c) != 0);
            let deepest = inner
                .map(|c| {
                    let child = n.child[c] as usize;
                    assert!(child > i, "child stored before its parent");
                    need[child]
                })
                .max()
                .unwrap_or(0);
            need[i] = (n.inner.count_ones() as usize).saturating_sub(1) + deepest;
        }
        let slots = |mask: u8| (0..8).filter(move |c| mask & (1 << c) != 0);
        // The top levels, those that fit in `hot_bytes`, first, level by level: nearly every
        // walk passes through them, so they stay in the cache, and an interleaved walk goes
        // through them without switching rays (`hot_end`).
        let mut level = vec![0usize; nodes.len()];
        let mut per_level = Vec::new();
        for (i, n) in nodes.iter().enumerate() {
            if per_level.len() <= level[i] {
                per_level.push(0usize);
            }
            per_level[level[i]] += 1 + n.leaf.count_ones() as usize;
            for c in slots(n.inner) {
                level[n.child[c] as usize] = level[i] + 1;
            }
        }
        let mut hot_levels = 0;
        let mut hot_units = 0;
        for &items in &per_level {
            // Counted generously: a packet as a node.
            hot_units += items * NODE_UNITS;
            if hot_units * 32 > hot_bytes {
                break;
            }
            hot_levels += 1;
        }
        let mut order = Vec::with_capacity(nodes.len());
        let (mut top, mut roots) = (std::collections::VecDeque::new(), Vec::new());
        if !nodes.is_empty() {
            if hot_levels > 0 {
                top.push_back(0usize);
            } else {
                roots.push(0usize);
            }
        }
        while let Some(i) = top.pop_front() {
            order.push(i);
            let n = &nodes[i];
            for c in slots(n.inner) {
                let child = n.child[c] as usize;
                if level[child] < hot_levels {
                    top.push_back(child);
                } else {
                    roots.push(child);
                }
            }
        }
        let hot_nodes = order.len();
        // Below them depth first, inner children in slot order; each node's packets right
        // after it.
        for root in roots {
            let mut stack = vec![root];
            while let Some(i) = stack.pop() {
                order.push(i);
                let n = &nodes[i];
                stack.extend(slots(n.inner).rev().map(|c| n.child[c] as usize));
            }
        }
        let mut node_at = vec![0u32; nodes.len()];
        let mut packet_at = vec![u32::MAX; packets.len()];
        let mut end = 0usize;
        let mut hot_end = 0usize;
        for (k, &i) in order.iter().enumerate() {
            end += end % 2;
            node_at[i] = end as u32;
            end += NODE_UNITS;
            // A packet that several of the node's leaves share is stored once.
            for c in slots(nodes[i].leaf) {
                let p = nodes[i].child[c] as usize;
                if packet_at[p] == u32::MAX {
                    packet_at[p] = end as u32;
                    end += PACKET_UNITS;
                }
            }
            if k + 1 == hot_nodes {
                hot_end = end;
            }
        }
        assert!(u32::try_from(end).is_ok(), "tree over 128 GiB");
        let mut units = vec![bytemuck::Zeroable::zeroed(); end];
        for &i in &order {
            let mut n = nodes[i];
            for c in slots(n.inner) {
                n.child[c] = node_at[n.child[c] as usize];
            }
            for c in slots(n.leaf) {
                let p = n.child[c] as usize;
                n.child[c] = packet_at[p];
                write_units(&mut units, packet_at[p] as usize, &packets[p]);
            }
            write_units(&mut units, node_at[i] as usize, &n);
        }
        Self {
            hot_end: hot_end as u32,
            stack_need: need.first().copied().unwrap_or(0),
            arena: Arena::of(units),
            nodes: nodes.len(),
            packets: packets.len(),
        }
    }

    /// Visits the leaves `ray` reaches within `t_max`, calling `leaf(packet, lanes, t_max)`;
    /// the call may shorten `t_max` (a closer hit), and returns `true` to stop the walk. With
    /// `ordered`, inner children are visited nearest first and a pushed child is skipped once
    /// `t_max` is below its entry distance (closest hit); without, farthest first in the
    /// builder's octant order (any hit: no distances to sort or compare; see
    /// [`WideNode::descend`]). Where a node has several leaves to visit, their packets are
    /// prefetched first; several inner children to visit likewise.
    #[inline(always)]
    pub(super) fn walk(
        &self,
        ray: &NodeRay,
        t_max: &mut f32,
        ordered: bool,
        mut leaf: impl FnMut(usize, u32, &mut f32) -> bool,
    ) {
        if self.nodes == 0 {
            return;
        }
        with_stack!((u32, f32), self.stack_need, stack, {
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
        if self.nodes == 0 {
            return false;
        }
        with_stack!(u32, self.stack_need + 1, stack, {
            stack.push(0);
            while let Some(node) = stack.pop() {
                let n = self.arena.node(node);
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

    /// The walk of `count` rays at once ([`WideBvh::walk`] for each): [`INTERLEAVE`] rays are
    /// walked in turn, one node each, and what a ray will read next (its next node, its
    /// leaves' packets) is prefetched when its turn ends, so that by its next turn it is in the
    /// cache: the cache misses of different rays overlap instead of each ray waiting on its
    /// own. Through the top levels (before `hot_end`, which every walk passes and the cache
    /// keeps) a turn goes on descending until it finds leaves or leaves them. `start(i)` gives
    /// ray `i`'s node ray, its `t_max` and the state `leaf(state, packet, lanes, t_max)` tests
    /// a packet with (it may shorten `t_max`, and returns `true` to stop the ray's walk);
    /// `finish(i, t_max, state)` is called once per ray, in no particular order. Each ray
    /// meets the leaves the single-ray walk would, in the same order.
    pub(super) fn walk_many<P>(
        &self,
        count: usize,
        ordered: bool,
        start: impl Fn(usize) -> (NodeRay, f32, P),
        leaf: impl Fn(&mut P, u32, u32, &mut f32) -> bool,
        mut finish: impl FnMut(usize, f32, P),
    ) {
        if self.nodes == 0 {
            for i in 0..count {
                let (_, t_max, state) = start(i);
                finish(i, t_max, state);
            }
            return;
        }
        let depth = self.stack_need + 1;
        let mut stacks = vec![(0u32, 0.0f32); INTERLEAVE * depth];
        let mut slots: [Option<Walker<P>>; INTERLEAVE] = std::array::from_fn(|_| None);
        let mut fed = 0;
        loop {
            let mut busy = false;
            for (s, slot) in slots.iter_mut().enumerate() {
                if slot.is_none() && fed < count {
                    let (ray, t_max, state) = start(fed);
                    *slot = Some(Walker {
                        index: fed,
                        ray,
                        t_max,
                        state,
                        depth: 0,
                        next: Some(0),
                        pending: [(0, 0); 8],
                        pending_count: 0,
                    });
                    fed += 1;
                }
                let Some(w) = slot else { continue };
                busy = true;
                // The leaves the last turn found, prefetched since.
                let mut stop = false;
                for &(p, lanes) in &w.pending[..w.pending_count] {
                    if leaf(&mut w.state, p, lanes, &mut w.t_max) {
                        stop = true;
                        break;
                    }
                }
                w.pending_count = 0;
                let stack = &mut stacks[s * depth..(s + 1) * depth];
                let mut node = if stop { None } else { w.next.take() };
                while node.is_none() && !stop && w.depth > 0 {
                    w.depth -= 1;
                    let (child, t) = stack[w.depth];
                    if t <= w.t_max * FAR_SLACK {
                        node = Some(child);
                    }
                }
                let Some(mut node) = node else {
                    if let Some(w) = slot.take() {
                        finish(w.index, w.t_max, w.state);
                    }
                    continue;
                };
                loop {
                    let n = self.arena.node(node);
                    let (hit, near) = n.intersect_both_planes(&w.ray, w.t_max);
                    let mut leaves = hit & u32::from(n.leaf);
                    while leaves != 0 {
                        let c = leaves.trailing_zeros() as usize;
                        leaves &= leaves - 1;
                        self.arena.packet(n.child[c]).prefetch();
                        w.pending[w.pending_count] = (n.child[c], (n.lanes >> (4 * c)) & 0xf);
                        w.pending_count += 1;
                    }
                    let inner = hit & u32::from(n.inner);
                    if inner != 0 {
                        let next = n.descend(inner, &near, &w.ray, ordered, |entry| {
                            stack[w.depth] = entry;
                            w.depth += 1;
                        });
                        if next < self.hot_end && w.pending_count == 0 {
                            // In the cache: go on with this ray.
                            node = next;
                            continue;
                        }
                        self.arena.node(next).prefetch();
                        w.next = Some(next);
                    } else if w.depth > 0 {
                        self.arena.node(stack[w.depth - 1].0).prefetch();
                    }
                    break;
                }
            }
            if !busy {
                return;
            }
        }
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
            let n = self.arena.node(node);
            let (hit, near) = n.intersect(ray, *t_max);
            let mut leaves = hit & u32::from(n.leaf);
            // Start loading what this node leads to before working on any of it, so that the
            // cache misses overlap: all leaves' packets when there are two or more to test, all
            // inner children when there are two or more to visit (those pushed are often popped
            // soon after). One leaf or child is read right away anyway.
            if leaves.count_ones() > 1 {
                let mut rest = leaves;
                while rest != 0 {
                    self.arena
                        .packet(n.child[rest.trailing_zeros() as usize])
                        .prefetch();
                    rest &= rest - 1;
                }
            }
            let inner_hit = hit & u32::from(n.inner);
            if inner_hit.count_ones() > 1 {
                let mut rest = inner_hit;
                while rest != 0 {
                    self.arena
                        .node(n.child[rest.trailing_zeros() as usize])
                        .prefetch();
                    rest &= rest - 1;
                }
            }
            while leaves != 0 {
                let c = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                if leaf(n.child[c] as usize, (n.lanes >> (4 * c)) & 0xf, t_max) {
                    return;
                }
            }
            let next = (inner_hit != 0)
                .then(|| n.descend(inner_hit, &near, ray, ordered, |entry| stack.push(entry)));
            node = match next {
                Some(child) => child,
                None => loop {
                    let Some((child, t)) = stack.pop() else {
                        return;
                    };
                    if t <= *t_max * FAR_SLACK {
                        break child;
                    }
                },
            };
        }
    }
}

impl WideBvh {
    /// The walk of up to eight coherent rays as one packet (rays in lanes): a node's eight
    /// child boxes are tested against the packet's bounding interval of rays (one eight-box
    /// test for all its rays, [`PacketNodeRays::cull`]); the inner children it keeps are
    /// visited, nearest first by its bound on their entry, with every ray that entered the
    /// node, and each leaf child it keeps is tested against each of those rays
    /// ([`PacketNodeRays::lanes_hit`], the very operations of [`WideNode::intersect`] for that
    /// ray). A leaf is handed to `leaf(rays, packet, lanes, t_max)` with the rays (bits) whose
    /// own box test it passed; `t_max[lane]` (each ray's, shortened by its hits) bounds that
    /// test, and a popped child is skipped for the rays whose `t_max` is below its entry bound.
    /// The cull keeps every box a ray's own test would, so each ray meets every leaf the
    /// single-ray walk would meet for it (and perhaps a few whose box it meets, under a node
    /// it would have missed by a rounding), in another order: its closest hit is the same.
    /// `stack` is reused from packet to packet.
    pub(super) fn walk_packet(
        &self,
        rays: &PacketNodeRays,
        t_max: &mut [f32; 8],
        stack: &mut Vec<(u32, u32, f32)>,
        mut leaf: impl FnMut(u32, u32, u32, &mut [f32; 8]),
    ) {
        if self.nodes == 0 || rays.active == 0 {
            return;
        }
        stack.clear();
        let mut entry = (0u32, rays.active);
        loop {
            let (node, active) = entry;
            let n = self.arena.node(node);
            // The largest of the eight, a NaN (a ray that meets nothing) passed over, by plain
            // compares (one `maxss` each) rather than `f32::max`'s NaN checks.
            let farthest = t_max
                .iter()
                .fold(f32::NEG_INFINITY, |m, &t| if t > m { t } else { m });
            let (kept, near) = rays.cull(n, farthest);
            // The kept children nearest first (by the packet's bound on their entry), their
            // packets and nodes prefetched.
            let mut rest = kept & u32::from(n.leaf | n.inner);
            let mut order = [0usize; 8];
            let mut count = 0;
            while rest != 0 {
                let c = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                if n.leaf & (1 << c) != 0 {
                    self.arena.packet(n.child[c]).prefetch();
                } else {
                    self.arena.node(n.child[c]).prefetch();
                }
                let mut j = count;
                while j > 0 && near[order[j - 1]] > near[c] {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = c;
                count += 1;
            }
            let mut inner = [(0u32, 0u32, 0.0f32); 8];
            let mut inner_count = 0;
            for &c in &order[..count] {
                if n.leaf & (1 << c) == 0 {
                    // An inner child goes on with every ray that entered this node: the
                    // cull's bound is all its entry distance needs (per-ray box tests here
                    // cost about what the packet saves; the leaves below test each ray).
                    inner[inner_count] = (n.child[c], active, near[c]);
                    inner_count += 1;
                    continue;
                }
                // A leaf: each ray's own box test, against its `t_max` as the leaves before
                // have left it.
                let lanes = rays.lanes_hit(n, c, f32x8::new(*t_max)) & active;
                if lanes != 0 {
                    leaf(lanes, n.child[c], (n.lanes >> (4 * c)) & 0xf, t_max);
                }
            }
            // Nearest visited first: pushed last.
            stack.extend(inner[..inner_count].iter().rev());
            entry = loop {
                let Some((child, lanes, near)) = stack.pop() else {
                    return;
                };
                // Skipped once every ray that entered it has found a hit nearer than its
                // entry.
                let live = lanes
                    & f32x8::splat(near)
                        .simd_le(f32x8::new(*t_max) * f32x8::splat(FAR_SLACK))
                        .to_bitmask();
                if live != 0 {
                    break (child, live);
                }
            };
        }
    }
}

/// Up to eight rays as [`WideBvh::walk_packet`] tests them: each ray's origin and inverse
/// direction in its lane (exactly as [`NodeRay`] forms them), and the interval of all of them
/// for the packet's conservative cull. Built only for rays whose inverse directions agree in
/// sign on each axis, so all enter a box through the same planes.
pub(super) struct PacketNodeRays {
    origin: [f32x8; 3],
    inv: [f32x8; 3],
    /// Per axis, 0 when the rays enter a box through its minimum, 1 through its maximum.
    near: [usize; 3],
    /// Per axis, the origin coordinate that makes the distance to the near plane smallest (the
    /// largest for rays entering through the minimum) and the one that makes the distance to
    /// the far plane largest.
    origin_near: [f32; 3],
    origin_far: [f32; 3],
    /// Per axis, the smallest and largest inverse direction.
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    /// The lanes that hold a ray.
    active: u32,
}

impl PacketNodeRays {
    /// The packet of the rays from `origins` along `directions` (at most eight, and as many
    /// of each), or `None` when their directions differ in sign on some axis or an origin or
    /// inverse direction is not finite.
    pub(super) fn new(origins: &[Vec3], directions: &[Vec3]) -> Option<Self> {
        let count = origins.len().min(directions.len()).min(8);
        if count == 0 {
            return None;
        }
        let mut origin = [[0.0f32; 8]; 3];
        let mut inv = [[0.0f32; 8]; 3];
        for i in 0..8 {
            let (o, d) = (origins[i.min(count - 1)], directions[i.min(count - 1)]);
            let d = d + Vec3::ZERO;
            for axis in 0..3 {
                origin[axis][i] = o[axis];
                inv[axis][i] = inverse(d[axis]);
            }
        }
        // `x - x` is 0 for a finite `x` and NaN for an infinite or NaN one: the 24 values in
        // three vector subtractions and two additions, not 24 scalar checks.
        let finite = |v: &[[f32; 8]; 3]| {
            let zero = |a: &[f32; 8]| f32x8::new(*a) - f32x8::new(*a);
            (zero(&v[0]) + zero(&v[1]) + zero(&v[2]))
                .simd_eq(f32x8::ZERO)
                .to_bitmask()
                == 0xff
        };
        // Plain compares (`minss` / `maxss`), not `f32::min`'s NaN checks: they run only on
        // finite values (checked below before they are used).
        let lo = |v: &[f32; 8]| {
            v.iter()
                .fold(f32::INFINITY, |m, &x| if x < m { x } else { m })
        };
        let hi = |v: &[f32; 8]| {
            v.iter()
                .fold(f32::NEG_INFINITY, |m, &x| if x > m { x } else { m })
        };
        // Entering through the maximum where the inverse is negative, as `NodeRay` decides.
        let near = inv.map(|v| usize::from(v[0] < 0.0));
        let agree = (0..3).all(|a| signs_agree(&inv[a], near[a]));
        if !finite(&origin) || !finite(&inv) || !agree {
            return None;
        }
        let pick = |a: usize, max_first: bool| {
            if (near[a] == 0) == max_first {
                hi(&origin[a])
            } else {
                lo(&origin[a])
            }
        };
        Some(Self {
            origin: origin.map(f32x8::new),
            inv: inv.map(f32x8::new),
            near,
            origin_near: [0, 1, 2].map(|a| pick(a, true)),
            origin_far: [0, 1, 2].map(|a| pick(a, false)),
            inv_lo: inv.map(|v| lo(&v)),
            inv_hi: inv.map(|v| hi(&v)),
            active: (1u32 << count) - 1,
        })
    }

    /// The children of `n` that some ray of the packet may meet within `t_max` (the largest of
    /// the rays'), bit `c` for child `c`, and per child a bound below every ray's entry
    /// distance. A child is dropped only when the nearest entry any ray could have lies beyond
    /// the farthest exit any could have (times [`FAR_SLACK`]). Rounding is monotone, so the
    /// distances formed from the interval's corners with the rays' own operations bound every
    /// ray's rounded ones.
    #[inline(always)]
    fn cull(&self, n: &WideNode, t_max: f32) -> (u32, [f32; 8]) {
        let planes: &[[f32; 8]; 6] = bytemuck::cast_ref(&n.bounds);
        let (mut t_near, mut t_far) = (f32x8::ZERO, f32x8::splat(t_max));
        for axis in 0..3 {
            let side = self.near[axis] & 1;
            let d_near = f32x8::new(planes[2 * axis + side]) - f32x8::splat(self.origin_near[axis]);
            let d_far =
                f32x8::new(planes[2 * axis + (side ^ 1)]) - f32x8::splat(self.origin_far[axis]);
            let (lo, hi) = (
                f32x8::splat(self.inv_lo[axis]),
                f32x8::splat(self.inv_hi[axis]),
            );
            t_near = t_near.fast_max((d_near * lo).fast_min(d_near * hi));
            t_far = t_far.fast_min((d_far * lo).fast_max(d_far * hi));
        }
        (
            t_near.simd_le(t_far * f32x8::splat(FAR_SLACK)).to_bitmask(),
            t_near.to_array(),
        )
    }

    /// The rays (lanes) that meet child `c` of `n` within their `t_max`, each by exactly the
    /// operations [`WideNode::intersect`] applies for it.
    #[inline(always)]
    fn lanes_hit(&self, n: &WideNode, c: usize, t_max: f32x8) -> u32 {
        // `bounds` as plain floats: child `c`'s plane is one load, not a vector taken apart.
        let b: &[f32; 48] = bytemuck::cast_ref(&n.bounds);
        let (half, j) = (c / 4, c % 4);
        let plane = |axis: usize, side: usize| b[4 * (4 * axis + 2 * side + half) + j];
        let t = |axis: usize, side: usize| {
            (f32x8::splat(plane(axis, side)) - self.origin[axis]) * self.inv[axis]
        };
        let slab = |axis: usize| {
            let side = self.near[axis] & 1;
            (t(axis, side), t(axis, side ^ 1))
        };
        slabs_hit([slab(0), slab(1), slab(2)], t_max).0
    }
}

/// Rays an interleaved walk ([`WideBvh::walk_many`]) keeps in flight.
const INTERLEAVE: usize = 8;

/// One ray of an interleaved walk: where it is in the tree.
struct Walker<P> {
    /// The ray's index in the batch.
    index: usize,
    ray: NodeRay,
    t_max: f32,
    /// What the leaf test needs and finds.
    state: P,
    /// Entries on its stack.
    depth: usize,
    /// The node to visit on its next turn (prefetched), else the stack's top.
    next: Option<u32>,
    /// Leaves to test on its next turn (prefetched): packet and lanes.
    pending: [(u32, u32); 8],
    pending_count: usize,
}

/// The ray as the node test sees it: origin and inverse direction splatted per axis, so that a
/// plane at `p` is met at `t = (p - origin) * inv`, within a few ulps of `t` itself whatever
/// the coordinates' size (the test allows for it with [`FAR_SLACK`]; the fused `p * inv -
/// origin * inv` would err by ulps of `origin * inv`, which a ray from far away makes larger
/// than the distances it compares), and for each axis which side of a box the ray enters
/// first. Negative zeros in the direction become positive and inverses are clamped to
/// [`MAX_INVERSE`], so no slab ever forms 0 * inf; the entry side is chosen from the sign of
/// the inverse itself, so near and far always agree with it (a mismatch would cull every box).
pub(super) struct NodeRay {
    pub(super) inv: [f32x8; 3],
    /// The origin per axis, splatted.
    pub(super) origin: [f32x8; 3],
    /// 0 when the ray enters through the box minimum on this axis, 1 through the maximum.
    pub(super) near: [usize; 3],
    /// The direction's octant as the builder orders children by: bit 2 set for x >= 0, bit 1 for
    /// y, bit 0 for z.
    pub(super) octant: usize,
}

/// The inverse of a direction component `x` (a negative zero made positive first), clamped to
/// [`MAX_INVERSE`].
#[inline(always)]
fn inverse(x: f32) -> f32 {
    let i = 1.0 / x;
    if i.abs() > MAX_INVERSE {
        MAX_INVERSE.copysign(x)
    } else {
        i
    }
}

/// Whether every lane of `inv` is negative (`near` 1) or none is (`near` 0).
fn signs_agree(inv: &[f32; 8], near: usize) -> bool {
    inv.iter().all(|&i| usize::from(i < 0.0) == near)
}

impl NodeRay {
    pub(super) fn new(origin: Vec3, direction: Vec3) -> Self {
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

#[cfg(test)]
mod stack_tests {
    use glam::Vec3;

    use super::INLINE_STACK;
    use crate::accel::{Accel, Ray};
    use rand::Rng;

    use crate::workload::rng;

    /// The unit cube split into 3 x 3 x 3 cells: a cluster of eight triangles in each cell but
    /// the one at the origin, and in that one the same again, `levels` deep. Each level gives a
    /// walk many inner children to push beside the one it descends into, so the tree's stack
    /// need grows with `levels`.
    fn nested(levels: usize, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut r = rng(seed);
        let mut positions = Vec::new();
        let mut side = 1.0f32;
        for _ in 0..levels {
            let cell = side / 3.0;
            for k in 1..27u32 {
                let at = Vec3::new((k % 3) as f32, (k / 3 % 3) as f32, (k / 9) as f32) * cell;
                for _ in 0..8 {
                    let mut point = || {
                        at + Vec3::new(r.random::<f32>(), r.random::<f32>(), r.random::<f32>())
                            * cell
                            * 0.8
                    };
                    positions.extend([point(), point(), point()]);
                }
            }
            side = cell;
        }
        let triangles = (0..positions.len() as u32 / 3)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        (positions, triangles)
    }

    /// Every stack the walks choose by the tree's stack need (one on the call stack, else one
    /// on the heap) holds what the walk pushes: on trees whose need lies in each range (a
    /// small need and one of a quarter or more of the call stack's capacity, both on it, and
    /// one over it), closest hits match the brute force, any-hit and the interleaved walks
    /// agree with it, and a walk that keeps every child visits every triangle exactly once.
    #[test]
    fn every_stack_size_holds_the_walk() {
        for (levels, need) in [
            (1, 1..=INLINE_STACK),
            (4, INLINE_STACK / 4..=INLINE_STACK),
            (11, INLINE_STACK + 1..=usize::MAX),
        ] {
            let (positions, triangles) = nested(levels, levels as u64);
            let accel = Accel::build(&positions, &triangles);
            assert!(
                need.contains(&accel.bvh.stack_need),
                "{levels} levels: stack need {} outside {need:?}",
                accel.bvh.stack_need
            );
            let mut seen = vec![0u32; triangles.len()];
            let stopped = accel.bvh.any_leaf(
                |_| 0xff,
                |p, lanes| {
                    let ids = accel.bvh.arena.packet(p as u32).ids;
                    for (lane, &id) in ids.iter().enumerate() {
                        if lanes & (1 << lane) != 0 {
                            seen[id as usize] += 1;
                        }
                    }
                    false
                },
            );
            assert!(!stopped);
            assert!(
                seen.iter().all(|&s| s == 1),
                "{levels} levels: a triangle not visited once"
            );
            let mut r = rng(99);
            let mut rays = Vec::new();
            for _ in 0..2000 {
                let origin =
                    Vec3::new(r.random::<f32>(), r.random::<f32>(), r.random::<f32>()) * 1.4 - 0.2;
                let target = if r.random::<f32>() < 0.5 {
                    // Toward the deepest levels, near the corner the boxes nest in.
                    Vec3::new(r.random::<f32>(), r.random::<f32>(), r.random::<f32>()) * 1e-3
                } else {
                    positions[(r.random::<u64>() % positions.len() as u64) as usize]
                };
                rays.push(Ray::new(origin, target - origin));
            }
            let mut woven = vec![None; rays.len()];
            accel.closest_interleaved(&rays, &mut woven);
            let mut woven_blocked = vec![false; rays.len()];
            accel.any_hit_interleaved(&rays, &mut woven_blocked);
            for (i, ray) in rays.iter().enumerate() {
                let slow = Accel::closest_brute_force(
                    &positions,
                    &triangles,
                    ray.origin,
                    ray.direction,
                    ray.t_max,
                );
                let fast = accel.closest(ray.origin, ray.direction, ray.t_max);
                assert_eq!(
                    fast.map(|h| h.t),
                    slow.map(|h| h.t),
                    "{levels} levels, ray {i}"
                );
                assert_eq!(woven[i], fast, "{levels} levels, ray {i}");
                let blocked = accel.any_hit(ray.origin, ray.direction, ray.t_max);
                assert_eq!(blocked, slow.is_some(), "{levels} levels, ray {i}");
                assert_eq!(woven_blocked[i], blocked, "{levels} levels, ray {i}");
            }
        }
    }
}
