//! The one-ray walks: closest hit front to back with distance culling, any hit with early
//! exit ([`Bvh8::walk`]), and the unordered visit of every leaf a test keeps
//! ([`Bvh8::any_leaf`], for shaft culling).

use obvhs::faststack::FastStack;

use super::layout::Bvh8;
use super::node::Node8;
use super::node::{FAR_SLACK, NodeRay};
use super::stack::with_stack;

impl Bvh8 {
    /// Visits the leaves `ray` reaches within `t_max`, calling `leaf(quad, lanes, t_max)`;
    /// the call may shorten `t_max` (a closer hit), and returns `true` to stop the walk. With
    /// `ordered`, inner children are visited nearest first and a pushed child is skipped once
    /// `t_max` is below its entry distance (closest hit); without, farthest first in the
    /// builder's octant order (any hit: no distances to sort or compare; see
    /// [`Node8::descend`]). Where a node has several leaves to visit, their quads are
    /// prefetched first; several inner children to visit likewise.
    #[inline(always)]
    pub(crate) fn walk(
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
    /// `leaf(quad, lanes)` until it returns `true`; returns whether one did.
    pub(crate) fn any_leaf(
        &self,
        overlap: impl Fn(&Node8) -> u32,
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
            // cache misses overlap: all leaves' quads when there are two or more to test, all
            // inner children when there are two or more to visit (those pushed are often popped
            // soon after). One leaf or child is read right away anyway.
            if leaves.count_ones() > 1 {
                let mut rest = leaves;
                while rest != 0 {
                    self.arena
                        .quad(n.child[rest.trailing_zeros() as usize])
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
