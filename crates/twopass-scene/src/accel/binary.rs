//! Binary trees over boxes of which many may be identical (coincident triangles: a mesh
//! exported twice, a face repeated). PLOC merges a pair only when each is the other's best
//! neighbour; among identical boxes every merge costs the same, the tie leaves one mutual
//! pair per pass, and the build takes as many passes as there are copies (quadratic time,
//! a tree as deep as the copies). So each set of identical boxes is built as one box and
//! expanded afterwards into a balanced subtree of its copies.

use std::collections::HashMap;

use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};

/// A binary tree (one box per leaf, leaf `primitive_indices` naming indices into `boxes`)
/// built by `build` over the distinct boxes of `boxes`, each box that occurs `k > 1` times
/// expanded into a balanced subtree of depth `ceil(log2 k)`. `build` gets a list of distinct
/// boxes and must return a tree with one box per leaf whose primitive indices index that list.
/// When every box is distinct, this is `build(boxes)` itself. `boxes` must not be empty.
pub fn build_coincident(boxes: &[Aabb], build: impl FnOnce(&[Aabb]) -> Bvh2) -> Bvh2 {
    // The copies of each distinct box, by the bits of its corners.
    let mut first: HashMap<[u32; 6], u32> = HashMap::with_capacity(boxes.len());
    let mut group = Vec::with_capacity(boxes.len());
    let mut distinct: Vec<Aabb> = Vec::new();
    for b in boxes {
        let key = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
        let g = *first.entry(key).or_insert_with(|| {
            distinct.push(*b);
            (distinct.len() - 1) as u32
        });
        group.push(g);
    }
    if distinct.len() == boxes.len() {
        return build(boxes);
    }
    // The members of group g are members[start[g]..start[g + 1]] (a counting sort).
    let mut start = vec![0u32; distinct.len() + 1];
    for &g in &group {
        start[g as usize + 1] += 1;
    }
    for g in 0..distinct.len() {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; boxes.len()];
    for (i, &g) in group.iter().enumerate() {
        members[fill[g as usize] as usize] = i as u32;
        fill[g as usize] += 1;
    }
    let tree = build(&distinct);
    expand(&tree, &distinct, &start, &members)
}

/// `tree` (over the distinct boxes) with each leaf replaced by a balanced subtree over the
/// copies of its box.
fn expand(tree: &Bvh2, distinct: &[Aabb], start: &[u32], members: &[u32]) -> Bvh2 {
    let mut nodes: Vec<Bvh2Node> = Vec::with_capacity(2 * members.len());
    let mut primitive_indices = Vec::with_capacity(members.len());
    nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
    /// Where a node of the expanded tree comes from.
    enum From {
        /// A node of `tree`.
        Tree(usize),
        /// The copies `members[range]` of one box.
        Copies(u32, u32, Aabb),
    }
    // (source, its slot in `nodes`); children are given adjacent slots, left first.
    let mut stack = vec![(From::Tree(0), 0usize)];
    while let Some((from, slot)) = stack.pop() {
        let (aabb, split) = match from {
            From::Tree(n) => {
                let node = &tree.nodes[n];
                if node.is_leaf() {
                    debug_assert_eq!(node.prim_count, 1, "one box per leaf");
                    let g = tree.primitive_indices[node.first_index as usize] as usize;
                    stack.push((From::Copies(start[g], start[g + 1], distinct[g]), slot));
                    continue;
                }
                let first = node.first_index as usize;
                (*node.aabb(), [From::Tree(first), From::Tree(first + 1)])
            }
            From::Copies(lo, hi, aabb) => {
                if hi - lo == 1 {
                    nodes[slot] = Bvh2Node::new(aabb, 1, primitive_indices.len() as u32);
                    primitive_indices.push(members[lo as usize]);
                    continue;
                }
                let mid = lo + (hi - lo) / 2;
                (
                    aabb,
                    [From::Copies(lo, mid, aabb), From::Copies(mid, hi, aabb)],
                )
            }
        };
        let first = nodes.len();
        nodes[slot] = Bvh2Node::new(aabb, 0, first as u32);
        nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
        nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
        let [left, right] = split;
        stack.push((right, first + 1));
        stack.push((left, first));
    }
    Bvh2 {
        nodes,
        primitive_indices,
        ..Bvh2::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use obvhs::ploc::PlocBuilder;
    use obvhs::{BvhBuildParams, ploc::PlocSearchDistance};

    fn ploc(boxes: &[Aabb]) -> Bvh2 {
        let p = BvhBuildParams::medium_build();
        PlocBuilder::with_capacity(boxes.len()).build(
            PlocSearchDistance::Minimum,
            boxes,
            (0..boxes.len() as u32).collect(),
            p.sort_precision,
            p.search_depth_threshold,
        )
    }

    /// Every input box in exactly one leaf, every inner node's box holding its children's, and
    /// the depth.
    fn check(tree: &Bvh2, boxes: &[Aabb]) -> usize {
        let mut seen = vec![false; boxes.len()];
        let mut depth = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((n, d)) = stack.pop() {
            depth = depth.max(d);
            let node = &tree.nodes[n];
            if node.is_leaf() {
                assert_eq!(node.prim_count, 1);
                let p = tree.primitive_indices[node.first_index as usize] as usize;
                assert!(!seen[p], "box {p} in two leaves");
                seen[p] = true;
                assert_eq!(*node.aabb(), boxes[p]);
            } else {
                for c in [node.first_index as usize, node.first_index as usize + 1] {
                    let child = tree.nodes[c].aabb();
                    assert!(node.aabb().min.cmple(child.min).all());
                    assert!(node.aabb().max.cmpge(child.max).all());
                    stack.push((c, d + 1));
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "a box in no leaf");
        depth
    }

    #[test]
    fn copies_of_one_box_make_a_balanced_tree() {
        let one = Aabb::new(Vec3A::ZERO, Vec3A::new(1.0, 0.0, 1.0));
        let boxes = vec![one; 100_000];
        let tree = build_coincident(&boxes, ploc);
        // 100,000 copies: a balanced tree of depth ceil(log2 100000) + 1 levels = 18.
        assert_eq!(check(&tree, &boxes), 18);
    }

    #[test]
    fn mixed_copies_keep_every_box() {
        let mut boxes = Vec::new();
        for i in 0..50 {
            let b = Aabb::new(Vec3A::splat(i as f32), Vec3A::splat(i as f32 + 0.5));
            // Box i occurs i + 1 times.
            boxes.extend(std::iter::repeat_n(b, i + 1));
        }
        let tree = build_coincident(&boxes, ploc);
        let depth = check(&tree, &boxes);
        // 50 distinct boxes (at most 50 levels above the copies) and at most 50 copies
        // (6 levels more); a chain over the 1,275 boxes would be far deeper.
        assert!(depth <= 56, "depth {depth}");
    }

    #[test]
    fn distinct_boxes_are_built_as_given() {
        let boxes: Vec<Aabb> = (0..100)
            .map(|i| Aabb::new(Vec3A::splat(i as f32), Vec3A::splat(i as f32 + 1.0)))
            .collect();
        let direct = ploc(&boxes);
        let tree = build_coincident(&boxes, ploc);
        let shape = |t: &Bvh2| {
            t.nodes
                .iter()
                .map(|n| (*n.aabb(), n.prim_count, n.first_index))
                .collect::<Vec<_>>()
        };
        assert_eq!(shape(&tree), shape(&direct));
        assert_eq!(tree.primitive_indices, direct.primitive_indices);
    }
}
