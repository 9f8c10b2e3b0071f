//! `[[light]]` tables into [`Lamp`]s, every value checked with the table's line and index.

use glam::Vec3;
use twopass_brdf::Rgb;

use super::loader::{Loader, in_range, rgb};
use crate::description::{LightDesc, Triple};
use crate::error::SceneError;
use crate::lamp::{Lamp, LampKind, MAX_LAMP_INTENSITY};
use crate::load::MAX_COORDINATE;

/// A spot's outer half angle when the table gives none, degrees (glTF's default, pi / 4).
const DEFAULT_OUTER_DEGREES: f32 = 45.0;

/// Where a `[[light]]` table is, for its errors.
struct At<'a> {
    ld: &'a Loader,
    line: usize,
    index: usize,
    name: Option<&'a str>,
}

impl At<'_> {
    fn err(&self, problem: String) -> SceneError {
        SceneError::Light {
            path: self.ld.path.clone(),
            line: self.line,
            index: self.index,
            name: self.name.map(str::to_owned),
            problem,
        }
    }

    fn point(&self, key: &str, p: [f32; 3]) -> Result<Vec3, SceneError> {
        if p.iter().all(|c| c.is_finite() && in_range(*c)) {
            Ok(Vec3::from_array(p))
        } else {
            Err(self.err(format!(
                "`{key}` {p:?} must be finite and within +-{MAX_COORDINATE:e} scene units"
            )))
        }
    }

    fn direction(&self, key: &str, d: Vec3) -> Result<Vec3, SceneError> {
        if !d.is_finite() {
            return Err(self.err(format!("`{key}` {d} is not finite")));
        }
        d.try_normalize()
            .ok_or_else(|| self.err(format!("`{key}` has zero length")))
    }

    /// The aim from `direction`, or from `position` toward `look_at`: exactly one of the two.
    fn aim(
        &self,
        direction: Option<[f32; 3]>,
        position: Option<Vec3>,
        look_at: Option<[f32; 3]>,
    ) -> Result<Vec3, SceneError> {
        match (direction, look_at) {
            (Some(d), None) => self.direction("direction", Vec3::from_array(d)),
            (None, Some(target)) => {
                let target = self.point("look_at", target)?;
                let from = position.ok_or_else(|| {
                    self.err("`look_at` needs `position` (the light travels from it)".into())
                })?;
                let d = target - from;
                if d == Vec3::ZERO {
                    return Err(self
                        .err("`look_at` equals `position`: the direction has zero length".into()));
                }
                self.direction("look_at - position", d)
            }
            _ => Err(self.err("give exactly one of `direction` and `look_at`".into())),
        }
    }

    /// The value times the colour, per channel, with the value's unit for messages.
    fn intensity(
        &self,
        key: &str,
        unit: &str,
        value: f32,
        colour: Option<Triple>,
    ) -> Result<Rgb, SceneError> {
        if !(value.is_finite() && value >= 0.0) {
            return Err(self.err(format!(
                "`{key}` must be finite and non-negative (got {value} {unit})"
            )));
        }
        let colour = colour.map_or(Rgb::ONE, rgb);
        if let Some((channel, c)) = colour
            .to_array()
            .into_iter()
            .enumerate()
            .find(|(_, c)| !(c.is_finite() && *c >= 0.0))
        {
            return Err(self.err(format!(
                "`colour` channel {channel} must be finite and non-negative (got {c})"
            )));
        }
        let out = colour * value;
        if out.max_element() > MAX_LAMP_INTENSITY {
            return Err(self.err(format!(
                "`{key}` times `colour` reaches {:e} {unit}, above the {MAX_LAMP_INTENSITY:e} the renderers represent",
                out.max_element()
            )));
        }
        Ok(out)
    }

    /// Radiant intensity (W/sr) from exactly one of `intensity` and `power`.
    fn radiant(
        &self,
        intensity: Option<f32>,
        power: Option<f32>,
        colour: Option<Triple>,
    ) -> Result<Rgb, SceneError> {
        match (intensity, power) {
            (Some(i), None) => self.intensity("intensity", "W/sr", i, colour),
            (None, Some(p)) => {
                self.intensity("power", "W", p, colour)?;
                self.intensity("power", "W", p / (4.0 * std::f32::consts::PI), colour)
            }
            _ => Err(self.err("give exactly one of `intensity` (W/sr) and `power` (W)".into())),
        }
    }
}

impl Loader {
    /// The lamp of `[[light]]` table `index` (1-based) at `line`.
    pub(super) fn lamp(
        &self,
        desc: &LightDesc,
        line: usize,
        index: usize,
    ) -> Result<Lamp, SceneError> {
        let name = match desc {
            LightDesc::Point { name, .. }
            | LightDesc::Spot { name, .. }
            | LightDesc::Directional { name, .. } => name.as_deref(),
        };
        let at = At {
            ld: self,
            line,
            index,
            name,
        };
        let lamp_name = name.map_or_else(|| format!("light {index}"), crate::input::printable);
        let lamp = match desc {
            LightDesc::Point {
                position,
                colour,
                intensity,
                power,
                ..
            } => Lamp {
                name: lamp_name,
                kind: LampKind::Point,
                position: at.point("position", *position)?,
                intensity: at.radiant(*intensity, *power, *colour)?,
            },
            LightDesc::Spot {
                position,
                direction,
                look_at,
                colour,
                intensity,
                power,
                inner_angle,
                outer_angle,
                ..
            } => {
                let position = at.point("position", *position)?;
                let direction = at.aim(*direction, Some(position), *look_at)?;
                let outer = outer_angle.unwrap_or(DEFAULT_OUTER_DEGREES);
                let inner = inner_angle.unwrap_or(0.0);
                if !(outer.is_finite() && outer > 0.0 && outer <= 90.0) {
                    return Err(at.err(format!(
                        "`outer_angle` must be in (0, 90] degrees (got {outer})"
                    )));
                }
                if !(inner.is_finite() && inner >= 0.0) {
                    return Err(at.err(format!(
                        "`inner_angle` must be finite and non-negative (got {inner} degrees)"
                    )));
                }
                if outer < inner {
                    return Err(at.err(format!(
                        "`outer_angle` ({outer} degrees) is smaller than `inner_angle` ({inner} degrees)"
                    )));
                }
                Lamp {
                    name: lamp_name,
                    kind: LampKind::Spot {
                        direction,
                        cos_inner: inner.to_radians().cos(),
                        cos_outer: outer.to_radians().cos(),
                    },
                    position,
                    intensity: at.radiant(*intensity, *power, *colour)?,
                }
            }
            LightDesc::Directional {
                direction,
                position,
                look_at,
                colour,
                irradiance,
                ..
            } => {
                let position = position.map(|p| at.point("position", p)).transpose()?;
                if direction.is_some() && position.is_some() {
                    return Err(at.err(
                        "`position` is only used with `look_at`; give `direction` alone".into(),
                    ));
                }
                Lamp {
                    name: lamp_name,
                    kind: LampKind::Directional {
                        direction: at.aim(*direction, position, *look_at)?,
                    },
                    position: position.unwrap_or(Vec3::ZERO),
                    intensity: at.intensity("irradiance", "W/m^2", *irradiance, *colour)?,
                }
            }
        };
        Ok(lamp)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use glam::Vec3;

    use crate::{LampKind, load_toml};

    use super::super::TEST_FLOOR as ROOM;

    #[test]
    fn light_tables_become_lamps_in_their_units() {
        let text = format!(
            "{ROOM}[[light]]\nkind = \"point\"\nname = \"bulb\"\nposition = [0, 1, 0]\npower = 100\n\
             [[light]]\nkind = \"spot\"\nposition = [0, 2, 0]\nlook_at = [0, 0, 0]\nintensity = 5\ncolour = [1, 0.5, 0]\ninner_angle = 10\nouter_angle = 30\n\
             [[light]]\nkind = \"directional\"\ndirection = [0, -2, 0]\nirradiance = 7\n"
        );
        let (scene, _) = load_toml(&text, Path::new("l.toml")).unwrap();
        assert_eq!(scene.lamps.len(), 3);
        let [bulb, spot, sun] = [&scene.lamps[0], &scene.lamps[1], &scene.lamps[2]];
        assert_eq!(bulb.name, "bulb");
        assert_eq!(bulb.kind, LampKind::Point);
        // 100 W over 4 pi sr.
        assert!((bulb.intensity.x - 100.0 / (4.0 * std::f32::consts::PI)).abs() < 1e-5);
        assert_eq!(spot.name, "light 2");
        assert_eq!(
            spot.kind,
            LampKind::Spot {
                direction: Vec3::NEG_Y,
                cos_inner: 10f32.to_radians().cos(),
                cos_outer: 30f32.to_radians().cos(),
            }
        );
        assert_eq!(spot.intensity.to_array(), [5.0, 2.5, 0.0]);
        assert_eq!(
            sun.kind,
            LampKind::Directional {
                direction: Vec3::NEG_Y
            }
        );
        assert_eq!(sun.intensity.to_array(), [7.0; 3]);
    }
}
