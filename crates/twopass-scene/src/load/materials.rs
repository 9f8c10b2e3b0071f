//! Materials: a scene file's material tables and an OBJ's MTL materials, converted and
//! validated once, each given its scene id.

use std::path::Path;

use twopass_brdf::{
    BlinnPhongParams, ComplexIor, CookTorranceParams, FresnelModel, Material, PhongParams, Rgb,
};

use super::loader::{Loader, rgb};
use crate::description::{FresnelDesc, MaterialDesc, Triple};
use crate::error::{SceneError, Warning};
use crate::obj;

impl Loader {
    pub(super) fn material(
        &self,
        desc: &MaterialDesc,
        line: usize,
    ) -> Result<Material, SceneError> {
        let name = desc.name();
        let spec_err = |problem: &str| SceneError::MaterialSpec {
            path: self.path.clone(),
            line,
            material: name.to_owned(),
            problem: problem.to_owned(),
        };
        let ior_of = |conductor: &Option<String>, ior: &Option<Triple>, k: &Option<Triple>| match (
            conductor, ior,
        ) {
            (Some(c), None) if k.is_none() => ComplexIor::conductor(c).ok_or_else(|| {
                let known: Vec<&str> = twopass_brdf::ior::CONDUCTORS
                    .iter()
                    .map(|c| c.name)
                    .collect();
                spec_err(&format!(
                    "unknown conductor `{c}` (known: {})",
                    known.join(", ")
                ))
            }),
            (None, Some(n)) => Ok(ComplexIor {
                n: rgb(*n),
                k: k.map_or(Rgb::ZERO, rgb),
            }),
            (Some(_), _) => Err(spec_err(
                "give either `conductor` or `ior` (with `k`), not both",
            )),
            (None, None) => Err(spec_err(
                "needs `conductor` (a measured metal) or `ior` (and `k`)",
            )),
        };
        let built = match desc {
            MaterialDesc::Lambert { diffuse, .. } => Material::lambert(rgb(*diffuse)),
            // Bound by their symbols in the text: rho, k_s, k_a, n.
            MaterialDesc::Phong {
                diffuse: rho,
                specular: ks,
                ambient: ka,
                exponent: n,
                normalized,
                ..
            } => Material::phong(PhongParams {
                ambient: ka.map_or(rgb(*rho), rgb),
                diffuse: rgb(*rho),
                specular: rgb(*ks),
                exponent: *n,
                normalized: *normalized,
            }),
            MaterialDesc::BlinnPhong {
                diffuse: rho,
                specular: ks,
                exponent: n,
                normalized,
                ..
            } => Material::blinn_phong(BlinnPhongParams {
                diffuse: rgb(*rho),
                specular: rgb(*ks),
                exponent: *n,
                normalized: *normalized,
            }),
            MaterialDesc::CookTorrance {
                diffuse,
                specular,
                roughness,
                conductor,
                ior,
                k,
                fresnel,
                ..
            } => Material::cook_torrance(CookTorranceParams {
                diffuse: rgb(*diffuse),
                specular: rgb(*specular),
                roughness: *roughness,
                ior: ior_of(conductor, ior, k)?,
                fresnel: match fresnel {
                    FresnelDesc::Exact => FresnelModel::Exact,
                    FresnelDesc::Schlick => FresnelModel::Schlick,
                },
            }),
            MaterialDesc::Mirror { reflectance, .. } => Material::mirror(rgb(*reflectance)),
            MaterialDesc::Dielectric { ior, .. } => Material::dielectric(*ior),
            MaterialDesc::Conductor {
                conductor, ior, k, ..
            } => Material::conductor(ior_of(conductor, ior, k)?),
        };
        built.map_err(|source| SceneError::Material {
            path: self.path.clone(),
            line: Some(line),
            material: name.to_owned(),
            source,
        })
    }

    /// Converts every MTL material once; returns (material id, emission) per MTL index.
    pub(super) fn mtl_materials(
        &mut self,
        mtl: &[tobj::Material],
        origins: &[obj::MtlOrigin],
        obj_path: &Path,
    ) -> Result<Vec<(u32, Rgb)>, SceneError> {
        let file = obj_path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        let mut out = Vec::with_capacity(mtl.len());
        for (i, m) in mtl.iter().enumerate() {
            let (material, emission) =
                obj::convert_material(m, origins.get(i), obj_path, &mut self.warnings)?;
            let name = format!("{file}:{}", m.name);
            let id = match self.material_ids.get(&name) {
                Some(&id) => id,
                None => {
                    let map = m.diffuse_texture.as_deref().and_then(|v| {
                        obj::diffuse_map(v, &m.name, origins.get(i), obj_path, &mut self.warnings)
                    });
                    let texture = match map {
                        Some(map) if material.reflects_diffusely() => {
                            Some(self.mtl_texture(&map, &m.name)?)
                        }
                        Some(map) => {
                            self.warnings.push(Warning::Texture {
                                path: map.library.clone(),
                                line: map.line,
                                at: format!("MTL material `{}`", m.name),
                                problem: "map_Kd on a material without a diffuse part (a mirror or glass): not used".into(),
                            });
                            None
                        }
                        None => None,
                    };
                    let id = self.add_material(name, material);
                    self.materials[id as usize].albedo_texture = texture;
                    id
                }
            };
            out.push((id, emission));
        }
        Ok(out)
    }
}
