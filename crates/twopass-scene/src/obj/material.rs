//! The mapping of an MTL material onto ours.

use std::path::Path;

use twopass_brdf::{BlinnPhongParams, Material, Rgb};

use super::model::MtlOrigin;
use crate::error::{SceneError, Warning};

/// The MTL material as one of ours, its emission (Ke), and warnings for what was clamped or
/// ignored. Mapping: `Kd` -> diffuse; `Ks` > 0 with `Ns` -> classic Blinn-Phong (the MTL
/// specification's illumination models 2 and up use (N.H)^Ns); `illum` 4, 6, 7 with `Ni` ->
/// smooth dielectric; `illum` 3 or 5 with `Ks` -> mirror of reflectance `Ks`; `Ke` -> emitted
/// radiance. Reflectances >= 1 are clamped to 0.999 with a warning. `map_Kd` is read by the
/// loader ([`super::diffuse_map`]); the other texture maps are warned about.
pub(crate) fn convert_material(
    m: &tobj::Material,
    origin: Option<&MtlOrigin>,
    obj: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(Material, Rgb), SceneError> {
    let mtl_err = |key: &str, problem: String| SceneError::MtlMaterial {
        path: origin.map_or_else(|| obj.to_owned(), |o| o.path.clone()),
        line: origin.map(|o| o.line_of(key)),
        material: m.name.clone(),
        problem,
    };
    let clamp = |key: &'static str, v: [f32; 3], max: f32, w: &mut Vec<Warning>| {
        Rgb::from_array(v.map(|c| {
            let to = if c.is_nan() { 0.0 } else { c.clamp(0.0, max) };
            if to != c {
                w.push(Warning::MtlClamped {
                    path: obj.to_owned(),
                    material: m.name.clone(),
                    key,
                    from: c,
                    to,
                });
            }
            to
        }))
    };
    let diffuse = clamp("Kd", m.diffuse.unwrap_or([0.5; 3]), 0.999, warnings);
    let specular = clamp("Ks", m.specular.unwrap_or([0.0; 3]), 1.0, warnings);
    let emission = Rgb::from_array(m.emissive.unwrap_or([0.0; 3]));
    for (channel, value) in emission.to_array().into_iter().enumerate() {
        if !value.is_finite() {
            return Err(mtl_err(
                "Ke",
                format!("Ke channel {channel} is not finite ({value})"),
            ));
        }
        if value < 0.0 {
            return Err(mtl_err(
                "Ke",
                format!("Ke channel {channel} is negative ({value} W/(m^2 sr))"),
            ));
        }
    }
    let mut ignored: Vec<String> = m.unknown_param.keys().cloned().collect();
    for (key, present) in [
        ("map_Ka", m.ambient_texture.is_some()),
        ("map_Ks", m.specular_texture.is_some()),
        ("map_Bump", m.normal_texture.is_some()),
        ("map_Ns", m.shininess_texture.is_some()),
        ("map_d", m.dissolve_texture.is_some()),
        ("d", m.dissolve.is_some_and(|d| d < 1.0)),
    ] {
        if present {
            ignored.push(key.to_owned());
        }
    }
    if !ignored.is_empty() {
        ignored.sort();
        warnings.push(Warning::MtlIgnored {
            path: obj.to_owned(),
            material: m.name.clone(),
            keys: ignored,
        });
    }
    let illum = m.illumination_model.unwrap_or(2);
    let material = match (illum, m.optical_density) {
        (4 | 6 | 7, Some(ni)) if ni != 1.0 => Material::dielectric(ni),
        (3 | 5, _) if specular.max_element() > 0.0 => Material::mirror(specular),
        _ if illum >= 2 && specular.max_element() > 0.0 => {
            Material::blinn_phong(BlinnPhongParams {
                diffuse,
                specular,
                exponent: m.shininess.unwrap_or(0.0).clamp(0.0, 1e6),
                normalized: false,
            })
        }
        _ => Material::lambert(diffuse),
    }
    .map_err(|source| mtl_err("newmtl", source.to_string()))?;
    Ok((material, emission))
}
