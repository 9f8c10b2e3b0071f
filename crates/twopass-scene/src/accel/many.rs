//! The many-ray queries: coherent rays (camera rays in pixel order) walked as packets of eight,
//! other rays interleaved where the tree is larger than the cache, else one after another.

use glam::Vec3;

use super::build::Accel;
use super::bvh::{NodeRay, RayPacket};
use super::hit::{Nearest, TriangleHit, keep_nearer, search_bound};
use super::quad::{QuadRay, RayLanes};
use super::ray::Ray;
use super::triangle::ShearedRay;

/// Size of the tree (nodes and quads, bytes) up to which [`Accel::closest_many`] and
/// [`Accel::any_hit_many`] walk rays that are not coherent one after another: such a tree
/// stays largely in the last-level cache, where interleaving has few misses to overlap and
/// only costs. Interleaving pays only when the tree is larger than the last-level cache, so
/// the best threshold depends on the machine; this one is of the order of a server's L3.
pub const INTERLEAVE_MIN_BYTES: usize = 16 << 20;

/// Angle between two neighbouring rays' directions, radians, within which
/// [`Accel::closest_many`] and [`Accel::any_hit_many`] count them as coherent (with
/// [`COHERENT_ORIGINS`]): one degree, about 13 pixels of a 512-pixel-wide image at a 40-degree
/// field of view.
pub const COHERENT_ANGLE: f32 = std::f32::consts::PI / 180.0;

/// Distance between two neighbouring rays' origins, as a fraction of the scene's diagonal,
/// within which the many-ray calls count them as coherent (with [`COHERENT_ANGLE`]).
pub const COHERENT_ORIGINS: f32 = 1e-3;

impl Accel {
    /// [`Accel::closest`] for many rays: `hits[i]` for ray `i`, the same answers. Coherent rays
    /// (neighbours within [`COHERENT_ANGLE`] and [`COHERENT_ORIGINS`] of each other, such as
    /// camera rays in pixel order) are walked eight at a time as one packet, which tests each
    /// node once for all eight and a leaf that many of them reach once per triangle for all
    /// of them. Other rays, where the tree is larger than
    /// [`INTERLEAVE_MIN_BYTES`], are walked several at a time, interleaved, so that one ray's
    /// cache misses overlap another's work. A smaller tree stays in the cache, where
    /// interleaving would only cost, so there they are walked one after another.
    ///
    /// # Panics
    /// When `hits` and `rays` differ in length.
    pub fn closest_many(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        if self.placed.is_some() {
            self.closest_each_placed(rays, hits);
        } else if self.coherent(rays) {
            self.closest_packets(rays, hits);
        } else if self.bvh.bytes() > INTERLEAVE_MIN_BYTES {
            self.closest_interleaved(rays, hits);
        } else {
            self.closest_each(rays, hits);
        }
    }

    /// [`Accel::closest_each`] in a scene with placed copies, which are walked ray by ray
    /// (their trees are entered per ray); kept out of line so that the walks of a scene
    /// without copies stay as they are.
    #[cold]
    #[inline(never)]
    fn closest_each_placed(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
        self.closest_each(rays, hits);
    }

    /// [`Accel::closest`] for each of `rays` in turn.
    fn closest_each(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
        for (hit, r) in hits.iter_mut().zip(rays) {
            *hit = self.closest(r.origin, r.direction, r.t_max);
        }
    }

    /// [`Accel::closest_many`]'s walk of coherent rays: eight neighbours at a time as one
    /// packet ([`Bvh8::walk_packet`]), or one after another where a packet's rays differ
    /// in direction octant or one of them is not finite.
    pub(super) fn closest_packets(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
        let mut stack = Vec::new();
        // Each packet's rays as the triangle tests see them, written in place packet after
        // packet (an array made anew per packet would be copied, a kilobyte per packet).
        let mut sheared: [QuadRay; 8] =
            std::array::from_fn(|_| QuadRay::new(&ShearedRay::new(Vec3::ZERO, Vec3::Z)));
        for (rays, hits) in rays.chunks(8).zip(hits.chunks_mut(8)) {
            let n = rays.len();
            let ray = |i: usize| &rays[i.min(n - 1)];
            let origins: [Vec3; 8] = std::array::from_fn(|i| ray(i).origin);
            let directions: [Vec3; 8] = std::array::from_fn(|i| ray(i).direction);
            let Some(packet) = RayPacket::new(&origins[..n], &directions[..n]) else {
                self.closest_each(rays, hits);
                continue;
            };
            for (i, s) in sheared.iter_mut().enumerate() {
                *s = QuadRay::new(&ShearedRay::new(ray(i).origin, ray(i).direction));
            }
            let mut t_max: [f32; 8] = std::array::from_fn(|i| ray(i).t_max);
            let mut best: [Option<Nearest>; 8] = [None; 8];
            let in_lanes = RayLanes::new(&sheared);
            self.bvh.walk_packet(
                &packet,
                &mut t_max,
                &mut stack,
                #[inline(always)]
                |mut rays, p, lanes, t_max| match &in_lanes {
                    // More than twice as many rays as triangles: each triangle against all
                    // the rays at once (with fewer rays, one test per ray costs less).
                    Some(in_lanes) if rays.count_ones() > 2 * lanes.count_ones() => {
                        self.nearer_in_lanes(in_lanes, rays, p, lanes, t_max, &mut best)
                    }
                    _ => {
                        while rays != 0 {
                            let i = rays.trailing_zeros() as usize;
                            rays &= rays - 1;
                            self.nearer(&sheared[i], p, lanes, &mut t_max[i], &mut best[i]);
                        }
                    }
                },
            );
            for (i, hit) in hits.iter_mut().enumerate() {
                *hit = best[i].map(|b| self.hit(b, t_max[i]));
            }
        }
    }

    /// [`Accel::nearer`] for each ray `rays` (bits) of a packet against lanes `lanes` of quad
    /// `p`, tested one triangle at a time against all those rays at once ([`RayLanes`]). Each
    /// triangle is tested against each ray as [`Accel::nearer`] would test it (with a bound
    /// of the ray's `t_max`, a few ulps beyond once it has a hit), each hit bit for bit the
    /// same, and kept by the same rule, so each ray ends with the hit the one-ray tests give.
    #[inline(always)]
    fn nearer_in_lanes(
        &self,
        in_lanes: &RayLanes,
        rays: u32,
        p: u32,
        lanes: u32,
        t_max: &mut [f32; 8],
        best: &mut [Option<Nearest>; 8],
    ) {
        let quad = self.bvh.arena.quad(p);
        let mut tris = lanes;
        while tris != 0 {
            let lane = tris.trailing_zeros() as usize;
            tris &= tris - 1;
            let bound = wide::f32x8::new(std::array::from_fn(|i| search_bound(t_max[i], &best[i])));
            let hits = in_lanes.intersect(quad, lane, rays, bound);
            let id = quad.ids[lane];
            let mut found = hits.mask;
            while found != 0 {
                let i = found.trailing_zeros() as usize;
                found &= found - 1;
                keep_nearer(&mut best[i], &mut t_max[i], hits.t_of(i), id, || Nearest {
                    quad: p,
                    lane,
                    id,
                    barycentric: hits.barycentric(i),
                });
            }
        }
    }

    /// Whether the many-ray calls interleave `rays`: the tree is larger than
    /// [`INTERLEAVE_MIN_BYTES`] and the rays are not [`Accel::coherent`].
    fn interleaves(&self, rays: &[Ray]) -> bool {
        self.bvh.bytes() > INTERLEAVE_MIN_BYTES && !self.coherent(rays)
    }

    /// Whether most of `rays` (three in four, of every fourth pair of neighbours) leave from
    /// within [`COHERENT_ORIGINS`] of the scene's diagonal of the ray before them, in a
    /// direction within [`COHERENT_ANGLE`] of it: camera rays in pixel order, say. Such rays
    /// walk the same nodes one after another, which then stay in the cache, so interleaving
    /// them only costs; [`Accel::closest_many`] walks them as packets instead.
    pub(super) fn coherent(&self, rays: &[Ray]) -> bool {
        let Some((lo, hi)) = self.bvh.bounds() else {
            return false;
        };
        let near = COHERENT_ORIGINS * (hi - lo).length();
        let cos = COHERENT_ANGLE.cos();
        let (mut pairs, mut close) = (0usize, 0usize);
        for w in rays.windows(2).step_by(4) {
            let (a, b) = (&w[0], &w[1]);
            pairs += 1;
            let lengths = a.direction.length() * b.direction.length();
            if a.direction.dot(b.direction) > cos * lengths && a.origin.distance(b.origin) <= near {
                close += 1;
            }
        }
        pairs > 0 && 4 * close >= 3 * pairs
    }

    /// [`Accel::closest_many`]'s interleaved walk, whatever the tree's size.
    pub(super) fn closest_interleaved(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
        self.bvh.walk_many(
            rays.len(),
            true,
            |i| Self::walk_start(&rays[i], None),
            #[inline(always)]
            |(sheared, best), p, lanes, t_max| {
                self.nearer(sheared, p, lanes, t_max, best);
                false
            },
            |i, t, (_, best)| hits[i] = best.map(|b| self.hit(b, t)),
        );
    }

    /// What an interleaved walk starts ray `r` with: the ray as the node and quad tests see
    /// it, its `t_max`, and `found`, what it has found so far.
    fn walk_start<F>(r: &Ray, found: F) -> (NodeRay, f32, (QuadRay, F)) {
        let sheared = QuadRay::new(&ShearedRay::new(r.origin, r.direction));
        (
            NodeRay::new(r.origin, r.direction),
            r.t_max,
            (sheared, found),
        )
    }

    /// [`Accel::any_hit`] for many rays: `blocked[i]` for ray `i`, the same answers, walked
    /// as [`Accel::closest_many`] walks its rays (interleaved on large trees unless the rays
    /// are coherent).
    ///
    /// # Panics
    /// When `blocked` and `rays` differ in length.
    pub fn any_hit_many(&self, rays: &[Ray], blocked: &mut [bool]) {
        assert_eq!(rays.len(), blocked.len(), "one answer per ray");
        if self.placed.is_none() && self.interleaves(rays) {
            self.any_hit_interleaved(rays, blocked);
        } else {
            for (b, r) in blocked.iter_mut().zip(rays) {
                *b = self.any_hit(r.origin, r.direction, r.t_max);
            }
        }
    }

    /// [`Accel::any_hit_many`]'s interleaved walk, whatever the tree's size.
    pub(super) fn any_hit_interleaved(&self, rays: &[Ray], blocked: &mut [bool]) {
        self.bvh.walk_many(
            rays.len(),
            false,
            |i| Self::walk_start(&rays[i], false),
            #[inline(always)]
            |(sheared, hit), p, lanes, t_max| {
                *hit = sheared
                    .intersect(self.bvh.arena.quad(p), lanes, *t_max)
                    .mask
                    != 0;
                *hit
            },
            |i, _, (_, hit)| blocked[i] = hit,
        );
    }
}
