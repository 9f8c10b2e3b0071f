//! The bake crate's tests, one binary (one link step): formats read back with independent
//! readers, and the lightmap checked against the solution, through the shared functions in
//! `common`.

mod common;

mod asset;
mod bake;
mod blender;
mod camera;
mod lightmap;
mod quantity;
mod rgbm;
mod validator;
mod vertex;
mod vertex_source;
