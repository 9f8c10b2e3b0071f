//! The albedo where a surface is shaded: a material's diffuse reflectance times its base colour
//! texture's value, the one look-up every pass uses (the tracer per hit, the bake per texel,
//! radiosity per element). A scene without textures pays one length check per query.

use glam::Vec2;
use twopass_brdf::{Material, Rgb};

use crate::scene::Scene;
use crate::texture::{AlbedoTexture, Texture};

impl Scene {
    /// Whether any triangle of the scene reads a base colour texture.
    pub fn has_textures(&self) -> bool {
        self.mesh.has_albedo_uvs()
    }

    /// The texture triangle `t` reads, how, and its corners' texture coordinates; `None` for
    /// an untextured triangle.
    pub fn albedo_texture_of(&self, t: u32) -> Option<(&Texture, &AlbedoTexture, [Vec2; 3])> {
        let uv = self.mesh.albedo_uv(t)?;
        let o = &self.objects[self.mesh.object_of(t) as usize];
        let a = self.materials[o.material as usize]
            .albedo_texture
            .as_ref()?;
        Some((&self.textures[a.texture as usize], a, uv))
    }

    /// The texture's linear value on triangle `t` at barycentrics `b` (with the sampler's
    /// filter, full resolution); 1 on an untextured triangle.
    pub fn albedo_tint(&self, t: u32, b: [f32; 3]) -> Rgb {
        match self.albedo_texture_of(t) {
            Some((tex, a, uv)) => tex.sample(a, uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2]),
            None => Rgb::ONE,
        }
    }

    /// The texture's area-weighted mean over the part of triangle `t` whose corners have
    /// barycentrics `corners` (an element of the radiosity mesh), from the mip level that fits
    /// it ([`Texture::mean_over`]); 1 on an untextured triangle. A triangle's texture
    /// coordinates are affine over it, so the mean over texture space is the mean over the
    /// surface.
    pub fn albedo_tint_over(&self, t: u32, corners: [[f32; 3]; 3]) -> Rgb {
        match self.albedo_texture_of(t) {
            Some((tex, a, uv)) => tex.mean_over(
                a,
                corners.map(|b| uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2]),
            ),
            None => Rgb::ONE,
        }
    }

    /// The diffuse reflectance rho on triangle `t` at barycentrics `b`: its material's times
    /// [`Scene::albedo_tint`].
    pub fn diffuse_albedo_at(&self, t: u32, b: [f32; 3]) -> Rgb {
        let rho = self.material_of(t).diffuse_albedo();
        if self.has_textures() {
            rho * self.albedo_tint(t, b)
        } else {
            rho
        }
    }

    /// The mean diffuse reflectance over the part of triangle `t` with barycentric corners
    /// `corners`: its material's times [`Scene::albedo_tint_over`].
    pub fn diffuse_albedo_over(&self, t: u32, corners: [[f32; 3]; 3]) -> Rgb {
        let rho = self.material_of(t).diffuse_albedo();
        if self.has_textures() {
            rho * self.albedo_tint_over(t, corners)
        } else {
            rho
        }
    }

    /// The mean diffuse reflectance over the whole of triangle `t` (its material's on an
    /// untextured one).
    pub fn triangle_albedo(&self, t: u32) -> Rgb {
        self.diffuse_albedo_over(t, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    }

    /// The material a surface is shaded with on triangle `t` at barycentrics `b`: its material,
    /// the diffuse part tinted by the texture there ([`Material::tinted`]); the material as it
    /// is on an untextured triangle.
    pub fn material_at(&self, t: u32, b: [f32; 3]) -> Material {
        let m = self.material_of(t);
        match self.albedo_texture_of(t) {
            Some((tex, a, uv)) => {
                m.tinted(tex.sample(a, uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2]))
            }
            None => *m,
        }
    }
}
