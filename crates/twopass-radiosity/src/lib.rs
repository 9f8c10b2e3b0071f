//! The view-independent pass of twopass: progressive-refinement radiosity (Cohen, Chen, Wallace
//! & Greenberg 1988) with exact differential-area-to-polygon form factors and ray-traced
//! visibility at the receiving vertices (Wallace, Elmquist & Haines 1989), patch/element
//! substructuring with conforming adaptive subdivision (Cohen et al. 1986), the ambient term
//! for partial solutions, power bookkeeping at every step, and a dense reference solve.
//!
//! Units: radiosity B and irradiance in W/m^2 per RGB channel with areas in the scene's units,
//! radiance L = B / pi in W/(m^2 sr). Emitters are one-sided with exitance E = pi L_e.
//!
//! ```no_run
//! use twopass_radiosity::{Options, Solver};
//! use twopass_scene::DiffuseRadiance;
//! let (scene, _) = twopass_scene::load("scenes/cornell-box.toml")?;
//! let mut solver = Solver::new(&scene, Options::default())?;
//! let finish = solver.run(|solver| {
//!     eprintln!("unshot {:.2e}", solver.progress().unshot_fraction);
//!     std::ops::ControlFlow::Continue(())
//! });
//! let solution = solver.solution();
//! let l = solution.radiance(0, [1.0 / 3.0; 3]); // W/(m^2 sr) leaving triangle 0's centre
//! # let _ = (finish, l);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bake;
mod direct;
pub mod element;
pub mod form_factor;
mod progressive;
mod solution;

pub use direct::{MAX_DENSE_VERTICES, dense_solve};
pub use form_factor::VisibilityRays;
pub use progressive::{
    Adaptive, Energy, Finish, MAX_ELEMENTS, Options, Progress, Residuals, SolveError, Solver, Stop,
};
pub use solution::Solution;
