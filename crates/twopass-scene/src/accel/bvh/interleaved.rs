//! The interleaved walk: several rays walked in turn, one node each, with what each reads next
//! prefetched at the end of its turn, so that the cache misses of different rays overlap.
//! It pays only when the tree is larger than the last-level cache; the many-ray calls decide.

use super::layout::Bvh8;
use super::node::{FAR_SLACK, NodeRay};

/// Rays an interleaved walk ([`Bvh8::walk_many`]) keeps in flight.
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
    /// Leaves to test on its next turn (prefetched): quad and lanes.
    pending: [(u32, u32); 8],
    pending_count: usize,
}

impl Bvh8 {
    /// The walk of `count` rays at once ([`Bvh8::walk`] for each): [`INTERLEAVE`] rays are
    /// walked in turn, one node each, and what a ray will read next (its next node, its
    /// leaves' quads) is prefetched when its turn ends, so that by its next turn it is in the
    /// cache: the cache misses of different rays overlap instead of each ray waiting on its
    /// own. Through the top levels (before `hot_end`, which every walk passes and the cache
    /// keeps) a turn goes on descending until it finds leaves or leaves them. `start(i)` gives
    /// ray `i`'s node ray, its `t_max` and the state `leaf(state, quad, lanes, t_max)` tests
    /// a quad with (it may shorten `t_max`, and returns `true` to stop the ray's walk);
    /// `finish(i, t_max, state)` is called once per ray, in no particular order. Each ray
    /// meets the leaves the single-ray walk would, in the same order.
    pub(crate) fn walk_many<P>(
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
                        self.arena.quad(n.child[c]).prefetch();
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
}
