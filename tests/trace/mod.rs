//! Validation of twopass-trace: closed forms, the furnace, mirror and glass against exact
//! optics, spawned rays, the hybrid invariant, determinism and non-finite samples.

mod adaptive;
mod analytic;
mod budget;
mod caustics;
mod common;
mod determinism;
mod furnace;
mod gather;
mod gathered;
mod hybrid;
mod lamps;
mod optics;
mod photons;
mod share;
mod sky;
mod splitting;
mod textured;
