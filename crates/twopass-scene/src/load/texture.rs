//! Textures while a scene loads: each source (a file, a glTF image) decoded once, the MTL's
//! `map_Kd` read into a material, the coordinates a textured object needs checked.

use crate::error::SceneError;
use crate::input::{self, InputKind};
use crate::obj::DiffuseMap;
use crate::texture::{AlbedoTexture, Wrap, decode};

use super::loader::Loader;

impl Loader {
    /// The index of the texture from source `key` (named `name` in messages), decoded from
    /// `bytes()` the first time it is asked for; the problem in words otherwise.
    pub(super) fn texture(
        &mut self,
        key: String,
        name: String,
        bytes: impl FnOnce(&Self) -> Result<Vec<u8>, String>,
    ) -> Result<u32, String> {
        if let Some(&id) = self.texture_ids.get(&key) {
            return Ok(id);
        }
        let data = bytes(self)?;
        let texture = decode(&data, name)?;
        let id = self.textures.len() as u32;
        self.textures.push(texture);
        self.texture_ids.insert(key, id);
        Ok(id)
    }

    /// The texture an MTL material's `map_Kd` names, read through the scene's read policy. A
    /// texture that cannot be used is an error, not a warning: the surface would be shown
    /// with a colour the file does not give it, and a bake of it would be wrong without a
    /// sign.
    pub(super) fn mtl_texture(
        &mut self,
        map: &DiffuseMap,
        material: &str,
    ) -> Result<AlbedoTexture, SceneError> {
        let file = map.file.clone();
        let id = self
            .texture(
                file.display().to_string(),
                file.display().to_string(),
                |ld| {
                    input::read_bytes(&file, InputKind::Texture, &ld.policy).map_err(|e| match e {
                        SceneError::Io { source, .. } => format!("cannot read: {source}"),
                        SceneError::Input { problem, .. } => problem,
                        other => other.to_string(),
                    })
                },
            )
            .map_err(|problem| SceneError::Texture {
                path: map.library.clone(),
                line: map.line,
                material: material.to_owned(),
                texture: file.display().to_string(),
                problem,
            })?;
        let wrap = if map.clamp {
            Wrap::ClampToEdge
        } else {
            Wrap::Repeat
        };
        Ok(AlbedoTexture {
            wrap_u: wrap,
            wrap_v: wrap,
            scale: map.scale,
            offset: map.offset,
            ..AlbedoTexture::new(id)
        })
    }
}
