//! The local shading frame: +z is the surface normal, x and y span the tangent plane.
//!
//! Every model of this crate works on unit directions expressed in this frame, both pointing
//! away from the surface: `wo` towards the viewer, `wi` towards the light. `cos theta` is
//! simply the z component.

use glam::Vec3;

/// Smallest cosine used in a denominator (dimensionless). Models that divide by `cos theta`
/// (published Phong, Cook-Torrance) use `max(cos, COS_FLOOR)` so that the value stays finite for
/// subnormal cosines; this can only lower `f cos`, and only for directions less than 1e-12 rad
/// above the horizon.
pub const COS_FLOOR: f32 = 1e-12;

/// An orthonormal frame whose `n` axis is the surface normal (world space to local and back).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// First tangent (local +x), unit length.
    pub s: Vec3,
    /// Second tangent (local +y), unit length.
    pub t: Vec3,
    /// Normal (local +z), unit length.
    pub n: Vec3,
}

impl Frame {
    /// A right-handed frame around the unit normal `n` (Duff et al. 2017, branchless).
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = n.any_orthonormal_pair();
        Self { s, t, n }
    }

    /// World direction `v` in local coordinates.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local direction `v` in world coordinates.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// cos theta of a local unit direction (its z component).
#[inline]
pub fn cos_theta(w: Vec3) -> f32 {
    w.z
}

/// sin^2 theta of a local unit direction, from the tangent components (accurate near the pole).
#[inline]
pub fn sin2_theta(w: Vec3) -> f32 {
    (w.x * w.x + w.y * w.y).min(1.0)
}

/// tan^2 theta of a local unit direction (infinite on the horizon).
#[inline]
pub fn tan2_theta(w: Vec3) -> f32 {
    sin2_theta(w) / (w.z * w.z)
}

/// Mirror reflection of `w` about the normal: (-x, -y, z).
#[inline]
pub fn reflect(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// Mirror reflection of `w` about the unit vector `h`: 2 (w.h) h - w.
#[inline]
pub fn reflect_about(w: Vec3, h: Vec3) -> Vec3 {
    2.0 * w.dot(h) * h - w
}

/// Whether `a` and `b` lie strictly on the same side of the tangent plane.
#[inline]
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// The unit direction of polar angle theta (given by its sine and cosine) and azimuth `phi` (rad).
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (sp, cp) = phi.sin_cos();
    Vec3::new(sin_theta * cp, sin_theta * sp, cos_theta)
}

/// The azimuth of `w` as a fraction of a turn, in [0, 1]: the inverse of the `phi = 2 pi u`
/// of [`spherical_direction`] that the warps use.
#[inline]
pub(crate) fn azimuth01(w: Vec3) -> f32 {
    let phi = w.y.atan2(w.x);
    let u = phi / std::f32::consts::TAU;
    if u < 0.0 { u + 1.0 } else { u.min(1.0) }
}

/// wo.h computed symmetrically in wo and wi (they are equal for the half vector `h`), so a
/// model that uses it stays exactly reciprocal.
#[inline]
pub(crate) fn symmetric_dot(wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
    0.5 * (wo.dot(h) + wi.dot(h))
}

/// Whether a BRDF is defined for the pair: both directions strictly above the surface.
#[inline]
pub(crate) fn both_above(wo: Vec3, wi: Vec3) -> bool {
    wo.z > 0.0 && wi.z > 0.0
}

/// `max(c, 0)^n` for c a cosine and n >= 0, zero for c <= 0 whatever n (also for n = 0), in [0, 1].
#[inline]
pub(crate) fn pow_lobe(c: f32, n: f32) -> f32 {
    if c > 0.0 { c.min(1.0).powf(n) } else { 0.0 }
}

/// The half vector of `wo` and `wi` (unit), or `None` when they are opposite.
#[inline]
pub(crate) fn half_vector(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    (wo + wi).try_normalize()
}

/// `wo` reflected about a sampled half vector `h`, or `None` when `h` faces away from `wo`:
/// how a half-vector (microfacet) lobe turns its sample into a direction.
#[inline]
pub(crate) fn reflect_about_half(wo: Vec3, h: Vec3) -> Option<Vec3> {
    (wo.dot(h) > 0.0).then(|| reflect_about(wo, h))
}

/// Density of `wi` for a lobe that draws the half vector `h` with density `pdf_h(h)` and
/// reflects `wo` about it: `pdf_h(h) / (4 wo.h)` (the reflection's Jacobian), 0 where the
/// half vector is undefined or faces away.
#[inline]
pub(crate) fn reflected_pdf(wo: Vec3, wi: Vec3, pdf_h: impl FnOnce(Vec3) -> f32) -> f32 {
    let Some(h) = half_vector(wo, wi) else {
        return 0.0;
    };
    let oh = symmetric_dot(wo, wi, h);
    if oh <= 0.0 {
        return 0.0;
    }
    pdf_h(h) / (4.0 * oh.max(COS_FLOOR))
}

/// `cos^n` given `d = 1 - cos` (d in [0, 2]): zero for d >= 1 (cos <= 0), else
/// exp(n ln(1 - d)). Working from `1 - cos`, computed without cancellation by the callers,
/// keeps exponents up to 1e6 accurate where cos itself rounds to 1 in f32.
#[inline]
pub(crate) fn pow_one_minus(d: f32, n: f32) -> f32 {
    if d.is_nan() || d >= 1.0 {
        return 0.0;
    }
    if d <= 0.0 {
        return 1.0;
    }
    (n * (-d).ln_1p()).exp().min(1.0)
}

/// sin^2 of the angle between the normal and the half vector of `wo` and `wi`, from their
/// unnormalized sum (accurate near the normal), or `None` when the sum is not above the surface.
#[inline]
pub(crate) fn half_sin2(wo: Vec3, wi: Vec3) -> Option<f32> {
    let s = wo + wi;
    let t2 = s.x * s.x + s.y * s.y;
    let l2 = t2 + s.z * s.z;
    (s.z > 0.0 && l2 > 0.0).then(|| (t2 / l2).min(1.0))
}
