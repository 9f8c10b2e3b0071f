//! Ray queries over an 8-wide BVH: closest hit and any hit (occlusion), with a watertight
//! ray-triangle test (Woop, Benthin & Wald 2013, as in pbrt-v4) and conservative error bounds,
//! so rays through shared edges and vertices never slip between triangles and spawned rays can
//! be offset safely (see [`SurfacePoint::spawn_origin`]).
//!
//! One job per module. The API: [`build`] (the accelerator and its build), [`query`] (closest
//! hit, any hit, shaft culling, the brute-force oracle), [`many`] (the many-ray calls), [`hit`]
//! (what a closest-hit query keeps and answers). Below it: [`ray`] (rays, surface points,
//! origin offsetting), [`triangle`] (the watertight test), [`quad`] (triangle quads: four
//! triangles per test), [`collapse`](mod@collapse) (the 8-wide tree from obvhs's binary one),
//! [`bvh`] (the 8-wide tree: its nodes, the node test, its layout and the walks), [`arena`]
//! (the tree's memory in 32-byte blocks, in huge pages), [`binary`] (binary trees over
//! coincident boxes), [`placed`] (the trees of instanced copies), [`prefetch`](mod@prefetch),
//! [`shaft`] (shaft culling).

mod arena;
mod binary;
mod build;
mod bvh;
mod collapse;
mod hit;
mod many;
mod placed;
mod prefetch;
mod quad;
mod query;
mod ray;
mod shaft;
#[cfg(test)]
mod tests;
mod triangle;

pub use binary::build_coincident;
pub use build::Accel;
pub use hit::TriangleHit;
pub use many::{COHERENT_ANGLE, COHERENT_ORIGINS, INTERLEAVE_MIN_BYTES};
pub use placed::{Placement, transform_error};
pub(crate) use ray::SHADOW_EPSILON;
pub use ray::{Ray, SurfacePoint};
pub use shaft::SHAFT_TOLERANCE;
pub(crate) use triangle::triangle_normal;
