//! glTF materials onto twopass's models (the table in the module docs of `load::gltf`).

use twopass_brdf::{ComplexIor, CookTorranceParams, FresnelModel, Material, Rgb};

use super::read::{GltfFile, quoted};
use crate::error::{SceneError, Warning};
use crate::load::loader::Loader;
use crate::texture::{AlbedoTexture, Filter, Wrap};

/// glTF `roughnessFactor` below which a metal is the smooth `conductor` (a delta reflection)
/// rather than Cook-Torrance: alpha = roughness^2 < 0.0025, a highlight narrower than about
/// 3 degrees, which the glossy lobe's sampling would only show as noise.
pub const SMOOTH_ROUGHNESS: f32 = 0.05;

/// Largest diffuse albedo and metal F0 taken, per channel: radiosity needs albedo < 1, and
/// F0 = 1 has no finite complex index.
const MAX_REFLECTANCE: f32 = 0.999;

impl Loader {
    /// The twopass material and emitted radiance (W/(m^2 sr)) of glTF material `m` (`None`:
    /// a primitive without a material), with its warnings; `at` names it in messages.
    pub(super) fn gltf_material(
        &mut self,
        m: &gltf::Material<'_>,
        file: &GltfFile,
    ) -> Result<(Material, Rgb, String, Option<AlbedoTexture>), SceneError> {
        let index = m.index().unwrap_or(0);
        let at = format!("material {index}{}", quoted(m.name()));
        let name = m
            .name()
            .map_or_else(|| format!("material {index}"), str::to_owned);
        let mut ignored = Vec::new();
        let pbr = m.pbr_metallic_roughness();
        let warn = |ld: &mut Self, problem: String| {
            ld.warnings.push(Warning::Gltf {
                path: ld.path.clone(),
                at: at.clone(),
                problem,
            });
        };
        let base_texture = pbr.base_color_texture();
        let textured = base_texture.is_some()
            && m.transmission()
                .is_none_or(|t| t.transmission_factor() <= 0.0)
            && pbr.metallic_factor() < 0.5;
        for (present, what) in [
            (
                base_texture.is_some() && !textured,
                "baseColorTexture (on glass or a metal)",
            ),
            (m.emissive_texture().is_some(), "emissiveTexture"),
            (
                pbr.metallic_roughness_texture().is_some(),
                "metallicRoughnessTexture",
            ),
            (m.normal_texture().is_some(), "normalTexture"),
            (m.occlusion_texture().is_some(), "occlusionTexture"),
        ] {
            if present {
                ignored.push(what);
            }
        }
        if !ignored.is_empty() {
            warn(
                self,
                format!(
                    "textures other than a Lambertian's base colour are not modelled: {} not used, the factors alone are",
                    ignored.join(", ")
                ),
            );
        }
        if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            warn(
                self,
                format!(
                    "alphaMode {:?} is not modelled: the surface is opaque",
                    m.alpha_mode()
                ),
            );
        }
        let base = pbr.base_color_factor();
        let clamped = |ld: &mut Self, what: &str, v: [f32; 3]| {
            let to = v.map(|c| {
                if c.is_nan() {
                    0.0
                } else {
                    c.clamp(0.0, MAX_REFLECTANCE)
                }
            });
            if to != v {
                warn(
                    ld,
                    format!("{what} {v:?} clamped to {to:?} (a reflectance must be below 1)"),
                );
            }
            Rgb::from_array(to)
        };
        let metallic = pbr.metallic_factor();
        let roughness = pbr.roughness_factor();
        let built = if let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0) {
            let ior = m.ior().unwrap_or(1.5);
            let factor = t.transmission_factor();
            let mut lost = Vec::new();
            if factor < 1.0 {
                lost.push(format!("transmission {factor} taken as 1"));
            }
            if roughness > 0.0 {
                lost.push(format!("roughness {roughness} taken as 0 (smooth glass)"));
            }
            if base[..3].iter().any(|&c| c < 1.0) {
                lost.push("the base colour's tint not used (clear glass)".to_owned());
            }
            if !lost.is_empty() {
                warn(
                    self,
                    format!(
                        "KHR_materials_transmission as a smooth clear dielectric of ior {ior}: {}",
                        lost.join(", ")
                    ),
                );
            }
            Material::dielectric(ior)
        } else if metallic < 0.5 {
            if metallic > 0.0 {
                warn(
                    self,
                    format!("metallicFactor {metallic} taken as 0 (a Lambertian)"),
                );
            }
            let albedo = clamped(self, "baseColorFactor", [base[0], base[1], base[2]]);
            Material::lambert(albedo)
        } else {
            if metallic < 1.0 {
                warn(
                    self,
                    format!("metallicFactor {metallic} taken as 1 (a conductor)"),
                );
            }
            let f0 = clamped(self, "baseColorFactor", [base[0], base[1], base[2]]);
            let ior = metal_index(f0);
            if roughness < SMOOTH_ROUGHNESS {
                Material::conductor(ior)
            } else {
                Material::cook_torrance(CookTorranceParams {
                    diffuse: Rgb::ZERO,
                    specular: Rgb::ONE,
                    roughness: roughness * roughness,
                    ior,
                    fresnel: FresnelModel::Exact,
                })
            }
        };
        let material = built.map_err(|source| SceneError::Gltf {
            path: self.path.clone(),
            at: at.clone(),
            problem: format!("cannot be modelled: {source}"),
        })?;
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emission = Rgb::from_array(m.emissive_factor().map(|c| c * strength));
        let emission = self.emission(emission, &name, None)?;
        let texture = match base_texture.filter(|_| textured) {
            Some(info) => Some(self.gltf_texture(file, &info.texture(), &name)?),
            None => None,
        };
        Ok((material, emission, name, texture))
    }

    /// glTF texture `t` as a base colour texture of material `material`: its image decoded
    /// once (from a buffer view, a data URI or a file), its sampler's wrap modes and
    /// magnification filter (the minification filter is not used: a region's mean is read from
    /// the box-filtered pyramid, a point at full resolution).
    fn gltf_texture(
        &mut self,
        file: &GltfFile,
        t: &gltf::Texture<'_>,
        material: &str,
    ) -> Result<AlbedoTexture, SceneError> {
        let image = t.source();
        let name = format!("image {}{}", image.index(), quoted(image.name()));
        let index = image.index();
        let id = self
            .texture(
                format!("glTF image {index}"),
                name.clone(),
                |_| match image.source() {
                    gltf::image::Source::View { view, .. } => {
                        let buffer = &file.buffers[view.buffer().index()];
                        buffer
                            .get(view.offset()..view.offset() + view.length())
                            .map(<[u8]>::to_vec)
                            .ok_or_else(|| {
                                format!(
                                    "its buffer view {} reaches past its buffer's {} bytes",
                                    view.index(),
                                    buffer.len()
                                )
                            })
                    }
                    gltf::image::Source::Uri { .. } => file.images[index]
                        .as_ref()
                        .map(|(bytes, _)| bytes.clone())
                        .ok_or_else(|| "cannot be read (see the warning above)".to_owned()),
                },
            )
            .map_err(|problem| SceneError::Texture {
                path: self.path.clone(),
                line: None,
                material: material.to_owned(),
                texture: name,
                problem,
            })?;
        let sampler = t.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        Ok(AlbedoTexture {
            wrap_u: wrap(sampler.wrap_s()),
            wrap_v: wrap(sampler.wrap_t()),
            filter: match sampler.mag_filter() {
                Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
                _ => Filter::Linear,
            },
            ..AlbedoTexture::new(id)
        })
    }
}

/// The complex index of a metal whose reflectance at normal incidence is `f0` per channel (in
/// [0, 1)): n = 1, k = 2 sqrt(F0 / (1 - F0)), since ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) is
/// then k^2 / (4 + k^2) = F0.
fn metal_index(f0: Rgb) -> ComplexIor {
    ComplexIor {
        n: Rgb::ONE,
        k: Rgb::from_array(f0.to_array().map(|f| 2.0 * (f / (1.0 - f)).sqrt())),
    }
}

#[cfg(test)]
mod tests {
    use twopass_brdf::Rgb;

    /// The exact Fresnel reflectance at normal incidence of the metal index is F0.
    #[test]
    fn metal_index_reflects_f0_at_normal_incidence() {
        for f0 in [0.0f32, 0.04, 0.5, 0.9, 0.999] {
            let ior = super::metal_index(Rgb::splat(f0));
            let r = twopass_brdf::fresnel::complex(1.0, ior.n.to_array()[0], ior.k.to_array()[0]);
            assert!((r - f0).abs() < 1e-4, "F0 {f0}: reflectance {r}");
        }
    }
}
