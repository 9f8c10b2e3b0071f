//! The walks' stacks: on trees whose stack need is small, near the inline stack's capacity and
//! over it, every walk holds what it pushes and answers as the brute-force oracle.

use glam::Vec3;
use rand::Rng;

use crate::accel::bvh::stack::INLINE_STACK;
use crate::accel::{Accel, Ray};
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
                let ids = accel.bvh.arena.quad(p as u32).ids;
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
