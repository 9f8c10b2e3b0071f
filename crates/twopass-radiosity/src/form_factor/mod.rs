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
