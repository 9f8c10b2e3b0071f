//! A node's `KHR_lights_punctual` light as a [`Lamp`]: placed and aimed by the node's world
//! transform, its photometric intensity made radiometric (the module docs of `load::gltf`).

use glam::{DMat4, DVec3};
use gltf::khr_lights_punctual::{Kind, Light};
use twopass_brdf::Rgb;

use super::read::quoted;
use crate::error::SceneError;
use crate::lamp::{LUMINOUS_EFFICACY, Lamp, LampKind, MAX_LAMP_INTENSITY};
use crate::load::loader::{Loader, in_range};

/// The lamp of `light`, on `node` whose world matrix is `world`; `at` names the node.
pub(super) fn lamp_of(
    ld: &mut Loader,
    light: &Light<'_>,
    node: &gltf::Node<'_>,
    world: DMat4,
    at: &str,
) -> Result<Lamp, SceneError> {
    let at = format!("{at}, light {}{}", light.index(), quoted(light.name()));
    let err = |problem: String| SceneError::Gltf {
        path: ld.path.clone(),
        at: at.clone(),
        problem,
    };
    let colour = Rgb::from_array(light.color());
    let value = light.intensity();
    let valid = |c: &f32| c.is_finite() && *c >= 0.0;
    if !(valid(&value) && colour.to_array().iter().all(valid)) {
        return Err(err(format!(
            "intensity {value} and color {colour} must be finite and non-negative"
        )));
    }
    let intensity = colour * (value / LUMINOUS_EFFICACY);
    if intensity.max_element() > MAX_LAMP_INTENSITY {
        return Err(err(format!(
            "intensity {value} reaches {:e} W/sr (or W/m^2), above the {MAX_LAMP_INTENSITY:e} the renderers represent",
            intensity.max_element()
        )));
    }
    let position = world.transform_point3(DVec3::ZERO).as_vec3();
    if !position.to_array().iter().all(|c| in_range(*c)) {
        return Err(err(format!(
            "the node places the light at {position}, outside the supported range"
        )));
    }
    let aim = || {
        world
            .transform_vector3(DVec3::NEG_Z)
            .normalize_or_zero()
            .as_vec3()
            .try_normalize()
            .ok_or_else(|| err("the node's transform collapses the light's -z axis".into()))
    };
    let kind = match light.kind() {
        Kind::Point => LampKind::Point,
        Kind::Directional => LampKind::Directional { direction: aim()? },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let ok = |a: f32| a.is_finite() && (0.0..=std::f32::consts::FRAC_PI_2).contains(&a);
            if !ok(inner_cone_angle) || !ok(outer_cone_angle) || outer_cone_angle < inner_cone_angle
            {
                return Err(err(format!(
                    "spot cone angles inner {inner_cone_angle} and outer {outer_cone_angle} radians must satisfy 0 <= inner <= outer <= pi / 2"
                )));
            }
            LampKind::Spot {
                direction: aim()?,
                cos_inner: inner_cone_angle.cos(),
                cos_outer: outer_cone_angle.cos(),
            }
        }
    };
    if let Some(range) = light.range() {
        ld.warnings.push(crate::error::Warning::Gltf {
            path: ld.path.clone(),
            at: at.clone(),
            problem: format!(
                "range {range} m is not modelled: the light falls off as 1 / r^2 without a cut-off"
            ),
        });
    }
    let name = node
        .name()
        .or(light.name())
        .map_or_else(|| format!("node {}", node.index()), crate::input::printable);
    Ok(Lamp {
        name,
        kind,
        position,
        intensity,
    })
}
