//! Fresnel reflectance: exact unpolarized reflectance of an interface of complex relative index
//! eta = n + i k (conductors and dielectrics alike), the real-index form with transmission and
//! total internal reflection for the smooth dielectric, Snell refraction, and Schlick's
//! approximation.
//!
//! All cosines are measured against the normal of the interface that reflects: the macroscopic
//! normal for delta lobes, the half vector `h` for microfacet lobes. Reflectances are
//! dimensionless, in [0, 1].

use glam::Vec3;

use crate::{ComplexIor, Rgb};

/// Which Fresnel reflectance a Cook-Torrance lobe evaluates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FresnelModel {
    /// Exact unpolarized Fresnel for a complex index, (R_s + R_p) / 2.
    #[default]
    Exact,
    /// Schlick's approximation from the normal-incidence reflectance of the same index.
    Schlick,
}

#[derive(Debug, Clone, Copy)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, s: f64) -> Self {
        Self::new(self.re * s, self.im * s)
    }
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Self) -> Self {
        let d = o.norm2();
        Self::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    /// Principal square root (non-negative real part).
    fn sqrt(self) -> Self {
        let r = self.re.hypot(self.im);
        let re = ((r + self.re) * 0.5).max(0.0).sqrt();
        let im = ((r - self.re) * 0.5).max(0.0).sqrt();
        Self::new(re, if self.im < 0.0 { -im } else { im })
    }
}

/// |a / b|^2, zero when both vanish (the eta = 1 grazing limit, where there is no interface).
fn ratio2(a: C, b: C) -> f64 {
    let d = b.norm2();
    if d == 0.0 {
        0.0
    } else {
        (a.norm2() / d).min(1.0)
    }
}

/// The s- and p-polarized reflectances `(R_s, R_p)` for light arriving from outside (index 1)
/// at `cos_i` (clamped to [0, 1]) on a medium of complex relative index `n + i k` (n > 0, k >= 0).
/// With k = 0 and n < 1 this includes total internal reflection (both equal 1).
pub fn polarized(cos_i: f32, n: f32, k: f32) -> (f32, f32) {
    if n == 1.0 && k == 0.0 {
        return (0.0, 0.0); // the same medium on both sides: no interface
    }
    let c = f64::from(cos_i.clamp(0.0, 1.0));
    let eta = C::new(f64::from(n), f64::from(k));
    let ci = C::new(c, 0.0);
    let sin2_t = C::new(1.0 - c * c, 0.0).div(eta.mul(eta));
    let cos_t = C::new(1.0, 0.0).sub(sin2_t).sqrt();
    let eta_cos_t = eta.mul(cos_t);
    let eta_cos_i = eta.scale(c);
    let rs = ratio2(ci.sub(eta_cos_t), ci.add(eta_cos_t));
    let rp = ratio2(eta_cos_i.sub(cos_t), eta_cos_i.add(cos_t));
    (rs as f32, rp as f32)
}

/// Exact unpolarized reflectance (R_s + R_p) / 2 at `cos_i` for the complex index `n + i k`.
pub fn complex(cos_i: f32, n: f32, k: f32) -> f32 {
    let (rs, rp) = polarized(cos_i, n, k);
    0.5 * (rs + rp)
}

/// [`complex`] per RGB channel of `ior`.
pub fn complex_rgb(cos_i: f32, ior: &ComplexIor) -> Rgb {
    per_channel(ior, |n, k| complex(cos_i, n, k))
}

/// `f(n, k)` for each RGB channel of `ior`.
fn per_channel(ior: &ComplexIor, f: impl Fn(f32, f32) -> f32) -> Rgb {
    Rgb::new(
        f(ior.n.x, ior.k.x),
        f(ior.n.y, ior.k.y),
        f(ior.n.z, ior.k.z),
    )
}

/// Reflectance at normal incidence, ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2): Schlick's F0.
pub fn normal_incidence(n: f32, k: f32) -> f32 {
    let (n, k) = (f64::from(n), f64::from(k));
    (((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)) as f32
}

/// Schlick's approximation F0 + (1 - F0)(1 - cos)^5, `cos` clamped to [0, 1].
pub fn schlick(cos: f32, f0: f32) -> f32 {
    let m = 1.0 - cos.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (1.0 - f0) * m2 * m2 * m
}

/// Schlick's approximation for the index `n + i k`: F0 from [`normal_incidence`]. For a
/// dielectric of index below 1 (light leaving the denser medium) the cosine of the transmitted
/// ray is used, and total internal reflection gives 1, the usual fix without which Schlick
/// misses the critical angle entirely.
pub fn schlick_ior(cos_i: f32, n: f32, k: f32) -> f32 {
    let f0 = normal_incidence(n, k);
    if k == 0.0 && n < 1.0 {
        let c = cos_i.clamp(0.0, 1.0);
        let sin2_t = (1.0 - c * c) / (n * n);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        return schlick((1.0 - sin2_t).sqrt(), f0);
    }
    schlick(cos_i, f0)
}

/// [`schlick_ior`] per RGB channel of `ior`.
pub fn schlick_rgb(cos_i: f32, ior: &ComplexIor) -> Rgb {
    per_channel(ior, |n, k| schlick_ior(cos_i, n, k))
}

/// Unpolarized reflectance of a smooth dielectric interface of real relative index `eta`
/// (inside over outside, > 0). `cos_i` > 0: light arrives from outside; `cos_i` < 0: from inside
/// (the index is inverted). Returns 1 beyond the critical angle (total internal reflection) and
/// 0 for eta = 1 (no interface).
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    let (c, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let c = c.min(1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - sin2_t).sqrt();
    let rp = (eta * c - ct) / (eta * c + ct);
    let rs = (c - eta * ct) / (c + eta * ct);
    (0.5 * (rp * rp + rs * rs)).clamp(0.0, 1.0)
}

/// Snell refraction of the local direction `wi` (pointing away from the surface, on either side)
/// through an interface of relative index `eta` (inside over outside; the inside is -z).
/// Returns the transmitted direction (unit, on the other side) and the ratio eta_t / eta_i it
/// crossed, or `None` under total internal reflection or for a direction in the tangent plane.
pub fn refract(wi: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let (cos_i, eta, nz) = if wi.z > 0.0 {
        (wi.z, eta, 1.0)
    } else if wi.z < 0.0 {
        (-wi.z, 1.0 / eta, -1.0)
    } else {
        return None;
    };
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let wt = -wi / eta + Vec3::new(0.0, 0.0, nz * (cos_i / eta - cos_t));
    Some((wt.normalize(), eta))
}
