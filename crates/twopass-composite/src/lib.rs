//! twopass-composite: linear RGB images and named layers in; tone-mapped PNGs, multi-layer EXRs,
//! comparison sheets and error metrics out. Depends on no renderer crate.

pub mod error;
pub mod false_colour;
pub mod image;
pub mod layer;
pub mod metric;
pub mod sheet;
mod text;
pub mod tonemap;
pub mod write;
