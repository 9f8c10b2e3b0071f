//! Form factors from a receiving point to a shooting polygon: the exact differential-area-to-
//! polygon form factor (Lambert's contour integral over the polygon's edges) for the
//! unoccluded part, times the visible fraction measured with stratified shadow rays.
//!
//! The exact point-to-polygon form factor ([`point_to_polygon`], [`SourceTriangle`]) and the
//! shadow rays and shaft culling ([`visibility()`], [`shaft_clear`], [`patches_clear`]) live in
//! a file each.

mod polygon;
mod visibility;

pub(crate) use polygon::RECEIVER_INSET;
pub use polygon::{SourceTriangle, point_to_polygon};
pub use visibility::{Shooter, VisibilityRays, patches_clear, shaft_clear, visibility};

/// Where element-mesh vertex `vertex` receives, form factors, lamps and shadow rays alike: a
/// hair inside its own scene triangle ([`RECEIVER_INSET`] of the way to its centroid), scene
/// units. A vertex on a junction lies in the plane of the surface it meets, which it would see
/// edge-on (F = 0), and half of its shadow rays would start a rounding error behind that
/// surface and find it blocking; from inside its own surface it gets the limits both converge
/// to.
pub(crate) fn receiving_point(
    scene: &twopass_scene::Scene,
    vertex: &crate::element::Vertex,
) -> glam::DVec3 {
    let centroid = scene
        .mesh
        .corners(vertex.triangle)
        .iter()
        .map(|c| c.as_dvec3())
        .sum::<glam::DVec3>()
        / 3.0;
    let p = vertex.position.as_dvec3();
    p + (centroid - p) * RECEIVER_INSET
}
