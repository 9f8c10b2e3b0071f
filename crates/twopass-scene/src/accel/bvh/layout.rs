//! The 8-wide tree laid out for the walks: nodes and quads in one arena, the top levels first
//! (level by level), the rest depth first, each node followed by its leaves' quads.

use glam::Vec3;

use super::node::{NODE_BLOCKS, Node8};
use crate::accel::arena::{Arena, write_blocks};
use crate::accel::quad::{QUAD_BLOCKS, TriangleQuad};

/// The tree, laid out for the walk: the root at block 0, then the rest of the top levels that
/// fit in [`HOT_BYTES`] level by level (blocks before `hot_end`), then the subtrees below them
/// depth first, each node followed by its leaves' quads (in slot order), then its inner
/// children's subtrees (in slot order). A node starts on an even block (64 bytes: a cache
/// line, since the table starts on one).
pub(crate) struct Bvh8 {
    pub(crate) arena: Arena,
    /// Number of nodes.
    pub(crate) nodes: usize,
    /// Number of quads (leaves).
    pub(crate) quads: usize,
    /// The most entries the traversal stack can hold at once: over every path from the root,
    /// the sum of the inner children pushed beside the one descended into.
    pub(crate) stack_need: usize,
    /// Nodes that start before this block are the tree's top levels (at most [`HOT_BYTES`]),
    /// stored first.
    pub(crate) hot_end: u32,
}

/// Size of the tree's top levels that are stored first and that an interleaved walk goes
/// through without switching rays, bytes (a part of a core's L2 cache).
pub(crate) const HOT_BYTES: usize = 128 << 10;

impl Bvh8 {
    /// The tree's memory (nodes and quads), bytes.
    pub(crate) fn bytes(&self) -> usize {
        std::mem::size_of_val(self.arena.blocks())
    }

    /// The box around every triangle (min, max), from the root's children; `None` for an
    /// empty tree.
    pub(crate) fn bounds(&self) -> Option<(Vec3, Vec3)> {
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
    /// their index in `nodes` or `quads`) and `quads`, its top levels stored first as far
    /// as they fit in `hot_bytes` ([`HOT_BYTES`] for the trees `Accel` builds;
    /// the tests vary it).
    pub(crate) fn new(nodes: Vec<Node8>, quads: &[TriangleQuad], hot_bytes: usize) -> Self {
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
        let mut hot_blocks = 0;
        for &items in &per_level {
            // Counted generously: a quad as a node.
            hot_blocks += items * NODE_BLOCKS;
            if hot_blocks * 32 > hot_bytes {
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
        // Below them depth first, inner children in slot order; each node's quads right
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
        let mut quad_at = vec![u32::MAX; quads.len()];
        let mut end = 0usize;
        let mut hot_end = 0usize;
        for (k, &i) in order.iter().enumerate() {
            end += end % 2;
            node_at[i] = end as u32;
            end += NODE_BLOCKS;
            // A quad that several of the node's leaves share is stored once.
            for c in slots(nodes[i].leaf) {
                let p = nodes[i].child[c] as usize;
                if quad_at[p] == u32::MAX {
                    quad_at[p] = end as u32;
                    end += QUAD_BLOCKS;
                }
            }
            if k + 1 == hot_nodes {
                hot_end = end;
            }
        }
        assert!(u32::try_from(end).is_ok(), "tree over 128 GiB");
        let mut blocks = vec![bytemuck::Zeroable::zeroed(); end];
        for &i in &order {
            let mut n = nodes[i];
            for c in slots(n.inner) {
                n.child[c] = node_at[n.child[c] as usize];
            }
            for c in slots(n.leaf) {
                let p = n.child[c] as usize;
                n.child[c] = quad_at[p];
                write_blocks(&mut blocks, quad_at[p] as usize, &quads[p]);
            }
            write_blocks(&mut blocks, node_at[i] as usize, &n);
        }
        Self {
            hot_end: hot_end as u32,
            stack_need: need.first().copied().unwrap_or(0),
            arena: Arena::of(blocks),
            nodes: nodes.len(),
            quads: quads.len(),
        }
    }
}
