//! Lamps: point, spot and directional lights (delta lights: no area, never hit by a ray), from
//! `[[light]]` tables and glTF's `KHR_lights_punctual`.
//!
//! Units: a point or spot lamp's `intensity` is radiant intensity I in W/sr, so the irradiance
//! it gives a surface at distance r (scene units) facing it is I / r^2 in W per scene unit
//! squared, the unit of the scene's emission; a directional lamp's is irradiance E in W per
//! scene unit squared on a surface facing it. A spot's intensity falls off between its inner
//! and outer cone angles by glTF's `KHR_lights_punctual` formula ([`spot_falloff`]).

use glam::Vec3;
use twopass_brdf::Rgb;

/// Luminous efficacy (lm/W) by which glTF's photometric lamp intensities (candela for point
/// and spot lamps, lux for directional ones) are divided to give radiometric ones (W/sr,
/// W/m^2): the factor Blender's glTF exporter multiplies by in its default ("Standard")
/// lighting mode, so a Blender lamp of P watts comes back as P watts.
pub const LUMINOUS_EFFICACY: f32 = 683.0;

/// Largest radiant intensity (W/sr) or irradiance (W/m^2) of a lamp per channel: its power and
/// the irradiance it gives near it must stay far inside f32 (as
/// [`MAX_EMITTED_POWER`](crate::MAX_EMITTED_POWER) bounds an area emitter).
pub const MAX_LAMP_INTENSITY: f32 = 1e30;

/// What kind of lamp, with its aim.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LampKind {
    /// Emits the same intensity in every direction from its position.
    Point,
    /// A point lamp limited to a cone around `direction` (unit), full intensity inside the
    /// inner angle, none outside the outer one, glTF's smooth falloff between.
    Spot {
        /// Axis of the cone (unit), from the lamp.
        direction: Vec3,
        /// Cosine of the inner cone's half angle.
        cos_inner: f32,
        /// Cosine of the outer cone's half angle (at most `cos_inner`).
        cos_outer: f32,
    },
    /// Parallel light travelling along `direction` (unit) from infinitely far away.
    Directional {
        /// Direction the light travels (unit).
        direction: Vec3,
    },
}

/// A lamp of the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Lamp {
    /// Name in messages (the `[[light]]` table's `name`, the glTF node's).
    pub name: String,
    /// Kind and aim.
    pub kind: LampKind,
    /// Position, scene units (unused by a directional lamp).
    pub position: Vec3,
    /// Radiant intensity I per channel in W/sr (point, spot: on the axis), or irradiance E per
    /// channel in W per scene unit squared on a surface facing a directional lamp.
    pub intensity: Rgb,
}

/// A lamp's light arriving at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LampLight {
    /// Unit direction from the point toward the lamp.
    pub direction: Vec3,
    /// Distance to the lamp, scene units (infinite for a directional lamp).
    pub distance: f32,
    /// Irradiance (W per scene unit squared per channel) on a surface facing the lamp:
    /// I(w) / r^2, or E; multiply by the cosine at the receiver.
    pub irradiance: Rgb,
}

/// glTF's spot falloff (`KHR_lights_punctual`): with `t = clamp((cos - cos_outer) /
/// max(0.001, cos_inner - cos_outer), 0, 1)`, the intensity's fraction is `t^2`; 1 inside the
/// inner cone, 0 outside the outer one.
pub fn spot_falloff(cos: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let t = ((cos - cos_outer) / (cos_inner - cos_outer).max(0.001)).clamp(0.0, 1.0);
    t * t
}

impl Lamp {
    /// The light the lamp sends to `point`, or `None` where it sends none (outside a spot's
    /// cone, or at the lamp's own position, where I / r^2 has no finite value).
    pub fn light_at(&self, point: Vec3) -> Option<LampLight> {
        if let LampKind::Directional { direction } = self.kind {
            return Some(LampLight {
                direction: -direction,
                distance: f32::INFINITY,
                irradiance: self.intensity,
            });
        }
        let d = self.position - point;
        let dist2 = d.length_squared();
        let distance = dist2.sqrt();
        let direction = d / distance;
        let falloff = match self.kind {
            LampKind::Spot {
                direction: axis,
                cos_inner,
                cos_outer,
            } => spot_falloff(-direction.dot(axis), cos_inner, cos_outer),
            _ => 1.0,
        };
        let irradiance = self.intensity * (falloff / dist2);
        // A receiver at (or a rounding error from) the lamp: r^2 is zero or so small that the
        // irradiance overflows; such a point gets no light rather than an infinity or a NaN.
        (falloff > 0.0 && dist2 > 0.0 && irradiance.is_finite()).then_some(LampLight {
            direction,
            distance,
            irradiance,
        })
    }

    /// The radiant intensity (W/sr per channel) a point or spot lamp sends in unit direction
    /// `direction` (from the lamp): I times the spot's falloff; zero for a directional lamp.
    pub fn intensity_toward(&self, direction: Vec3) -> Rgb {
        match self.kind {
            LampKind::Point => self.intensity,
            LampKind::Spot {
                direction: axis,
                cos_inner,
                cos_outer,
            } => self.intensity * spot_falloff(direction.dot(axis), cos_inner, cos_outer),
            LampKind::Directional { .. } => Rgb::ZERO,
        }
    }

    /// The power the lamp emits, W per channel: 4 pi I for a point lamp; for a spot, I times
    /// the solid angle its falloff weighs, 2 pi ((1 - cos_inner) + (cos_inner - cos_outer) / 3)
    /// (the falloff t^2 is linear in t over the cosine); for a directional lamp, what crosses
    /// the bounding sphere of a scene whose bounding box has diagonal `scene_diagonal` (scene
    /// units): E pi R^2 with R half the diagonal.
    pub fn power(&self, scene_diagonal: f32) -> Rgb {
        let tau = 2.0 * std::f32::consts::PI;
        match self.kind {
            LampKind::Point => self.intensity * (2.0 * tau),
            LampKind::Spot {
                cos_inner,
                cos_outer,
                ..
            } => {
                // t rises linearly with the cosine over w = max(0.001, blend) from cos_outer,
                // so the falloff integrates to w / 3 over the ramp and to 1 past it.
                let w = (cos_inner - cos_outer).max(0.001);
                let solid = if cos_outer + w <= 1.0 {
                    (1.0 - cos_outer) - 2.0 * w / 3.0
                } else {
                    (1.0 - cos_outer).powi(3) / (3.0 * w * w)
                };
                self.intensity * (tau * solid)
            }
            LampKind::Directional { .. } => {
                let r = 0.5 * scene_diagonal;
                self.intensity * (std::f32::consts::PI * r * r)
            }
        }
    }

    /// Whether a lamp is a delta light the scene's emitted power counts in full (every lamp
    /// but a directional one, whose power is only what crosses the scene).
    pub fn is_local(&self) -> bool {
        !matches!(self.kind, LampKind::Directional { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(inner_deg: f32, outer_deg: f32) -> Lamp {
        Lamp {
            name: "s".into(),
            kind: LampKind::Spot {
                direction: Vec3::NEG_Y,
                cos_inner: inner_deg.to_radians().cos(),
                cos_outer: outer_deg.to_radians().cos(),
            },
            position: Vec3::ZERO,
            intensity: Rgb::ONE,
        }
    }

    #[test]
    fn spot_power_is_the_integral_of_its_falloff() {
        // Midpoint rule over the cosine, independent of the closed form.
        for (inner, outer) in [(0.0, 45.0), (20.0, 30.0), (30.0, 30.0), (10.0, 89.0)] {
            let lamp = spot(inner, outer);
            let LampKind::Spot {
                cos_inner,
                cos_outer,
                ..
            } = lamp.kind
            else {
                unreachable!()
            };
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + (f64::from(i) + 0.5) * 2.0 / f64::from(n);
                    f64::from(spot_falloff(c as f32, cos_inner, cos_outer))
                })
                .sum::<f64>()
                * 2.0
                / f64::from(n);
            let expected = 2.0 * std::f64::consts::PI * sum;
            let got = f64::from(lamp.power(0.0).x);
            assert!(
                (got - expected).abs() < 1e-3 * expected,
                "{inner}..{outer}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn point_light_at_its_own_position_gives_none() {
        let lamp = Lamp {
            name: "p".into(),
            kind: LampKind::Point,
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity: Rgb::splat(1e10),
        };
        assert!(lamp.light_at(lamp.position).is_none());
        let near = lamp.light_at(lamp.position + Vec3::X * 1e-25);
        assert!(near.is_none_or(|l| l.irradiance.is_finite()));
        let l = lamp.light_at(Vec3::new(1.0, 0.0, 3.0)).expect("lit");
        assert_eq!(l.irradiance, Rgb::splat(1e10 / 4.0));
        assert_eq!(l.direction, Vec3::Y);
    }
}
