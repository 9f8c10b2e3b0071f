//! Progressive refinement (Cohen, Chen, Wallace & Greenberg 1988) with ray-traced form factors
//! at the receiving vertices (Wallace, Elmquist & Haines 1989) and adaptive element subdivision,
//! plus the specular transfer of [`crate::specular`]: each shot also traces the shooter's light
//! through mirrors and glass and deposits it where it lands.
//!
//! The dense reference solve of the same system ([`dense_solve`]) lives here too: it reads the
//! solver's form-factor rows and patch weights.

mod build;
mod dense;
mod output;
mod patch_elements;
mod refine;
mod rows;
mod schedule;
mod shafts;
mod shoot;
mod state;

pub use dense::{MAX_DENSE_VERTICES, dense_solve};
pub use state::{MAX_ELEMENTS, MAX_SWEEP_FORM_FACTORS, ProgressiveSolver};
