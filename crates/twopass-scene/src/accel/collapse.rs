//! Collapsing obvhs's binary BVH (one triangle per leaf) into 8-wide nodes whose leaves hold
//! up to [`LEAF_SIZE`] triangles, one four-lane quad test each. Which binary nodes become
//! 8-wide nodes, which become leaves and which are opened into their parent is chosen by
//! dynamic programming on the surface area heuristic (the collapse of Ylitie, Karras & Laine
//! 2017, with our costs: a leaf costs one quad test however many lanes it fills). Leaves
//! of one node whose triangles fit together share a quad, each testing only its own lanes.

use glam::Vec4;
use obvhs::bvh2::Bvh2;

use super::bvh::Node8;

/// Most triangles in one leaf: the lanes of one quad.
pub(super) const LEAF_SIZE: u32 = 4;

/// SAH cost of testing a node's eight child boxes, per unit of the node's half area.
const NODE_COST: f32 = 1.0;

/// SAH cost of one quad test (up to four triangles), per unit of the leaf's half area.
const LEAF_COST: f32 = 1.0;

/// What the DP chose for a binary node given `i` slots (`choice[node][i - 1]`).
#[derive(Clone, Copy)]
enum Choice {
    /// One slot: the subtree as one leaf.
    Leaf,
    /// One slot: the subtree as one 8-wide node.
    Inner,
    /// Split the slots: `k` to the left child, the rest to the right one.
    Split(u8),
    /// Use one slot fewer (as cheap or cheaper).
    Fewer,
}

/// The DP's tables over the binary tree.
struct Plan<'a> {
    bvh: &'a Bvh2,
    choice: Vec<[Choice; 8]>,
}

impl Plan<'_> {
    /// The pieces binary node `n` is opened into with `i` slots, appended to `out`.
    fn pieces(&self, n: usize, i: usize, out: &mut Vec<usize>) {
        match self.choice[n][i - 1] {
            Choice::Leaf | Choice::Inner => out.push(n),
            Choice::Fewer => self.pieces(n, i - 1, out),
            Choice::Split(k) => {
                let left = self.bvh.nodes[n].first_index as usize;
                self.pieces(left, usize::from(k), out);
                self.pieces(left + 1, i - usize::from(k), out);
            }
        }
    }

    /// The scene triangles under binary node `n`, appended to `out`.
    fn triangles(&self, n: usize, out: &mut Vec<u32>) {
        let mut stack = vec![n];
        while let Some(n) = stack.pop() {
            let node = &self.bvh.nodes[n];
            if node.is_leaf() {
                let first = node.first_index as usize;
                out.extend_from_slice(
                    &self.bvh.primitive_indices[first..first + node.prim_count as usize],
                );
            } else {
                let left = node.first_index as usize;
                stack.extend([left + 1, left]);
            }
        }
    }
}

/// The DP: for every binary node, the cheapest way to represent its subtree in 1 to 8 child
/// slots of an 8-wide parent.
fn plan(bvh: &Bvh2) -> Plan<'_> {
    let count = bvh.nodes.len();
    // Pre-order: every child after its parent; the DP runs it backwards.
    let mut order = Vec::with_capacity(count);
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        order.push(n);
        let node = &bvh.nodes[n];
        if !node.is_leaf() {
            let left = node.first_index as usize;
            stack.extend([left, left + 1]);
        }
    }
    let mut cost = vec![[0.0f32; 8]; count];
    let mut prims = vec![0u32; count];
    let mut choice = vec![[Choice::Fewer; 8]; count];
    for &n in order.iter().rev() {
        let node = &bvh.nodes[n];
        let area = node.aabb().half_area();
        if node.is_leaf() {
            assert!(
                node.prim_count <= LEAF_SIZE,
                "binary leaf over the leaf size"
            );
            prims[n] = node.prim_count;
            cost[n] = [area * LEAF_COST; 8];
            choice[n][0] = Choice::Leaf;
            continue;
        }
        let (l, r) = (node.first_index as usize, node.first_index as usize + 1);
        prims[n] = prims[l] + prims[r];
        // distribute[j - 1]: the cheapest split of `j` slots over the two children.
        let mut distribute = [(f32::INFINITY, 0u8); 8];
        for (j, d) in distribute.iter_mut().enumerate().skip(1) {
            for k in 1..=j {
                let c = cost[l][k - 1] + cost[r][j - k];
                if c < d.0 {
                    *d = (c, k as u8);
                }
            }
        }
        let inner = area * NODE_COST + distribute[7].0;
        let leaf = if prims[n] <= LEAF_SIZE {
            area * LEAF_COST
        } else {
            f32::INFINITY
        };
        (cost[n][0], choice[n][0]) = if leaf <= inner {
            (leaf, Choice::Leaf)
        } else {
            (inner, Choice::Inner)
        };
        for i in 1..8 {
            (cost[n][i], choice[n][i]) = if distribute[i].0 < cost[n][i - 1] {
                (distribute[i].0, Choice::Split(distribute[i].1))
            } else {
                (cost[n][i - 1], Choice::Fewer)
            };
        }
    }
    Plan { bvh, choice }
}

/// Assigns the children (boxes' centres `centres` relative to their parent's) to slots so that
/// bit 2 of a child's slot is set when it lies towards +x, bit 1 towards +y and bit 0 towards
/// +z (greedily, best match first): visiting `slot ^ octant` in descending order is then
/// roughly front to back for a ray whose direction's octant is `octant` (bit set for a
/// non-negative component).
fn slots(centres: &[Vec4]) -> [usize; 8] {
    let mut score = [[0.0f32; 8]; 8];
    for (c, centre) in centres.iter().enumerate() {
        for (s, score) in score[c].iter_mut().enumerate() {
            let sign = |bit: usize| if s & (1 << bit) != 0 { 1.0 } else { -1.0 };
            *score = centre.x * sign(2) + centre.y * sign(1) + centre.z * sign(0);
        }
    }
    let mut slot = [usize::MAX; 8];
    let mut free = 0xffu32;
    for _ in 0..centres.len() {
        let mut best = (f32::NEG_INFINITY, 0, 0);
        for (c, scores) in score.iter().enumerate().take(centres.len()) {
            if slot[c] != usize::MAX {
                continue;
            }
            for (s, &v) in scores.iter().enumerate() {
                if free & (1 << s) != 0 && (v > best.0 || best.0 == f32::NEG_INFINITY) {
                    best = (v, c, s);
                }
            }
        }
        slot[best.1] = best.2;
        free &= !(1 << best.2);
    }
    slot
}

/// Collapses `bvh` (non-empty, one triangle per leaf) into 8-wide nodes, root first and every
/// node before its children (depth first), each naming its inner children by their index in
/// the list. `leaf(triangles)` stores scene triangles (at most [`LEAF_SIZE`]: those of one
/// leaf, or of several leaves of one node that fit together) as one quad and returns its
/// index, which names those leaves; each leaf's lanes in it are in the node's `lanes`.
pub(super) fn collapse(bvh: &Bvh2, mut leaf: impl FnMut(&[u32]) -> u32) -> Vec<Node8> {
    let plan = plan(bvh);
    let mut nodes: Vec<Node8> = Vec::new();
    let mut pieces = Vec::with_capacity(8);
    let mut leaves: Vec<(usize, Vec<u32>)> = Vec::with_capacity(8);
    // (binary node, its 8-wide parent and slot there); the root has no parent.
    let mut stack = vec![(0usize, usize::MAX, 0usize)];
    while let Some((n, parent, parent_slot)) = stack.pop() {
        let index = nodes.len();
        if parent != usize::MAX {
            nodes[parent].child[parent_slot] = index as u32;
        }
        pieces.clear();
        match plan.choice[n][0] {
            // A root that is one leaf: one node with that leaf as its only child.
            Choice::Leaf => pieces.push(n),
            _ => plan.pieces(n, 8, &mut pieces),
        }
        let centre = bvh.nodes[n].aabb().center();
        let centres: Vec<Vec4> = pieces
            .iter()
            .map(|&p| (bvh.nodes[p].aabb().center() - centre).extend(0.0))
            .collect();
        let slot = slots(&centres);
        let mut min = [[f32::INFINITY; 8]; 3];
        let mut max = [[f32::NEG_INFINITY; 8]; 3];
        let mut node = Node8::EMPTY;
        let mut inner = Vec::with_capacity(8);
        for (&p, &s) in pieces.iter().zip(&slot) {
            let b = bvh.nodes[p].aabb();
            for axis in 0..3 {
                min[axis][s] = b.min[axis];
                max[axis][s] = b.max[axis];
            }
            if matches!(plan.choice[p][0], Choice::Leaf) {
                let mut tris = Vec::with_capacity(LEAF_SIZE as usize);
                plan.triangles(p, &mut tris);
                leaves.push((s, tris));
                node.leaf |= 1 << s;
            } else {
                node.inner |= 1 << s;
                inner.push((p, s));
            }
        }
        // The node's leaves share quads where their triangles fit together (largest first,
        // each into the first quad with room, in slot order among equals): a quad's
        // lanes are tested only where its leaf's box is hit, so sharing costs no test, and
        // the tree is smaller (fuller quads, fewer of them).
        leaves.sort_by_key(|(s, t)| (std::cmp::Reverse(t.len()), *s));
        let mut shared: Vec<(Vec<u32>, Vec<usize>)> = Vec::with_capacity(8);
        for (s, t) in leaves.drain(..) {
            match shared
                .iter_mut()
                .find(|(held, _)| held.len() + t.len() <= LEAF_SIZE as usize)
            {
                Some((held, slots)) => {
                    node.lanes |= (((1 << t.len()) - 1) << held.len()) << (4 * s);
                    held.extend_from_slice(&t);
                    slots.push(s);
                }
                None => {
                    node.lanes |= ((1 << t.len()) - 1) << (4 * s);
                    shared.push((t, vec![s]));
                }
            }
        }
        for (held, slots) in &shared {
            let quad = leaf(held);
            for &s in slots {
                node.child[s] = quad;
            }
        }
        node.set_bounds(&min, &max);
        nodes.push(node);
        // The first inner child (in slot order) is stored right after this node.
        inner.sort_unstable_by_key(|&(_, s)| s);
        stack.extend(inner.iter().rev().map(|&(p, s)| (p, index, s)));
    }
    nodes
}
