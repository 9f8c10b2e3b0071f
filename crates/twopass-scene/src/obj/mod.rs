//! Wavefront OBJ + MTL through tobj, with the file and line context tobj does not give, and
//! the mapping of MTL materials onto ours.

mod lines;
mod map;
mod material;
mod model;
mod mtl;
mod normalize;
mod read;
mod scan;
#[cfg(test)]
mod tests;

pub(crate) use map::{DiffuseMap, diffuse_map};
pub(crate) use material::convert_material;
pub(crate) use model::MtlOrigin;
pub(crate) use read::load;
