//! V-cavity masking and shadowing (Torrance & Sparrow 1967, Cook & Torrance 1981):
//! G = min(1, 2 (N.H)(N.V) / (V.H), 2 (N.H)(N.L) / (V.H)), in [0, 1] (dimensionless).

use glam::Vec3;

use crate::frame::COS_FLOOR;

/// G(wo, wi, h) for local unit directions `wo` = V, `wi` = L and their half vector `h`.
/// V.H (= L.H) is taken as the mean of the two dot products so that G is exactly symmetric.
/// Zero when any cosine is not positive.
pub fn g(wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
    let vh = 0.5 * (wo.dot(h) + wi.dot(h));
    if wo.z <= 0.0 || wi.z <= 0.0 || h.z <= 0.0 || vh <= 0.0 {
        return 0.0;
    }
    let k = 2.0 * h.z / vh.max(COS_FLOOR);
    (k * wo.z).min(k * wi.z).clamp(0.0, 1.0)
}
