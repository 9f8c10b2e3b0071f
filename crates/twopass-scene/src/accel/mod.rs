//! Ray queries over an 8-wide BVH: closest hit and any hit (occlusion), with a watertight
//! ray-triangle test (Woop, Benthin & Wald 2013, as in pbrt-v4) and conservative error bounds,
//! so rays through shared edges and vertices never slip between triangles and spawned rays can
//! be offset safely (see [`SurfacePoint::spawn_origin`]).
//!
//! One job per module: [`ray`] (rays, surface points, origin offsetting), [`triangle`] (the
//! watertight test), [`quad`] (triangle quads: four triangles per test), [`collapse`](mod@collapse)
//! (the 8-wide tree from obvhs's binary one), [`bvh`] (the 8-wide tree: its nodes, the node
//! test, its layout and the walks), [`arena`] (the tree's memory, in huge pages, in 32-byte
//! blocks), [`prefetch`](mod@prefetch), [`shaft`] (shaft culling); this file is the API:
//! building, closest hit, any hit and the brute-force oracle.

mod arena;
mod bvh;
mod collapse;
mod prefetch;
mod quad;
mod ray;
mod shaft;
#[cfg(test)]
mod tests;
mod triangle;

use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams, aabb::Aabb, bvh2::reinsertion::ReinsertionOptimizer, ploc::PlocBuilder,
};

use bvh::{Bvh8, NodeRay, RayPacket};
use collapse::collapse;
use quad::{QuadRay, RayLanes, TriangleQuad};
pub(crate) use ray::SHADOW_EPSILON;
pub use ray::{Ray, SurfacePoint};
pub use shaft::SHAFT_TOLERANCE;
use shaft::Shaft;
pub(crate) use triangle::triangle_normal;
use triangle::{AxisTriangle, ShearedRay};

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

/// The nearest hit a closest-hit walk has found so far (its `t` is the walk's `t_max`).
#[derive(Clone, Copy)]
struct Nearest {
    /// Where its quad starts in the tree's arena.
    quad: u32,
    /// Its lane in the quad.
    lane: usize,
    /// Scene triangle index.
    id: u32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2.
    barycentric: [f32; 3],
}

/// The result of a closest-hit query: which triangle, where along the ray, barycentrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Scene triangle index.
    pub triangle: u32,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2 (sum 1).
    pub barycentric: [f32; 3],
    /// Positions of the triangle's vertices 0, 1, 2 (the mesh's, bit for bit), from the
    /// accelerator's copy that the test just read, so the caller need not fetch them again.
    pub corners: [Vec3; 3],
}

/// An 8-wide BVH over the scene's triangles (a binary tree built by obvhs's PLOC builder,
/// collapsed into 8-wide nodes with leaves of up to four triangles) with the queries every
/// pass uses.
pub struct Accel {
    /// The tree: its nodes, and one quad per leaf (the leaf's triangles, at most four, in its
    /// first lanes) right after the node that leads to it.
    bvh: Bvh8,
    build_time: Duration,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("quads", &self.bvh.quads)
            .field("nodes", &self.bvh.nodes)
            .field("build_time", &self.build_time)
            .finish()
    }
}

impl Accel {
    /// Builds the BVH over `triangles` (vertex indices into `positions`) with obvhs's
    /// `medium_build` preset. Triangles must be valid (finite, non-degenerate), as the loader
    /// guarantees; an empty list gives an accelerator that hits nothing.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        Self::build_with(positions, triangles, BvhBuildParams::medium_build())
    }

    /// Builds the BVH with explicit obvhs build parameters. Those of the binary tree apply
    /// (PLOC search distance and depth threshold, sort precision, reinsertion ratio); the leaf
    /// sizes and collapse costs do not (the 8-wide collapse chooses leaves of up to four
    /// triangles by its own costs).
    pub fn build_with(positions: &[Vec3], triangles: &[[u32; 3]], params: BvhBuildParams) -> Self {
        Self::build_laid_out(positions, triangles, params, bvh::HOT_BYTES)
    }

    /// [`Accel::build_with`], the tree's top levels stored first as far as they fit in
    /// `hot_bytes`.
    fn build_laid_out(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        params: BvhBuildParams,
        hot_bytes: usize,
    ) -> Self {
        let start = Instant::now();
        let corners: Vec<[Vec3A; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| Vec3A::from(positions[i as usize])))
            .collect();
        // Each triangle's exact bounds: the node test allows for its own rounding
        // (`FAR_SLACK` of `bvh/node.rs`), so boxes need no padding.
        let boxes: Vec<Aabb> = corners
            .iter()
            .map(|c| Aabb {
                min: c[0].min(c[1]).min(c[2]),
                max: c[0].max(c[1]).max(c[2]),
            })
            .collect();
        let mut quads = Vec::new();
        let bvh = if boxes.is_empty() {
            Bvh8::new(Vec::new(), &[], hot_bytes)
        } else {
            let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
                params.ploc_search_distance,
                &boxes,
                (0..boxes.len() as u32).collect(),
                params.sort_precision,
                params.search_depth_threshold,
            );
            ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
            let nodes = collapse(&bvh2, |leaf| {
                let tris: Vec<[Vec3A; 3]> = leaf.iter().map(|&i| corners[i as usize]).collect();
                quads.push(TriangleQuad::new(&tris, leaf));
                (quads.len() - 1) as u32
            });
            Bvh8::new(nodes, &quads, hot_bytes)
        };
        Self {
            bvh,
            build_time: start.elapsed(),
        }
    }

    /// Wall-clock time the build took, including the BVH-order copy of the triangles.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Number of BVH nodes (8-wide).
    pub fn node_count(&self) -> usize {
        self.bvh.nodes
    }

    /// Number of triangle quads (up to four triangles each; a leaf's, or several leaves' of
    /// one node).
    pub fn quad_count(&self) -> usize {
        self.bvh.quads
    }

    /// Memory of the tree (its nodes and triangle quads), bytes.
    pub fn bytes(&self) -> usize {
        self.bvh.bytes()
    }

    /// The closest hit with `0 < t < t_max`, if any; of hits at the same `t` (a ray through an
    /// edge or vertex that triangles share), the one with the smallest triangle index, as
    /// [`Accel::closest_brute_force`] finds, whatever order the walk meets them in.
    pub fn closest(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<TriangleHit> {
        let sheared = QuadRay::new(&ShearedRay::new(origin, direction));
        let ray = NodeRay::new(origin, direction);
        let mut best = None;
        let mut t_max = t_max;
        self.bvh.walk(
            &ray,
            &mut t_max,
            true,
            #[inline(always)]
            |p, lanes, t_max| {
                self.nearer(&sheared, p as u32, lanes, t_max, &mut best);
                false
            },
        );
        best.map(|b| self.hit(b, t_max))
    }

    /// Tests lanes `lanes` of quad `p` against `ray` (up to [`search_bound`]) and keeps in
    /// `best` (its `t` is `t_max`) the nearer of it and the quad's nearest hit, at equal `t`
    /// the one with the smaller triangle index ([`keep_nearer`]).
    #[inline(always)]
    fn nearer(
        &self,
        ray: &QuadRay,
        p: u32,
        lanes: u32,
        t_max: &mut f32,
        best: &mut Option<Nearest>,
    ) {
        let quad = self.bvh.arena.quad(p);
        let hits = ray.intersect(quad, lanes, search_bound(*t_max, best));
        if hits.mask == 0 {
            return;
        }
        let lane = hits.nearest(&quad.ids);
        let id = quad.ids[lane];
        keep_nearer(best, t_max, hits.t_of(lane), id, || Nearest {
            quad: p,
            lane,
            id,
            barycentric: hits.barycentric(lane),
        });
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

    /// The hit `best` at `t`.
    fn hit(&self, best: Nearest, t: f32) -> TriangleHit {
        let quad = self.bvh.arena.quad(best.quad);
        // The quad's coordinates as plain arrays: `Vec4`'s index by a variable lane is a
        // jump table, an indirect branch per coordinate.
        let v: &[[[f32; 4]; 3]; 3] = bytemuck::cast_ref(&quad.v);
        let lane = best.lane & 3;
        TriangleHit {
            triangle: best.id,
            t,
            barycentric: best.barycentric,
            corners: [0, 1, 2].map(|i| Vec3::new(v[0][i][lane], v[1][i][lane], v[2][i][lane])),
        }
    }

    /// Whether anything is hit with `0 < t < t_max`; stops at the first hit found.
    pub fn any_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        let sheared = QuadRay::new(&ShearedRay::new(origin, direction));
        let ray = NodeRay::new(origin, direction);
        let mut hit = false;
        let mut t_max = t_max;
        self.bvh.walk(
            &ray,
            &mut t_max,
            false,
            #[inline(always)]
            |p, lanes, t_max| {
                hit = sheared
                    .intersect(self.bvh.arena.quad(p as u32), lanes, *t_max)
                    .mask
                    != 0;
                hit
            },
        );
        hit
    }

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
        if self.coherent(rays) {
            self.closest_packets(rays, hits);
        } else if self.bvh.bytes() > INTERLEAVE_MIN_BYTES {
            self.closest_interleaved(rays, hits);
        } else {
            self.closest_each(rays, hits);
        }
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
    fn closest_packets(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
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
    fn coherent(&self, rays: &[Ray]) -> bool {
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
    fn closest_interleaved(&self, rays: &[Ray], hits: &mut [Option<TriangleHit>]) {
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

    /// [`Accel::any_hit`] for many rays: `blocked[i]` for ray `i`, the same answers, walked
    /// as [`Accel::closest_many`] walks its rays (interleaved on large trees unless the rays
    /// are coherent).
    ///
    /// # Panics
    /// When `blocked` and `rays` differ in length.
    pub fn any_hit_many(&self, rays: &[Ray], blocked: &mut [bool]) {
        assert_eq!(rays.len(), blocked.len(), "one answer per ray");
        if self.interleaves(rays) {
            self.any_hit_interleaved(rays, blocked);
        } else {
            for (b, r) in blocked.iter_mut().zip(rays) {
                *b = self.any_hit(r.origin, r.direction, r.t_max);
            }
        }
    }

    /// [`Accel::any_hit_many`]'s interleaved walk, whatever the tree's size.
    fn any_hit_interleaved(&self, rays: &[Ray], blocked: &mut [bool]) {
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

    /// Whether every segment from `apex` to a point of triangle `base` is certainly
    /// unblocked: no scene triangle reaches into the tetrahedron they fill (shaft culling,
    /// Haines & Wallace 1991). `false` means a triangle may block some of them, not that one
    /// does: cast rays then. Triangles in the apex's or the base's plane never block (a
    /// segment meets such a plane only at its end), so the receiver's and the shooter's own
    /// surfaces do not count. With `apex_normal` (the receiver's geometric normal), when all
    /// of `base` is in front of the receiver's plane, nothing behind that plane counts either
    /// (a solid's other faces, seen from one of its faces). Conservative up to
    /// [`SHAFT_TOLERANCE`].
    pub fn shaft_clear(&self, apex: Vec3, apex_normal: Option<Vec3>, base: [Vec3; 3]) -> bool {
        let shaft = Shaft::new(apex, apex_normal, base);
        !self.bvh.any_leaf(
            |node| shaft.overlap(node),
            |p, lanes| shaft.may_block(self.bvh.arena.quad(p as u32), lanes),
        )
    }

    /// Whether every segment between a point of triangle `a` and a point of triangle `b`
    /// (unit geometric normals `na`, `nb`) is certainly unblocked: no scene triangle reaches
    /// into the convex hull of the two (shaft culling between patches). Triangles in the plane
    /// of `a` or `b` do not count when the other lies wholly in front of that plane, nor do
    /// those behind it, as in [`Accel::shaft_clear`]; that test with any point of `a` as the
    /// apex covers a part of this hull, so a pair this test clears needs no per-point test.
    /// `false` when the two triangles lie in one plane (the hull is flat). Conservative up to
    /// [`SHAFT_TOLERANCE`].
    pub fn shaft_clear_between(&self, a: [Vec3; 3], na: Vec3, b: [Vec3; 3], nb: Vec3) -> bool {
        let Some(shaft) = Shaft::hull(a, na, b, nb) else {
            return false;
        };
        !self.bvh.any_leaf(
            |node| shaft.overlap(node),
            |p, lanes| shaft.may_block(self.bvh.arena.quad(p as u32), lanes),
        )
    }

    /// Reference answer by testing every triangle, O(n): the oracle for BVH tests.
    pub fn closest_brute_force(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let sheared = ShearedRay::new(origin, direction);
        let mut best: Option<TriangleHit> = None;
        for (i, t) in triangles.iter().enumerate() {
            let corners = t.map(|k| positions[k as usize]);
            let v = AxisTriangle::new(corners.map(Vec3A::from));
            let limit = best.map_or(t_max, |b| b.t);
            if let Some((t, barycentric)) = sheared.intersect(&v, limit) {
                best = Some(TriangleHit {
                    triangle: i as u32,
                    t,
                    barycentric,
                    corners,
                });
            }
        }
        best
    }
}

/// `t.next_up()` four times over for a positive `t` (a hit's distance; at most infinity): one
/// integer add on its bits, capped at infinity's, the bits of consecutive positive floats
/// being consecutive integers. The general `next_up` steps (with their checks for zero,
/// negative and NaN, which a hit's distance never is) cost more than the add.
#[inline(always)]
fn four_ulps_up(t: f32) -> f32 {
    debug_assert!(t > 0.0, "{t} is not a hit's distance");
    f32::from_bits((t.to_bits() + 4).min(f32::INFINITY.to_bits()))
}

/// The bound a closest-hit walk tests a ray's next triangles with: its `t_max`, and once it
/// has a hit (`best`), a few ulps beyond, so that a triangle at exactly the hit's `t` is not
/// rounded away by the test's early rejection and [`keep_nearer`] decides between them.
#[inline(always)]
fn search_bound(t_max: f32, best: &Option<Nearest>) -> f32 {
    if best.is_some() {
        four_ulps_up(t_max)
    } else {
        t_max
    }
}

/// Keeps a hit of triangle `id` at `t` (`found` forms it) as the ray's nearest hit (`best`,
/// its `t` in `t_max`) when it is nearer, or as near with a smaller triangle index: the
/// answer then does not depend on the order a walk meets triangles in.
#[inline(always)]
fn keep_nearer(
    best: &mut Option<Nearest>,
    t_max: &mut f32,
    t: f32,
    id: u32,
    found: impl FnOnce() -> Nearest,
) {
    if best.is_none_or(|b| t < *t_max || (t == *t_max && id < b.id)) {
        *t_max = t;
        *best = Some(found());
    }
}
