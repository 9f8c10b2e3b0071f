//! Collapsing obvhs's binary BVH (one triangle per leaf) into 8-wide nodes whose leaves hold
//! up to [`LEAF_SIZE`] triangles, one four-lane packet test each. Which binary nodes become
//! 8-wide nodes, which become leaves and which are opened into their parent is chosen by
//! dynamic programming on the surface area heuristic (the collapse of Ylitie, Karras & Laine
//! 2017, with our costs: a leaf costs one packet test however many lanes it fills). Leaves
//! of one node whose triangles fit together share a packet, each testing only its own lanes.

use glam::Vec4;
use obvhs::bvh2::Bvh2;

use super::wide::WideNode;

/// Most triangles in one leaf: the lanes of one packet.
pub(super) const LEAF_SIZE: u32 = 4;

/// SAH cost of testing a node's eight child boxes, per unit of the node's half area.
const NODE_COST: f32 = 1.0;

/// SAH cost of one packet test (up to four triangles), per unit of the leaf's half area.
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
/// leaf, or of several leaves of one node that fit together) as one packet and returns its
/// index, which names those leaves; each leaf's lanes in it are in the node's `lanes`.
pub(super) fn collapse(bvh: &Bvh2, mut leaf: impl FnMut(&[u32]) -> u32) -> Vec<WideNode> {
    let plan = plan(bvh);
    let mut nodes: Vec<WideNode> = Vec::new();
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
        let mut node = WideNode::EMPTY;
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
        // The node's leaves share packets where their triangles fit together (largest first,
        // each into the first packet with room, in slot order among equals): a packet's
        // lanes are tested only where its leaf's box is hit, so sharing costs no test, and
        // the tree is smaller (on the generated 1M room 3.50 triangles per packet instead of
        // 2.59, nodes and packets 62.7 MB instead of 78.9 before alignment padding).
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
            let packet = leaf(held);
            for &s in slots {
                node.child[s] = packet;
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

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec3A};

    use super::LEAF_SIZE;
    use crate::accel::wide::{HOT_BYTES, PacketNodeRays};
    use crate::accel::{Accel, Ray, TriangleHit};
    use rand::Rng;

    use crate::workload::rng;

    /// Checks the subtree of node `node`: every child box contains its subtree's triangles,
    /// leaves hold 1 to [`LEAF_SIZE`] triangles whose stored corners are the mesh's, unused
    /// lanes name no triangle. Counts each triangle met in `seen`; returns the bounds of the
    /// subtree's corners.
    fn check(
        accel: &Accel,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        node: usize,
        seen: &mut [u32],
    ) -> (Vec3A, Vec3A) {
        let n = accel.bvh.arena.node(node as u32);
        assert_eq!(n.inner & n.leaf, 0, "a child both inner and leaf");
        let mut all = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        // Per packet, the lanes the node's leaves hold.
        let mut shared = std::collections::HashMap::new();
        for c in 0..8 {
            let (lo, hi) = if n.leaf & (1 << c) != 0 {
                let p = n.child[c] as usize;
                let lanes = (n.lanes >> (4 * c)) & 0xf;
                assert!(
                    lanes != 0 && ((lanes >> lanes.trailing_zeros()) + 1).is_power_of_two(),
                    "lanes {lanes:b}"
                );
                assert!(lanes.count_ones() <= LEAF_SIZE);
                // Leaves of this node that share the packet hold other lanes of it.
                let held = shared.entry(p).or_insert(0);
                assert_eq!(*held & lanes, 0, "two leaves hold one lane");
                *held |= lanes;
                let packet = accel.bvh.arena.packet(p as u32);
                let v = &packet.v;
                let mut b = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
                for (lane, &id) in packet.ids.iter().enumerate() {
                    if lanes & (1 << lane) == 0 {
                        continue;
                    }
                    seen[id as usize] += 1;
                    for (vertex, &i) in triangles[id as usize].iter().enumerate() {
                        let q =
                            Vec3A::new(v[0][vertex][lane], v[1][vertex][lane], v[2][vertex][lane]);
                        assert_eq!(Vec3::from(q), positions[i as usize]);
                        b = (b.0.min(q), b.1.max(q));
                    }
                }
                b
            } else if n.inner & (1 << c) != 0 {
                let child = n.child[c] as usize;
                assert!(child > node, "child stored before its parent");
                check(accel, positions, triangles, child, seen)
            } else {
                continue;
            };
            let (half, lane) = (c / 4, c % 4);
            for axis in 0..3 {
                assert!(
                    n.bounds[4 * axis + half][lane] <= lo[axis],
                    "box misses a corner"
                );
                assert!(
                    n.bounds[4 * axis + 2 + half][lane] >= hi[axis],
                    "box misses a corner"
                );
            }
            all = (all.0.min(lo), all.1.max(hi));
        }
        // A packet's lanes that no leaf holds name no triangle.
        for (p, held) in shared {
            for (lane, &id) in accel.bvh.arena.packet(p as u32).ids.iter().enumerate() {
                assert_eq!(held & (1 << lane) == 0, id == u32::MAX, "lane {lane}");
            }
        }
        all
    }

    /// Builds the accelerator and checks the whole tree; every triangle is in exactly one leaf.
    fn build_and_check(positions: &[Vec3], triangles: &[[u32; 3]], hot_bytes: usize) -> Accel {
        let accel = Accel::build_laid_out(
            positions,
            triangles,
            obvhs::BvhBuildParams::medium_build(),
            hot_bytes,
        );
        let mut seen = vec![0; triangles.len()];
        if triangles.is_empty() {
            assert_eq!(accel.node_count(), 0);
        } else {
            check(&accel, positions, triangles, 0, &mut seen);
        }
        assert!(
            seen.iter().all(|&s| s == 1),
            "a triangle not in exactly one leaf"
        );
        accel
    }

    /// `count` random triangles of varied sizes in a box of side `scale` (optionally all in
    /// the plane z = 0).
    fn soup(count: usize, scale: f32, flat: bool, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut r = rng(seed);
        let point = |r: &mut rand_pcg::Pcg64Mcg| {
            let z = if flat { 0.0 } else { r.random::<f32>() };
            Vec3::new(r.random::<f32>(), r.random::<f32>(), z) * scale
        };
        let mut positions = Vec::new();
        for _ in 0..count {
            let a = point(&mut r);
            let size = 0.002 + 0.2 * r.random::<f32>().powi(4);
            let corner = |r: &mut rand_pcg::Pcg64Mcg| {
                let d = (point(r) - Vec3::splat(0.5 * scale)) * size;
                a + if flat { d.with_z(0.0) } else { d }
            };
            let (b, c) = (corner(&mut r), corner(&mut r));
            positions.extend([a, b, c]);
        }
        let triangles = (0..count as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        (positions, triangles)
    }

    /// What two closest-hit answers must share: the distance and the triangle (of triangles
    /// hit at the same distance, through a shared edge or vertex, the smallest index).
    fn key(h: Option<TriangleHit>) -> Option<(f32, u32)> {
        h.map(|h| (h.t, h.triangle))
    }

    #[test]
    fn collapsed_trees_are_valid_and_agree_with_the_oracle() {
        let cases = [
            (0, 1.0, false),
            (1, 1.0, false),
            (3, 1.0, false),
            (4, 1.0, false),
            (5, 1.0, false),
            (9, 1.0, true),
            (2000, 1.0, false),
            (2000, 1e-4, false),
            (2000, 1e5, false),
            (2000, 1.0, true),
        ];
        for (seed, &(count, scale, flat)) in cases.iter().enumerate() {
            let (positions, triangles) = soup(count, scale, flat, seed as u64);
            let accel = build_and_check(&positions, &triangles, HOT_BYTES);
            // The same tree with no top levels stored first (every interleaved turn one node),
            // with only the first two or so (turns go on through them, then switch), and with
            // every level first.
            let laid_out =
                [0, 6 << 10, usize::MAX].map(|hot| build_and_check(&positions, &triangles, hot));
            if count == 2000 {
                let ends = laid_out
                    .each_ref()
                    .map(|a| (a.bvh.hot_end as usize, a.bvh.arena.units().len()));
                assert_eq!(ends[0].0, 0);
                assert!(ends[1].0 > 0 && ends[1].0 < ends[1].1, "{ends:?}");
                assert_eq!(ends[2].0, ends[2].1);
            }
            let mut r = rng(1000 + seed as u64);
            // Every ray cast, and the brute force's answer: the many-ray walks must agree.
            let mut rays = Vec::new();
            let mut expected = Vec::new();
            for _ in 0..1000 {
                let o = Vec3::new(
                    r.random::<f32>(),
                    r.random::<f32>(),
                    r.random::<f32>() * 2.0 - 0.5,
                ) * scale;
                let target = if triangles.is_empty() || r.random::<f32>() < 0.5 {
                    Vec3::new(r.random::<f32>(), r.random::<f32>(), r.random::<f32>()) * scale
                } else {
                    // Aimed at a vertex: watertightness at shared corners.
                    positions[(r.random::<u64>() % positions.len() as u64) as usize]
                };
                let d = target - o;
                if d.length() == 0.0 {
                    continue;
                }
                let fast = accel.closest(o, d, f32::INFINITY);
                let slow = Accel::closest_brute_force(&positions, &triangles, o, d, f32::INFINITY);
                // Same distance and, at shared edges and vertices, the same triangle.
                assert_eq!(key(fast), key(slow), "case {seed}");
                assert_eq!(
                    accel.any_hit(o, d, f32::INFINITY),
                    slow.is_some(),
                    "case {seed}"
                );
                rays.push(Ray {
                    origin: o,
                    direction: d,
                    t_max: f32::INFINITY,
                });
                expected.push(slow);
                if let Some(h) = slow {
                    // Just short of the nearest hit: nothing is hit.
                    assert!(!accel.any_hit(o, d, h.t), "case {seed}");
                    rays.push(Ray {
                        origin: o,
                        direction: d,
                        t_max: h.t,
                    });
                    expected.push(None);
                }
            }
            // Whole batches, and batches shorter than the rays a walk keeps in flight.
            for (accel, n) in [&accel, &laid_out[0], &laid_out[1], &laid_out[2]]
                .into_iter()
                .flat_map(|a| [rays.len(), 0, 1, 7, 9].map(|n| (a, n)))
            {
                let n = n.min(rays.len());
                // The public calls (one ray after another on these small trees) and the
                // interleaved walks they use on large ones.
                let mut hits = vec![None; n];
                accel.closest_many(&rays[..n], &mut hits);
                let mut blocked = vec![true; n];
                accel.any_hit_many(&rays[..n], &mut blocked);
                let mut woven = vec![None; n];
                accel.closest_interleaved(&rays[..n], &mut woven);
                let mut woven_blocked = vec![true; n];
                accel.any_hit_interleaved(&rays[..n], &mut woven_blocked);
                for (i, (ray, slow)) in rays.iter().zip(&expected).take(n).enumerate() {
                    let one = accel.closest(ray.origin, ray.direction, ray.t_max);
                    assert_eq!(hits[i], one, "case {seed}");
                    assert_eq!(woven[i], one, "case {seed}");
                    assert_eq!(key(hits[i]), key(*slow), "case {seed}");
                    assert_eq!(blocked[i], slow.is_some(), "case {seed}");
                    assert_eq!(woven_blocked[i], slow.is_some(), "case {seed}");
                }
            }
        }
    }

    /// Coherent rays (a pinhole camera's, in row order) walked as packets of eight give every
    /// ray exactly the single-ray walk's answer and the brute force's distance and triangle:
    /// rays from one origin and from slightly different ones, some aimed at vertices (ties at
    /// shared corners), some stopped just short of their hit, a fan that crosses an axis (its
    /// packets there fall back to one ray at a time), batches that do not fill their last
    /// packet, scenes of 1e-4 to 1e5 units.
    #[test]
    fn coherent_packets_agree_with_the_single_ray_walk_and_the_oracle() {
        for (seed, &(count, scale, flat)) in [
            (2000, 1.0, false),
            (2000, 1e-4, false),
            (2000, 1e5, false),
            (2000, 1.0, true),
            (3, 1.0, false),
        ]
        .iter()
        .enumerate()
        {
            let (positions, triangles) = soup(count, scale, flat, 70 + seed as u64);
            let accel = build_and_check(&positions, &triangles, HOT_BYTES);
            let (p, t) = (&positions, &triangles);
            let oracle = |r: &Ray| Accel::closest_brute_force(p, t, r.origin, r.direction, r.t_max);
            let mut r = rng(2000 + seed as u64);
            // Looking down at the soup from above its middle (every direction has z < 0), in
            // from its side (x > 0 throughout), and from its front with a fan whose directions
            // change sign across the image (those packets fall back).
            for (eye, look, spread) in [
                (Vec3::new(0.5, 0.5, 2.0), Vec3::new(0.5, 0.5, 0.0), 0.6),
                (Vec3::new(-1.0, 0.4, 0.5), Vec3::new(0.5, 0.5, 0.5), 0.3),
                (Vec3::new(0.5, -1.0, 0.5), Vec3::new(0.5, 0.5, 0.5), 0.4),
            ] {
                let (eye, look) = (eye * scale, look * scale);
                let forward = (look - eye).normalize();
                let (right, up) = forward.any_orthonormal_pair();
                let (w, h) = (37, 29);
                let mut rays = Vec::new();
                for y in 0..h {
                    for x in 0..w {
                        let u = spread * ((x as f32 + 0.5) / w as f32 - 0.5);
                        let v = spread * ((y as f32 + 0.5) / h as f32 - 0.5);
                        let mut d = forward + right * u + up * v;
                        let mut o = eye;
                        match (x + y * w) % 7 {
                            // From an origin a little apart from the eye.
                            1 => {
                                o += Vec3::new(
                                    r.random::<f32>(),
                                    r.random::<f32>(),
                                    r.random::<f32>(),
                                ) * 1e-3
                                    * scale
                            }
                            // Aimed at a vertex.
                            3 if !positions.is_empty() => {
                                let p = positions
                                    [(r.random::<u64>() % positions.len() as u64) as usize];
                                // In the octant of the ray it replaces, so that its packet
                                // holds.
                                if (p - eye).signum() == d.signum() {
                                    d = p - eye;
                                }
                            }
                            _ => {}
                        }
                        rays.push(Ray {
                            origin: o,
                            direction: d,
                            t_max: f32::INFINITY,
                        });
                    }
                }
                // Every fourth ray stopped just short of its nearest hit.
                for ray in rays.iter_mut().step_by(4) {
                    if let Some(h) = accel.closest(ray.origin, ray.direction, f32::INFINITY) {
                        ray.t_max = h.t;
                    }
                }
                let origins: Vec<Vec3> = rays.iter().map(|r| r.origin).collect();
                let directions: Vec<Vec3> = rays.iter().map(|r| r.direction).collect();
                let packets = origins
                    .chunks(8)
                    .zip(directions.chunks(8))
                    .filter(|(o, d)| PacketNodeRays::new(o, d).is_some())
                    .count();
                assert!(
                    2 * packets > rays.len() / 8,
                    "most rays are walked as packets ({packets})"
                );
                for n in [rays.len(), 1, 8, 13] {
                    // The packet walk itself (`closest_many` takes it for batches it finds
                    // coherent; the aimed and displaced rays here would make it doubt).
                    let mut hits = vec![None; n];
                    accel.closest_packets(&rays[..n], &mut hits);
                    for (ray, hit) in rays.iter().zip(&hits) {
                        let one = accel.closest(ray.origin, ray.direction, ray.t_max);
                        assert_eq!(*hit, one, "case {seed}");
                        assert_eq!(key(*hit), key(oracle(ray)), "case {seed}");
                    }
                }
            }
        }
        // A fan across the x = 0 plane: its packets there mix signs and are walked one ray
        // at a time.
        let o = [Vec3::ZERO; 2];
        assert!(
            PacketNodeRays::new(&o, &[Vec3::new(-0.1, 0.0, 1.0), Vec3::new(0.1, 0.0, 1.0)])
                .is_none()
        );
        assert!(
            PacketNodeRays::new(&o, &[Vec3::new(0.1, 0.0, 1.0), Vec3::new(0.2, 0.0, 1.0)])
                .is_some()
        );
        assert!(PacketNodeRays::new(&o[..1], &[Vec3::new(f32::NAN, 0.0, 1.0)]).is_none());
        assert!(PacketNodeRays::new(&[], &[]).is_none());
    }
}
