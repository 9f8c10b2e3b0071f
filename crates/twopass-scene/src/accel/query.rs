//! The one-ray queries: closest hit, any hit, shaft culling, and the brute-force oracle.

use glam::{Vec3, Vec3A};

use super::build::Accel;
use super::bvh::NodeRay;
use super::hit::{Nearest, TriangleHit, keep_nearer, search_bound};
use super::quad::QuadRay;
use super::shaft::Shaft;
use super::triangle::{AxisTriangle, ShearedRay};

impl Accel {
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
        let best = best.map(|b| self.hit(b, t_max));
        match &self.placed {
            None => best,
            Some(placed) => placed.closest(origin, direction, t_max, best),
        }
    }

    /// Tests lanes `lanes` of quad `p` against `ray` (up to [`search_bound`]) and keeps in
    /// `best` (its `t` is `t_max`) the nearer of it and the quad's nearest hit, at equal `t`
    /// the one with the smaller triangle index ([`keep_nearer`]).
    #[inline(always)]
    pub(super) fn nearer(
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

    /// The hit `best` at `t`.
    #[inline(always)]
    pub(super) fn hit(&self, best: Nearest, t: f32) -> TriangleHit {
        let quad = self.bvh.arena.quad(best.quad);
        // The quad's coordinates as plain arrays: `Vec4`'s index by a variable lane is a
        // jump table, an indirect branch per coordinate.
        let v: &[[[f32; 4]; 3]; 3] = bytemuck::cast_ref(&quad.v);
        let lane = best.lane & 3;
        TriangleHit {
            triangle: best.id,
            t,
            barycentric: best.barycentric,
            corners: [
                Vec3::new(v[0][0][lane], v[1][0][lane], v[2][0][lane]),
                Vec3::new(v[0][1][lane], v[1][1][lane], v[2][1][lane]),
                Vec3::new(v[0][2][lane], v[1][2][lane], v[2][2][lane]),
            ],
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
        hit || self
            .placed
            .as_ref()
            .is_some_and(|p| p.any_hit(origin, direction, t_max))
    }

    /// Whether every segment from `apex` to a point of triangle `base` is certainly
    /// unblocked: no scene triangle reaches into the tetrahedron they fill (shaft culling,
    /// Haines & Wallace 1991). `false` means a triangle may block some of them, not that one
    /// does: cast rays then. Triangles in the apex's or the base's plane never block (a
    /// segment meets such a plane only at its end), so the receiver's and the shooter's own
    /// surfaces do not count. With `apex_normal` (the receiver's geometric normal), when all
    /// of `base` is in front of the receiver's plane, nothing behind that plane counts either
    /// (a solid's other faces, seen from one of its faces). Conservative up to
    /// [`SHAFT_TOLERANCE`](super::shaft::SHAFT_TOLERANCE).
    pub fn shaft_clear(&self, apex: Vec3, apex_normal: Option<Vec3>, base: [Vec3; 3]) -> bool {
        let shaft = Shaft::new(apex, apex_normal, base);
        !self.bvh.any_leaf(
            |node| shaft.overlap(node),
            |p, lanes| shaft.may_block(self.bvh.arena.quad(p as u32), lanes),
        ) && self.placed.as_ref().is_none_or(|p| {
            p.all_clear(&[apex, base[0], base[1], base[2]], |tree, m| {
                tree.shaft_clear(
                    m.transform_point3(apex),
                    apex_normal.map(|n| plane_normal(m, n)),
                    base.map(|q| m.transform_point3(q)),
                )
            })
        })
    }

    /// Whether every segment between a point of triangle `a` and a point of triangle `b`
    /// (unit geometric normals `na`, `nb`) is certainly unblocked: no scene triangle reaches
    /// into the convex hull of the two (shaft culling between patches). Triangles in the plane
    /// of `a` or `b` do not count when the other lies wholly in front of that plane, nor do
    /// those behind it, as in [`Accel::shaft_clear`]; that test with any point of `a` as the
    /// apex covers a part of this hull, so a pair this test clears needs no per-point test.
    /// `false` when the two triangles lie in one plane (the hull is flat). Conservative up to
    /// [`SHAFT_TOLERANCE`](super::shaft::SHAFT_TOLERANCE).
    pub fn shaft_clear_between(&self, a: [Vec3; 3], na: Vec3, b: [Vec3; 3], nb: Vec3) -> bool {
        let Some(shaft) = Shaft::hull(a, na, b, nb) else {
            return false;
        };
        !self.bvh.any_leaf(
            |node| shaft.overlap(node),
            |p, lanes| shaft.may_block(self.bvh.arena.quad(p as u32), lanes),
        ) && self.placed.as_ref().is_none_or(|p| {
            p.all_clear(&[a[0], a[1], a[2], b[0], b[1], b[2]], |tree, m| {
                tree.shaft_clear_between(
                    a.map(|q| m.transform_point3(q)),
                    plane_normal(m, na),
                    b.map(|q| m.transform_point3(q)),
                    plane_normal(m, nb),
                )
            })
        })
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

/// A plane's unit normal `n` after the affine map `m` (the inverse transpose of its linear
/// part), so that points in front of the plane stay in front of its image.
fn plane_normal(m: &glam::Affine3A, n: Vec3) -> Vec3 {
    (m.matrix3.inverse().transpose() * Vec3A::from(n))
        .normalize_or_zero()
        .into()
}
