//! Ray packets: up to eight coherent rays (camera rays in pixel order) walked as one, each
//! node's eight boxes tested once against the packet's bounding interval of rays, each leaf's
//! box against each ray.

use glam::Vec3;
use wide::f32x8;

use super::layout::Bvh8;
use super::node::{FAR_SLACK, Node8, inverse, slabs_hit};

impl Bvh8 {
    /// The walk of up to eight coherent rays as one packet (rays in lanes): a node's eight
    /// child boxes are tested against the packet's bounding interval of rays (one eight-box
    /// test for all its rays, [`RayPacket::cull`]); the inner children it keeps are
    /// visited, nearest first by its bound on their entry, with every ray that entered the
    /// node, and each leaf child it keeps is tested against each of those rays
    /// ([`RayPacket::lanes_hit`], the very operations of [`Node8::intersect`] for that
    /// ray). A leaf is handed to `leaf(rays, quad, lanes, t_max)` with the rays (bits) whose
    /// own box test it passed; `t_max[lane]` (each ray's, shortened by its hits) bounds that
    /// test, and a popped child is skipped for the rays whose `t_max` is below its entry bound.
    /// The cull keeps every box a ray's own test would, so each ray meets every leaf the
    /// single-ray walk would meet for it (and perhaps a few whose box it meets, under a node
    /// it would have missed by a rounding), in another order: its closest hit is the same.
    /// `stack` is reused from packet to packet.
    pub(crate) fn walk_packet(
        &self,
        rays: &RayPacket,
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
            // quads and nodes prefetched.
            let mut rest = kept & u32::from(n.leaf | n.inner);
            let mut order = [0usize; 8];
            let mut count = 0;
            while rest != 0 {
                let c = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                if n.leaf & (1 << c) != 0 {
                    self.arena.quad(n.child[c]).prefetch();
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

/// Up to eight rays as [`Bvh8::walk_packet`] tests them: each ray's origin and inverse
/// direction in its lane (exactly as [`NodeRay`] forms them), and the interval of all of them
/// for the packet's conservative cull. Built only for rays whose inverse directions agree in
/// sign on each axis, so all enter a box through the same planes.
pub(crate) struct RayPacket {
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

impl RayPacket {
    /// The packet of the rays from `origins` along `directions` (at most eight, and as many
    /// of each), or `None` when their directions differ in sign on some axis or an origin or
    /// inverse direction is not finite.
    pub(crate) fn new(origins: &[Vec3], directions: &[Vec3]) -> Option<Self> {
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
    pub(crate) fn cull(&self, n: &Node8, t_max: f32) -> (u32, [f32; 8]) {
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
    /// operations [`Node8::intersect`] applies for it.
    #[inline(always)]
    pub(crate) fn lanes_hit(&self, n: &Node8, c: usize, t_max: f32x8) -> u32 {
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

/// Whether every lane of `inv` is negative (`near` 1) or none is (`near` 0).
fn signs_agree(inv: &[f32; 8], near: usize) -> bool {
    inv.iter().all(|&i| usize::from(i < 0.0) == near)
}
