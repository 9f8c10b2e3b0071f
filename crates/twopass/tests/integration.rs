//! The command line's tests, one binary (one link step): each module drives the built
//! `twopass` as scripts do, through the shared functions in `common`.

mod common;

mod bake;
mod bakes;
mod cli;
mod compare;
mod fuzz_bake;
mod gltf_input;
mod lamps;
mod lightmap;
mod lightmap_render;
mod limits;
mod outputs;
mod parts;
mod planner;
mod readme;
mod render;
mod sky;
mod slurm;
mod textures;
mod third_party;
mod tradeoff;
mod view;
