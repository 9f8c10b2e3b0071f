//! The gather at a fixed number of rays per point, for outputs of many points each averaged
//! over an area.

use twopass_scene::{RadianceEstimate, RadianceEstimator};

use super::Gatherer;

/// A [`Gatherer`] that casts the same number of gather rays at every point
/// ([`Gatherer::fixed`]): the same shadow rays, seeds and deadline, the same solution and
/// caustic photons.
#[derive(Debug, Clone, Copy)]
pub struct Fixed<'g, 'a> {
    gatherer: &'g Gatherer<'a>,
    rays: u32,
}

impl Fixed<'_, '_> {
    /// Gather rays per point.
    pub fn rays(&self) -> u32 {
        self.rays
    }
}

impl RadianceEstimator for Fixed<'_, '_> {
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate {
        self.gatherer
            .estimate_with(triangle, barycentric, key, self.rays, self.rays)
    }
}

impl<'a> Gatherer<'a> {
    /// The same gather with `rays` gather rays at every point (at least 1, at most the
    /// gather's own [`GatherSettings::max_rays`](super::GatherSettings::max_rays)), never
    /// fewer where a point's first rays agree: for outputs whose points are many and averaged
    /// over an area, such as the six points of each element of an element mesh, where a few
    /// rays per point average out and stopping early would bias (the rays that missed a small
    /// bright patch agree on darkness).
    pub fn fixed(&self, rays: u32) -> Fixed<'_, 'a> {
        Fixed {
            gatherer: self,
            rays: rays.clamp(1, self.settings.max_rays),
        }
    }
}
