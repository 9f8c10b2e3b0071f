//! The collapsed tree's invariants (boxes contain their triangles, every triangle stored once,
//! the layout's top levels first) and the walks on it against the brute-force oracle: one ray,
//! interleaved and in packets, on random triangle soups and at every scale.

use glam::{Vec3, Vec3A};
use rand::Rng;

use crate::accel::bvh::{HOT_BYTES, RayPacket};
use crate::accel::collapse::LEAF_SIZE;
use crate::accel::{Accel, Ray, TriangleHit};
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
            // Leaves of this node that share the quad hold other lanes of it.
            let held = shared.entry(p).or_insert(0);
            assert_eq!(*held & lanes, 0, "two leaves hold one lane");
            *held |= lanes;
            let quad = accel.bvh.arena.quad(p as u32);
            let v = &quad.v;
            let mut b = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
            for (lane, &id) in quad.ids.iter().enumerate() {
                if lanes & (1 << lane) == 0 {
                    continue;
                }
                seen[id as usize] += 1;
                for (vertex, &i) in triangles[id as usize].iter().enumerate() {
                    let q = Vec3A::new(v[0][vertex][lane], v[1][vertex][lane], v[2][vertex][lane]);
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
    // A quad's lanes that no leaf holds name no triangle.
    for (p, held) in shared {
        for (lane, &id) in accel.bvh.arena.quad(p as u32).ids.iter().enumerate() {
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
                .map(|a| (a.bvh.hot_end as usize, a.bvh.arena.blocks().len()));
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
                            o += Vec3::new(r.random::<f32>(), r.random::<f32>(), r.random::<f32>())
                                * 1e-3
                                * scale
                        }
                        // Aimed at a vertex.
                        3 if !positions.is_empty() => {
                            let p =
                                positions[(r.random::<u64>() % positions.len() as u64) as usize];
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
                .filter(|(o, d)| RayPacket::new(o, d).is_some())
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
    assert!(RayPacket::new(&o, &[Vec3::new(-0.1, 0.0, 1.0), Vec3::new(0.1, 0.0, 1.0)]).is_none());
    assert!(RayPacket::new(&o, &[Vec3::new(0.1, 0.0, 1.0), Vec3::new(0.2, 0.0, 1.0)]).is_some());
    assert!(RayPacket::new(&o[..1], &[Vec3::new(f32::NAN, 0.0, 1.0)]).is_none());
    assert!(RayPacket::new(&[], &[]).is_none());
}

/// Depth of the 8-wide tree below `node` (1 for a node with only leaves), without recursion.
fn depth(accel: &Accel) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1usize)];
    while let Some((node, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = accel.bvh.arena.node(node);
        for c in 0..8 {
            if n.inner & (1 << c) != 0 {
                stack.push((n.child[c], d + 1));
            }
        }
    }
    deepest
}

/// Issue 43, finding 2: 10^5 copies of one triangle. The tree is valid, every copy is in it
/// once, and it is shallow: 10^5 triangles in leaves of up to 4 need 25,000 leaves, which
/// 8-wide nodes hold in ceil(log8 25000) = 5 levels; a balanced binary tree collapsed by 3
/// levels per node stays within a few more (a chain of copies would be thousands deep).
#[test]
fn coincident_triangles_build_a_shallow_valid_tree() {
    let positions = vec![
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let triangles = vec![[0u32, 1, 2]; 100_000];
    let accel = build_and_check(&positions, &triangles, HOT_BYTES);
    let d = depth(&accel);
    assert!((5..=8).contains(&d), "depth {d}");
    // A ray straight down through the triangle hits a copy at distance 1.
    let hit = accel
        .closest(Vec3::new(0.25, 1.0, -0.25), Vec3::NEG_Y, f32::INFINITY)
        .expect("the copies are hit");
    assert_eq!(hit.t, 1.0);
    assert!(accel.any_hit(Vec3::new(0.25, 1.0, -0.25), Vec3::NEG_Y, 2.0));
}
