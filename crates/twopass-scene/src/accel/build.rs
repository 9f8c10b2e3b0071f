//! The accelerator and its build: obvhs's PLOC binary tree over the triangles' boxes (copies
//! of one box built as one, see [`build_coincident`]), collapsed into 8-wide nodes with triangle-quad leaves and laid out for the walks.

use std::time::{Duration, Instant};

use glam::{Affine3A, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    bvh2::{Bvh2, reinsertion::ReinsertionOptimizer},
    ploc::PlocBuilder,
};

use super::binary::build_coincident;
use super::bvh::{self, Bvh8};
use super::collapse::collapse;
use super::quad::TriangleQuad;

/// An 8-wide BVH over the scene's triangles (a binary tree built by obvhs's PLOC builder,
/// collapsed into 8-wide nodes with leaves of up to four triangles) with the queries every
/// pass uses.
pub struct Accel {
    /// The tree: its nodes, and one quad per leaf (the leaf's triangles, at most four, in its
    /// first lanes) right after the node that leads to it.
    pub(super) bvh: Bvh8,
    /// The placed copies of stored objects, with their own trees; `None` without copies.
    pub(super) placed: Option<Box<Placed>>,
    pub(super) build_time: Duration,
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
    pub(super) fn build_laid_out(
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
            let bvh2 = build_coincident(&boxes, |boxes| {
                let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
                    params.ploc_search_distance,
                    boxes,
                    (0..boxes.len() as u32).collect(),
                    params.sort_precision,
                    params.search_depth_threshold,
                );
                ReinsertionOptimizer::default().run(
                    &mut bvh2,
                    params.reinsertion_batch_ratio,
                    None,
                );
                bvh2
            });
            let nodes = collapse(&bvh2, |leaf| {
                let tris: Vec<[Vec3A; 3]> = leaf.iter().map(|&i| corners[i as usize]).collect();
                quads.push(TriangleQuad::new(&tris, leaf));
                (quads.len() - 1) as u32
            });
            Bvh8::new(nodes, &quads, hot_bytes)
        };
        Self {
            bvh,
            placed: None,
            build_time: start.elapsed(),
        }
    }

    /// Wall-clock time the build took, including the BVH-order copy of the triangles.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Number of BVH nodes (8-wide), the copies' shared trees included.
    pub fn node_count(&self) -> usize {
        self.bvh.nodes + self.placed.as_ref().map_or(0, |p| p.sizes().0)
    }

    /// Number of triangle quads (up to four triangles each; a leaf's, or several leaves' of
    /// one node), the copies' shared trees included.
    pub fn quad_count(&self) -> usize {
        self.bvh.quads + self.placed.as_ref().map_or(0, |p| p.sizes().1)
    }

    /// Memory of the trees (nodes and triangle quads; the copies' shared trees and the tree
    /// over them), bytes.
    pub fn bytes(&self) -> usize {
        self.bvh.bytes() + self.placed.as_ref().map_or(0, |p| p.sizes().2)
    }
}

/// The placed copies of a mesh: the shared trees and the tree over the copies.
pub(super) struct Placed {
    /// One tree per source run of stored triangles, over the source's triangles (ids from 0).
    pub(super) trees: Vec<Accel>,
    pub(super) copies: Vec<Copy>,
    /// The tree over the copies' bounds; its leaves' slots index `copies` through
    /// `primitive_indices`.
    pub(super) top: Bvh2,
}

/// One copy: its source's tree and how to reach it.
pub(super) struct Copy {
    pub(super) tree: u32,
    /// Mesh-wide index of the copy's first triangle.
    pub(super) first: u32,
    pub(super) from_world: Affine3A,
    pub(super) to_world: Affine3A,
    pub(super) flips: bool,
}
