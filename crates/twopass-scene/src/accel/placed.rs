//! Copies of stored objects placed by a transform ([`Repeat`](crate::Repeat), a glTF mesh
//! several nodes show): one tree per source, which all its copies share, and a binary tree
//! (obvhs) over the copies' world bounds. A ray is carried into a copy's source space, where
//! `t` is unchanged (the direction is transformed, not renormalised), and its hit back out.

use std::time::Instant;

use glam::{Affine3A, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::ray::{Ray as TopRay, RayHit};

use super::binary::build_coincident;
use super::build::{Accel, Copy, Placed};
use super::hit::{TriangleHit, four_ulps_up};
use super::ray::gamma;

/// One placed copy of a run of stored triangles, as the accelerator needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// The first of the stored triangles it copies.
    pub source: u32,
    /// How many it copies.
    pub count: u32,
    /// Index of the copy's first triangle in the whole mesh (hits name `first` + the source
    /// triangle's place in the run).
    pub first: u32,
    /// From the source's world place to the copy's.
    pub to_world: Affine3A,
    /// Its inverse.
    pub from_world: Affine3A,
    /// Whether `to_world` mirrors (the copy's corners 1 and 2 are the source's 2 and 1).
    pub flips: bool,
}

/// A bound on the rounding a point at `position` (world) of a copy placed by `to_world`
/// (inverse `from_world`) picks up through a ray query's two transforms (into the source's
/// space and its hit back out), per axis, scene units.
pub fn transform_error(to_world: &Affine3A, from_world: &Affine3A, position: Vec3) -> Vec3 {
    let abs =
        |m: glam::Mat3A| glam::Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
    let (a, inv) = (abs(to_world.matrix3), abs(from_world.matrix3));
    let p = Vec3A::from(position).abs();
    // The source point's size, then: the forward transform's rounding (a |x| + |b|), the
    // world point's own, and a spawned origin's trip back into the source (a times its
    // rounding there), each within a few ulps of its terms.
    let local = inv * p + from_world.translation.abs();
    let e = 2.0 * (a * local) + to_world.translation.abs() + p;
    Vec3::from(e * gamma(8))
}

impl Accel {
    /// Builds the BVH over stored triangles and placed copies of runs of them (instancing): one
    /// tree over the stored triangles, one per copied run, shared by its copies, and a tree
    /// over the copies. Hits name the stored triangles by their index and a copy's by
    /// [`Placement::first`] plus its place in the run.
    pub fn build_placed(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        placements: &[Placement],
    ) -> Self {
        let start = Instant::now();
        let mut accel = Self::build(positions, triangles);
        accel.placed = Placed::build(positions, triangles, placements);
        accel.build_time = start.elapsed();
        accel
    }
}

impl Copy {
    /// `(origin, direction)` in the source's space.
    #[inline]
    fn carry(&self, origin: Vec3, direction: Vec3) -> (Vec3, Vec3) {
        (
            self.from_world.transform_point3(origin),
            self.from_world.transform_vector3(direction),
        )
    }

    /// A hit on the source's tree as a hit of this copy.
    #[inline]
    fn hit(&self, h: TriangleHit) -> TriangleHit {
        let mut corners = h.corners.map(|p| self.to_world.transform_point3(p));
        let mut barycentric = h.barycentric;
        if self.flips {
            corners.swap(1, 2);
            barycentric.swap(1, 2);
        }
        TriangleHit {
            triangle: self.first + h.triangle,
            t: h.t,
            barycentric,
            corners,
        }
    }
}

impl Placed {
    /// The trees and the top tree of the copies `placements` of runs of `triangles` (vertex
    /// indices into `positions`); `None` without copies.
    pub(super) fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        placements: &[Placement],
    ) -> Option<Box<Self>> {
        let repeats = placements;
        if repeats.is_empty() {
            return None;
        }
        let mut sources: Vec<(u32, u32)> = Vec::new();
        let mut trees = Vec::new();
        let mut copies = Vec::with_capacity(repeats.len());
        let mut boxes = Vec::with_capacity(repeats.len());
        for r in repeats {
            let len = r.count;
            let key = (r.source, len);
            let tree = match sources.iter().position(|&s| s == key) {
                Some(i) => i,
                None => {
                    let run = &triangles[r.source as usize..(r.source + len) as usize];
                    trees.push(Accel::build(positions, run));
                    sources.push(key);
                    trees.len() - 1
                }
            };
            // The world box of the source's corners moved by the copy, widened by the
            // transforms' rounding (the hits are found in the source's space).
            let mut b = Aabb::empty();
            for t in r.source..r.source + len {
                for &v in &triangles[t as usize] {
                    b.extend(Vec3A::from(
                        r.to_world.transform_point3(positions[v as usize]),
                    ));
                }
            }
            let pad = transform_error(
                &r.to_world,
                &r.from_world,
                Vec3::from(b.min.abs().max(b.max.abs())),
            );
            boxes.push(Aabb {
                min: b.min - Vec3A::from(pad),
                max: b.max + Vec3A::from(pad),
            });
            copies.push(Copy {
                tree: tree as u32,
                first: r.first,
                from_world: r.from_world,
                to_world: r.to_world,
                flips: r.flips,
            });
        }
        // Copies in one place are refused at load, but boxes may still coincide (copies of
        // different sources): built as `Accel`'s trees are.
        let top = build_coincident(&boxes, |boxes| {
            PlocBuilder::with_capacity(boxes.len()).build(
                PlocSearchDistance::Minimum,
                boxes,
                (0..boxes.len() as u32).collect(),
                SortPrecision::U64,
                1,
            )
        });
        Some(Box::new(Self { trees, copies, top }))
    }

    fn copy(&self, slot: usize) -> &Copy {
        &self.copies[self.top.primitive_indices[slot] as usize]
    }

    /// The nearer of `best` and the copies' closest hit with `0 < t < t_max`; at
    /// equal `t`, the smaller triangle index (as [`Accel::closest`]). Never inlined: the
    /// stored triangles' walk stays as lean as in a scene without copies.
    #[cold]
    #[inline(never)]
    pub(super) fn closest(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        mut best: Option<TriangleHit>,
    ) -> Option<TriangleHit> {
        let bound = |best: &Option<TriangleHit>| best.map_or(t_max, |b| four_ulps_up(b.t));
        let ray = TopRay::new(origin.into(), direction.into(), 0.0, bound(&best));
        let mut top_hit = RayHit::none();
        self.top.ray_traverse(ray, &mut top_hit, |_, slot| {
            let copy = self.copy(slot);
            let (o, d) = copy.carry(origin, direction);
            let tree = &self.trees[copy.tree as usize];
            let Some(h) = tree.closest(o, d, bound(&best)) else {
                return f32::INFINITY;
            };
            let h = copy.hit(h);
            if best.is_none_or(|b| h.t < b.t || (h.t == b.t && h.triangle < b.triangle)) {
                best = Some(h);
                h.t
            } else {
                f32::INFINITY
            }
        });
        best
    }

    /// Whether a copy is hit with `0 < t < t_max` (never inlined, as [`Placed::closest`]).
    #[cold]
    #[inline(never)]
    pub(super) fn any_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        let ray = TopRay::new(origin.into(), direction.into(), 0.0, t_max);
        !self.top.ray_traverse_miss(ray, |_, slot| {
            let copy = self.copy(slot);
            let (o, d) = copy.carry(origin, direction);
            if self.trees[copy.tree as usize].any_hit(o, d, t_max) {
                0.0
            } else {
                f32::INFINITY
            }
        })
    }

    /// Whether no copy may reach into the convex hull of `points` (world): `clear` answers for
    /// one copy's tree, given the points moved into its source's space and the transform
    /// that moved them.
    pub(super) fn all_clear(
        &self,
        points: &[Vec3],
        mut clear: impl FnMut(&Accel, &Affine3A) -> bool,
    ) -> bool {
        let mut b = Aabb::empty();
        for &p in points {
            b.extend(Vec3A::from(p));
        }
        let mut all = true;
        self.top.aabb_traverse(b, |bvh, node| {
            let n = &bvh.nodes[node as usize];
            for slot in n.first_index..n.first_index + n.prim_count {
                let copy = self.copy(slot as usize);
                if !clear(&self.trees[copy.tree as usize], &copy.from_world) {
                    all = false;
                    return false;
                }
            }
            true
        });
        all
    }

    /// Nodes and quads of the shared trees, and bytes including the top tree.
    pub(super) fn sizes(&self) -> (usize, usize, usize) {
        self.trees.iter().fold(
            (
                0,
                0,
                std::mem::size_of_val(self.top.nodes.as_slice())
                    + std::mem::size_of_val(self.top.primitive_indices.as_slice())
                    + std::mem::size_of_val(self.copies.as_slice()),
            ),
            |(n, q, b), t| (n + t.node_count(), q + t.quad_count(), b + t.bytes()),
        )
    }
}
