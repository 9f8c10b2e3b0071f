//! The ambient term of a partial solve (Cohen, Chen, Wallace & Greenberg 1988), one formula
//! for both solvers.

use glam::DVec3;

/// The ambient term, W/m^2: `power` not yet passed on (W per channel) spread over the scene's
/// `area` and multiplied by the interreflection factor 1 / (1 - mean reflectance), where
/// `reflectance_area` is the area-weighted sum of the surfaces' reflectances (so the mean
/// reflectance is `reflectance_area / area`).
pub(crate) fn ambient(power: DVec3, reflectance_area: DVec3, area: f64) -> DVec3 {
    let mean_rho = reflectance_area / area;
    power / area / (DVec3::ONE - mean_rho).max(DVec3::splat(1e-6))
}
