//! The sky: light from infinitely far away in every direction a ray escapes the scene by, from
//! a `[sky]` table. A uniform environment (the same radiance from the whole sphere), or a clear
//! daylight sky (Preetham et al. 1999, the `preetham` module) over the upper hemisphere with a sun of
//! finite angular size (a disc of uniform radiance). Optional portals ([`Portal`]: the
//! windows through which an interior sees the sky) make sampling aim at them.
//!
//! Units: radiance in W/(m^2 sr) per channel (scene units squared, as the emitters'); the
//! daylight model's luminance (cd/m^2) is divided by [`LUMINOUS_EFFICACY`] (683 lm/W, as the
//! lamps' photometric values) and multiplied by the table's `scale`. Directions are unit
//! vectors in world space; "up" is the sky's [`Sky::up`] (the scene's +y unless the table
//! says otherwise).
//!
//! Sampling ([`Sky::sample_sun`], [`Sky::sample_dome`]): the sun uniformly over its cone, the
//! rest by the cosine about the receiving normal, mixed with points on the portals when there
//! are any. Both densities are exposed for multiple importance sampling against BRDF sampling.

pub(crate) mod irradiance;
pub(crate) mod preetham;

use std::f64::consts::{PI, TAU};

use glam::{DVec3, Vec2, Vec3};
use twopass_brdf::Rgb;
use twopass_brdf::frame::Frame;
use twopass_brdf::sample::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};

use crate::lamp::LUMINOUS_EFFICACY;
use preetham::{Preetham, SUN_ILLUMINANCE_OUTSIDE, rgb_of_yxy, sun_transmittance};

/// The sun's angular diameter when the table gives none, degrees (the real sun's mean).
pub const SUN_DIAMETER_DEGREES: f32 = 0.53;

/// The turbidities the daylight model is fitted for (Preetham et al. 1999): T in [2, 10].
pub const TURBIDITY_RANGE: [f32; 2] = [2.0, 10.0];

/// Share of the dome's samples aimed through the portals when the sky has any; the rest are
/// cosine-distributed about the normal, so a point that sees the sky other than through a
/// portal (outdoors, or a portal the scene forgot) still gets all of its light (one-sample
/// mixture, Veach 1997: the density is the mixture's).
pub const PORTAL_SHARE: f32 = 0.5;

/// A window through which the sky lights an interior: a parallelogram (scene units), not
/// geometry (rays pass through it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Portal {
    /// One corner.
    pub origin: Vec3,
    /// First edge from `origin`.
    pub edge_u: Vec3,
    /// Second edge from `origin`.
    pub edge_v: Vec3,
}

impl Portal {
    /// Area, scene units squared.
    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }

    /// Distance along the ray from `x` in unit direction `dir` to the portal, and the cosine
    /// between `dir` and its normal (absolute), if the ray crosses it.
    fn crossing(&self, x: Vec3, dir: Vec3) -> Option<(f32, f32)> {
        let n = self.edge_u.cross(self.edge_v);
        let n2 = n.length_squared();
        let denom = dir.dot(n);
        if denom == 0.0 || n2 <= 0.0 {
            return None;
        }
        let t = (self.origin - x).dot(n) / denom;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let d = x + dir * t - self.origin;
        let a = d.cross(self.edge_v).dot(n) / n2;
        let b = self.edge_u.cross(d).dot(n) / n2;
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then(|| (t, denom.abs() / n2.sqrt()))
    }
}

/// The sun of a daylight sky above the horizon: a disc of uniform radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit direction toward the sun's centre.
    pub direction: Vec3,
    /// 1 - cos of the disc's half angle (kept apart: cos is within f32 rounding of 1).
    pub one_minus_cos: f32,
    /// sin^2 of the disc's half angle.
    pub sin2_half: f32,
    /// Radiance of the disc, W/(m^2 sr) per channel.
    pub radiance: Rgb,
}

impl Sun {
    /// The disc's solid angle, sr: 2 pi (1 - cos half angle).
    pub fn solid_angle(&self) -> f32 {
        std::f32::consts::TAU * self.one_minus_cos
    }

    /// Whether unit direction `dir` lies inside the disc (by the sine of its angle to the
    /// centre, exact for the tiny angles where the cosine rounds to 1).
    fn contains(&self, dir: Vec3) -> bool {
        dir.dot(self.direction) > 0.0
            && dir.cross(self.direction).length_squared() <= self.sin2_half
    }
}

/// What the sky is.
#[derive(Debug, Clone, PartialEq)]
pub enum SkyKind {
    /// The same radiance from every direction of the sphere.
    Uniform {
        /// Radiance, W/(m^2 sr) per channel (scale applied).
        radiance: Rgb,
    },
    /// Preetham et al.'s clear sky over the upper hemisphere (black below the horizon: the
    /// ground is the scene's), with a sun.
    Daylight(Daylight),
}

/// A clear daylight sky's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Daylight {
    /// Atmospheric turbidity T (dimensionless, in [`TURBIDITY_RANGE`]).
    pub turbidity: f32,
    /// Unit direction toward the sun's centre (may be below the horizon: then the sun gives
    /// no light and the dome is the model's for a sun on the horizon, where its fits end).
    pub sun_direction: Vec3,
    /// The sun's angular diameter, radians.
    pub sun_diameter: f32,
    /// Factor on every radiance (dimensionless): sets the units.
    pub scale: f32,
    model: Preetham,
}

/// A scene's sky.
#[derive(Debug, Clone, PartialEq)]
pub struct Sky {
    /// What it is.
    pub kind: SkyKind,
    /// Unit "up": the zenith of the daylight model (unused by a uniform sky).
    pub up: Vec3,
    /// The sun, when the sky has one above the horizon.
    pub sun: Option<Sun>,
    /// The windows the dome's samples aim through (none: the whole hemisphere).
    pub portals: Vec<Portal>,
    /// Integral of the dome's radiance (the sun left out) over the sphere, W/m^2 per channel.
    dome_integral: Rgb,
    /// The sky's irradiance on a surface facing up, by the dome and by the sun, W/m^2
    /// (luminance): they set how often each is sampled.
    up_irradiance: [f32; 2],
}

impl Sky {
    /// A uniform sky of radiance `radiance` (W/(m^2 sr) per channel) over the whole sphere.
    pub fn uniform(radiance: Rgb, portals: Vec<Portal>) -> Self {
        let dome_integral = radiance * (4.0 * std::f32::consts::PI);
        Self {
            kind: SkyKind::Uniform { radiance },
            up: Vec3::Y,
            sun: None,
            portals,
            dome_integral,
            up_irradiance: [
                twopass_brdf::colour::luminance(radiance) * std::f32::consts::PI,
                0.0,
            ],
        }
    }

    /// A daylight sky: turbidity `turbidity` (in [`TURBIDITY_RANGE`]), the sun toward unit
    /// `sun_direction` with angular diameter `sun_diameter` (radians, positive), zenith `up`
    /// (unit), every radiance times `scale`.
    pub fn daylight(
        turbidity: f32,
        sun_direction: Vec3,
        sun_diameter: f32,
        up: Vec3,
        scale: f32,
        portals: Vec<Portal>,
    ) -> Self {
        let cos_s = f64::from(sun_direction.dot(up)).clamp(-1.0, 1.0);
        let theta_s = cos_s.acos();
        let model = Preetham::new(f64::from(turbidity), theta_s);
        let half = f64::from(sun_diameter) / 2.0;
        let one_minus_cos = 2.0 * (half / 2.0).sin().powi(2);
        let sun = (cos_s > 0.0).then(|| {
            // The sun's illuminance above the atmosphere spread over its disc: a larger disc
            // gives the same light, softer shadows.
            let radiance = sun_transmittance(f64::from(turbidity), theta_s)
                * (SUN_ILLUMINANCE_OUTSIDE / (TAU * one_minus_cos) / f64::from(LUMINOUS_EFFICACY)
                    * f64::from(scale));
            Sun {
                direction: sun_direction,
                one_minus_cos: one_minus_cos as f32,
                sin2_half: half.sin().powi(2) as f32,
                radiance: radiance.as_vec3(),
            }
        });
        let mut sky = Self {
            kind: SkyKind::Daylight(Daylight {
                turbidity,
                sun_direction,
                sun_diameter,
                scale,
                model,
            }),
            up,
            sun,
            portals,
            dome_integral: Rgb::ZERO,
            up_irradiance: [0.0; 2],
        };
        // Midpoint rule over the upper hemisphere: the dome is smooth there.
        let frame = Frame::from_normal(up);
        let (n_theta, n_phi) = (64, 128);
        let (mut total, mut cos_total) = (DVec3::ZERO, DVec3::ZERO);
        for i in 0..n_theta {
            let theta = (f64::from(i) + 0.5) / f64::from(n_theta) * PI / 2.0;
            for j in 0..n_phi {
                let phi = (f64::from(j) + 0.5) / f64::from(n_phi) * TAU;
                let local = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                let l = sky
                    .dome_radiance(frame.to_world(local.as_vec3()))
                    .as_dvec3();
                let w = theta.sin() * (PI / 2.0 / f64::from(n_theta)) * (TAU / f64::from(n_phi));
                total += l * w;
                cos_total += l * w * theta.cos();
            }
        }
        sky.dome_integral = total.as_vec3();
        let sun_e = sky.sun.map_or(0.0, |s| {
            twopass_brdf::colour::luminance(s.radiance) * s.solid_angle() * s.direction.dot(up)
        });
        sky.up_irradiance = [twopass_brdf::colour::luminance(cos_total.as_vec3()), sun_e];
        sky
    }

    /// Radiance of the dome (the sky without the sun's disc) arriving from unit direction
    /// `dir` (pointing away from the receiver, toward the sky), W/(m^2 sr) per channel.
    pub fn dome_radiance(&self, dir: Vec3) -> Rgb {
        match &self.kind {
            SkyKind::Uniform { radiance } => *radiance,
            SkyKind::Daylight(d) => {
                let cos_theta = dir.dot(self.up);
                if cos_theta <= 0.0 {
                    return Rgb::ZERO;
                }
                let gamma = f64::from(dir.dot(d.sun_direction).clamp(-1.0, 1.0)).acos();
                let yxy = d.model.yxy(f64::from(cos_theta), gamma);
                // kcd/m^2 to W/(m^2 sr).
                (rgb_of_yxy(yxy) * (1000.0 / f64::from(LUMINOUS_EFFICACY) * f64::from(d.scale)))
                    .as_vec3()
            }
        }
    }

    /// Radiance of the sun's disc from unit direction `dir`: its radiance inside the disc and
    /// above the horizon, zero elsewhere.
    pub fn sun_radiance(&self, dir: Vec3) -> Rgb {
        match self.sun {
            Some(s) if s.contains(dir) && dir.dot(self.up) > 0.0 => s.radiance,
            _ => Rgb::ZERO,
        }
    }

    /// Radiance arriving from unit direction `dir`: what a ray that escapes the scene sees.
    pub fn radiance(&self, dir: Vec3) -> Rgb {
        self.dome_radiance(dir) + self.sun_radiance(dir)
    }

    /// Probability with which a light sample of the sky takes the sun (the rest: the dome),
    /// in proportion to their irradiance on a surface facing up, at least 0.1 each when both
    /// give light.
    pub fn sun_share(&self) -> f32 {
        let [dome, sun] = self.up_irradiance;
        if sun <= 0.0 || self.sun.is_none() {
            0.0
        } else if dome <= 0.0 {
            1.0
        } else {
            (sun / (sun + dome)).clamp(0.1, 0.9)
        }
    }

    /// A direction toward the sun's disc, uniform over its cone, for `u` uniform in [0, 1)^2,
    /// with its density (1/sr); `None` without a sun above the horizon.
    pub fn sample_sun(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let s = self.sun?;
        let one_minus = u.x * s.one_minus_cos;
        let cos = 1.0 - one_minus;
        let sin = (one_minus * (2.0 - one_minus)).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u.y;
        let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        let dir = Frame::from_normal(s.direction).to_world(local).normalize();
        Some((dir, 1.0 / s.solid_angle()))
    }

    /// Density (1/sr) of [`Self::sample_sun`] for unit direction `dir`.
    pub fn sun_pdf(&self, dir: Vec3) -> f32 {
        match self.sun {
            Some(s) if s.contains(dir) => 1.0 / s.solid_angle(),
            _ => 0.0,
        }
    }

    /// A direction of the dome's light at `x` whose receiving normal is `normal` (unit), for
    /// `u` uniform in [0, 1)^2 and `pick` in [0, 1), with its density (1/sr,
    /// [`Self::dome_pdf`]): cosine-distributed about `normal`, or with portals, with
    /// probability [`PORTAL_SHARE`] through a portal chosen by area at a point uniform on it.
    pub fn sample_dome(&self, x: Vec3, normal: Vec3, u: Vec2, pick: f32) -> Option<(Vec3, f32)> {
        let dir = if self.portals.is_empty() || pick >= PORTAL_SHARE {
            Frame::from_normal(normal)
                .to_world(square_to_cosine_hemisphere(u))
                .normalize()
        } else {
            let total: f32 = self.portals.iter().map(Portal::area).sum();
            let mut target = pick / PORTAL_SHARE * total;
            let portal = self
                .portals
                .iter()
                .find(|p| {
                    target -= p.area();
                    target < 0.0
                })
                .unwrap_or(&self.portals[self.portals.len() - 1]);
            let y = portal.origin + portal.edge_u * u.x + portal.edge_v * u.y;
            (y - x).try_normalize()?
        };
        let pdf = self.dome_pdf(x, normal, dir);
        (pdf > 0.0 && pdf.is_finite()).then_some((dir, pdf))
    }

    /// Density (1/sr) with which [`Self::sample_dome`] at `x` with normal `normal` returns
    /// unit direction `dir`.
    pub fn dome_pdf(&self, x: Vec3, normal: Vec3, dir: Vec3) -> f32 {
        let cosine = cosine_hemisphere_pdf(Vec3::Z * dir.dot(normal));
        if self.portals.is_empty() {
            return cosine;
        }
        let total: f32 = self.portals.iter().map(Portal::area).sum();
        let through: f32 = self
            .portals
            .iter()
            .filter_map(|p| p.crossing(x, dir))
            .map(|(t, cos)| {
                if cos > 0.0 {
                    t * t / (total * cos)
                } else {
                    0.0
                }
            })
            .sum();
        PORTAL_SHARE * through + (1.0 - PORTAL_SHARE) * cosine
    }

    /// The radiance integrated over all directions, W/m^2 per channel: the dome's (the sun
    /// left out) and the sun's disc's (L_sun Omega_sun; zero without a sun above the horizon).
    /// They set how light leaving the sky is shared between the two.
    pub fn integrals(&self) -> (Rgb, Rgb) {
        let sun = self.sun.map_or(Rgb::ZERO, |s| {
            if s.direction.dot(self.up) > 0.0 {
                s.radiance * s.solid_angle()
            } else {
                Rgb::ZERO
            }
        });
        (self.dome_integral, sun)
    }

    /// A direction toward the dome for light that leaves the sky into the scene (where
    /// [`Self::sample_dome`] serves a receiving point): uniform over the sphere for a uniform
    /// sky, over the hemisphere above the horizon for daylight (the dome is black below it),
    /// for `u` uniform in [0, 1)^2 (the cosine to [`Self::up`] linear in `u.x`, so strata stay
    /// strata), with its density (1/sr).
    pub fn sample_dome_emission(&self, u: Vec2) -> (Vec3, f32) {
        let (z, pdf) = match self.kind {
            SkyKind::Daylight(_) => (u.x, 1.0 / std::f32::consts::TAU),
            SkyKind::Uniform { .. } => (1.0 - 2.0 * u.x, 0.25 / std::f32::consts::PI),
        };
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u.y;
        let local = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        (Frame::from_normal(self.up).to_world(local).normalize(), pdf)
    }

    /// The power the sky sends into the bounding sphere of a scene whose bounding box has
    /// diagonal `scene_diagonal` (scene units), W per channel: pi R^2 times the radiance
    /// integrated over the directions, R half the diagonal; an upper bound of the light that
    /// can reach any surface of the scene.
    pub fn power(&self, scene_diagonal: f32) -> Rgb {
        let r = 0.5 * scene_diagonal;
        let sun = self.sun.map_or(Rgb::ZERO, |s| s.radiance * s.solid_angle());
        (self.dome_integral + sun) * (std::f32::consts::PI * r * r)
    }

    /// A one-line description for `info`.
    pub fn describe(&self) -> String {
        let portals = match self.portals.len() {
            0 => String::new(),
            n => format!(", {n} portal{}", if n == 1 { "" } else { "s" }),
        };
        match &self.kind {
            SkyKind::Uniform { radiance } => format!(
                "uniform, radiance [{}, {}, {}] W/(m^2 sr){portals}",
                radiance.x, radiance.y, radiance.z
            ),
            SkyKind::Daylight(d) => {
                let elevation = d
                    .sun_direction
                    .dot(self.up)
                    .clamp(-1.0, 1.0)
                    .asin()
                    .to_degrees();
                let sun = match self.sun {
                    Some(s) => format!(
                        "sun {:.2} deg wide, {:.3e} W/(m^2 sr) luminance",
                        d.sun_diameter.to_degrees(),
                        twopass_brdf::colour::luminance(s.radiance)
                    ),
                    None => "sun below the horizon (no sun light)".into(),
                };
                format!(
                    "daylight (Preetham), turbidity {}, sun elevation {elevation:.1} deg, {sun}, zenith {:.3} kcd/m^2, scale {}{portals}",
                    d.turbidity,
                    d.model.zenith_luminance(),
                    d.scale
                )
            }
        }
    }
}

#[cfg(test)]
mod tests;
