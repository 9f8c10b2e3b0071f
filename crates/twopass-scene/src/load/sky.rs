//! The `[sky]` table and the `[[portal]]` tables into a [`Sky`], every value checked with the
//! table's line and key.

use glam::Vec3;
use toml::Spanned;

use super::loader::{Loader, in_range, rgb};
use crate::description::{PortalDesc, SkyDesc};
use crate::error::SceneError;
use crate::lamp::MAX_LAMP_INTENSITY;
use crate::load::MAX_COORDINATE;
use crate::sky::{Portal, SUN_DIAMETER_DEGREES, Sky, TURBIDITY_RANGE};

/// Turbidity when the table gives none (a clear day).
const DEFAULT_TURBIDITY: f32 = 3.0;

impl Loader {
    fn sky_err(&self, line: usize, table: String, problem: String) -> SceneError {
        SceneError::Sky {
            path: self.path.clone(),
            line,
            table,
            problem,
        }
    }

    /// The sky of the `[sky]` table (none without one) with the `[[portal]]` tables' portals;
    /// portals without a sky are an error (they would light nothing).
    pub(super) fn sky(
        &self,
        sky: Option<&Spanned<SkyDesc>>,
        portals: &[Spanned<PortalDesc>],
    ) -> Result<Option<Sky>, SceneError> {
        let portal_line = portals.first().map(|p| self.line(p));
        let portals = portals
            .iter()
            .enumerate()
            .map(|(i, p)| self.portal(p.get_ref(), self.line(p), i + 1))
            .collect::<Result<Vec<_>, _>>()?;
        let Some(sky) = sky else {
            if let Some(line) = portal_line {
                return Err(self.sky_err(
                    line,
                    "portal 1".into(),
                    "`[[portal]]` needs a `[sky]` table (a portal only lets the sky in)".into(),
                ));
            }
            return Ok(None);
        };
        let line = self.line(sky);
        let err = |problem: String| self.sky_err(line, "sky".into(), problem);
        let scale_of = |scale: Option<f32>| {
            let s = scale.unwrap_or(1.0);
            if s.is_finite() && s > 0.0 {
                Ok(s)
            } else {
                Err(err(format!(
                    "`scale` must be finite and positive (got {s})"
                )))
            }
        };
        let direction = |key: &str, d: [f32; 3]| {
            let v = Vec3::from_array(d);
            if !v.is_finite() {
                return Err(err(format!("`{key}` {d:?} is not finite")));
            }
            v.try_normalize()
                .ok_or_else(|| err(format!("`{key}` has zero length")))
        };
        let out = match sky.get_ref() {
            SkyDesc::Uniform { radiance, scale } => {
                let scale = scale_of(*scale)?;
                let l = rgb(*radiance);
                if let Some((c, v)) = l
                    .to_array()
                    .into_iter()
                    .enumerate()
                    .find(|(_, v)| !(v.is_finite() && *v >= 0.0))
                {
                    return Err(err(format!(
                        "`radiance` channel {c} must be finite and non-negative (got {v} W/(m^2 sr))"
                    )));
                }
                let l = l * scale;
                if l.max_element() > MAX_LAMP_INTENSITY {
                    return Err(err(format!(
                        "`radiance` times `scale` reaches {:e} W/(m^2 sr), above the {MAX_LAMP_INTENSITY:e} the renderers represent",
                        l.max_element()
                    )));
                }
                Sky::uniform(l, portals)
            }
            SkyDesc::Daylight {
                turbidity,
                sun_elevation,
                sun_azimuth,
                sun_direction,
                sun_diameter,
                up,
                scale,
            } => {
                let scale = scale_of(*scale)?;
                let t = turbidity.unwrap_or(DEFAULT_TURBIDITY);
                let [lo, hi] = TURBIDITY_RANGE;
                if !(t.is_finite() && (lo..=hi).contains(&t)) {
                    return Err(err(format!(
                        "`turbidity` must be in [{lo}, {hi}], where the daylight model is fitted (got {t})"
                    )));
                }
                let up = up.map_or(Ok(Vec3::Y), |u| direction("up", u))?;
                let sun = match (sun_direction, sun_elevation) {
                    (Some(d), None) => {
                        if sun_azimuth.is_some() {
                            return Err(err(
                                "`sun_azimuth` goes with `sun_elevation`, not `sun_direction`"
                                    .into(),
                            ));
                        }
                        direction("sun_direction", *d)?
                    }
                    (None, Some(el)) => {
                        if !(el.is_finite() && (-90.0..=90.0).contains(el)) {
                            return Err(err(format!(
                                "`sun_elevation` must be in [-90, 90] degrees (got {el})"
                            )));
                        }
                        let az = sun_azimuth.unwrap_or(0.0);
                        if !az.is_finite() {
                            return Err(err(format!("`sun_azimuth` must be finite (got {az})")));
                        }
                        sun_from_angles(up, el.to_radians(), az.to_radians())
                    }
                    _ => {
                        return Err(err(
                            "give exactly one of `sun_elevation` (degrees, with `sun_azimuth`) and `sun_direction`".into(),
                        ));
                    }
                };
                let diameter = sun_diameter.unwrap_or(SUN_DIAMETER_DEGREES);
                if !(diameter.is_finite() && diameter > 0.0 && diameter <= 45.0) {
                    return Err(err(format!(
                        "`sun_diameter` must be in (0, 45] degrees (got {diameter})"
                    )));
                }
                Sky::daylight(t, sun, diameter.to_radians(), up, scale, portals)
            }
        };
        Ok(Some(out))
    }

    /// The portal of `[[portal]]` table `index` (1-based) at `line`.
    fn portal(&self, p: &PortalDesc, line: usize, index: usize) -> Result<Portal, SceneError> {
        let err = |problem: String| self.sky_err(line, format!("portal {index}"), problem);
        for (key, v) in [
            ("origin", p.origin),
            ("edge_u", p.edge_u),
            ("edge_v", p.edge_v),
        ] {
            if !v.iter().all(|c| c.is_finite() && in_range(*c)) {
                return Err(err(format!(
                    "`{key}` {v:?} must be finite and within +-{MAX_COORDINATE:e} scene units"
                )));
            }
        }
        let portal = Portal {
            origin: Vec3::from_array(p.origin),
            edge_u: Vec3::from_array(p.edge_u),
            edge_v: Vec3::from_array(p.edge_v),
        };
        if portal.area().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(err(
                "`edge_u` and `edge_v` are parallel or zero: the portal has no area".into(),
            ));
        }
        Ok(portal)
    }
}

/// The unit direction toward a sun at `elevation` above the horizon of zenith `up` and
/// `azimuth` (radians) from the horizontal part of +z (of +x when `up` is along z) toward the
/// horizontal direction a quarter turn from it (+x for `up` = +y).
fn sun_from_angles(up: Vec3, elevation: f32, azimuth: f32) -> Vec3 {
    let north = (Vec3::Z - up * up.z)
        .try_normalize()
        .unwrap_or_else(|| (Vec3::X - up * up.x).normalize());
    let east = up.cross(north);
    (up * elevation.sin() + (north * azimuth.cos() + east * azimuth.sin()) * elevation.cos())
        .normalize()
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use glam::Vec3;

    use crate::{SkyKind, load_toml};

    use super::super::TEST_FLOOR as ROOM;

    fn load(extra: &str) -> Result<crate::Scene, String> {
        load_toml(&format!("{ROOM}{extra}"), Path::new("s.toml"))
            .map(|(s, _)| s)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn sky_tables_become_a_sky() {
        let s = load("[sky]\nkind = \"uniform\"\nradiance = [1, 2, 3]\nscale = 2\n").unwrap();
        let sky = s.sky.expect("sky");
        assert_eq!(
            sky.kind,
            SkyKind::Uniform {
                radiance: Vec3::new(2.0, 4.0, 6.0)
            }
        );
        let s = load("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nsun_azimuth = 90\n").unwrap();
        let sky = s.sky.expect("sky");
        let sun = sky.sun.expect("sun above the horizon");
        // Elevation 30 degrees toward +x.
        let expected = Vec3::new(30f32.to_radians().cos(), 0.5, 0.0);
        assert!(
            (sun.direction - expected).length() < 1e-6,
            "{}",
            sun.direction
        );
        assert!(
            load("[sky]\nkind = \"daylight\"\nsun_elevation = -5\n")
                .unwrap()
                .sky
                .unwrap()
                .sun
                .is_none()
        );
    }

    #[test]
    fn the_sun_stands_over_the_skys_own_up() {
        // With +z up, elevation 90 is +z, and azimuth 90 at elevation 0 a quarter turn from
        // the horizontal part of +x (the reference when up is along z) toward up x it.
        let s = load("[sky]\nkind = \"daylight\"\nsun_elevation = 90\nup = [0, 0, 2]\n").unwrap();
        let sky = s.sky.unwrap();
        assert_eq!(sky.up, Vec3::Z);
        assert!((sky.sun.unwrap().direction - Vec3::Z).length() < 1e-6);
        let s = load(
            "[sky]\nkind = \"daylight\"\nsun_elevation = 0\nsun_azimuth = 90\nup = [0, 0, 1]\n",
        )
        .unwrap();
        let SkyKind::Daylight(d) = &s.sky.as_ref().unwrap().kind else {
            panic!("daylight")
        };
        assert!(
            (d.sun_direction - Vec3::Y).length() < 1e-6,
            "{}",
            d.sun_direction
        );
    }

    #[test]
    fn bad_sky_values_name_the_file_line_and_key() {
        // The [sky] table (or the first [[portal]]) starts at line 14 of the file.
        #[rustfmt::skip]
        let cases = [
            ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nturbidity = 20\n", "s.toml:14: sky: `turbidity` must be in [2, 10], where the daylight model is fitted (got 20)"),
            ("[sky]\nkind = \"daylight\"\nsun_elevation = 95\n", "s.toml:14: sky: `sun_elevation` must be in [-90, 90] degrees (got 95)"),
            ("[sky]\nkind = \"daylight\"\nsun_direction = [0, 0, 0]\n", "s.toml:14: sky: `sun_direction` has zero length"),
            ("[sky]\nkind = \"daylight\"\n", "s.toml:14: sky: give exactly one of `sun_elevation` (degrees, with `sun_azimuth`) and `sun_direction`"),
            ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nsun_diameter = 0\n", "s.toml:14: sky: `sun_diameter` must be in (0, 45] degrees (got 0)"),
            ("[sky]\nkind = \"uniform\"\nradiance = [1, -1, 0]\n", "s.toml:14: sky: `radiance` channel 1 must be finite and non-negative (got -1 W/(m^2 sr))"),
            ("[sky]\nkind = \"uniform\"\nradiance = 1\nscale = -1\n", "s.toml:14: sky: `scale` must be finite and positive (got -1)"),
            ("[sky]\nkind = \"uniform\"\nradiance = 1\n[[portal]]\norigin = [0, 1, 0]\nedge_u = [1, 0, 0]\nedge_v = [2, 0, 0]\n", "s.toml:17: portal 1: `edge_u` and `edge_v` are parallel or zero: the portal has no area"),
        ];
        let cases = cases.into_iter().chain([(
            "[[portal]]\norigin = [0, 1, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\n",
            "s.toml:14: portal 1: `[[portal]]` needs a `[sky]` table (a portal only lets the sky in)",
        )]);
        for (extra, expected) in cases {
            assert_eq!(load(extra).unwrap_err(), expected, "{extra}");
        }
    }
}
