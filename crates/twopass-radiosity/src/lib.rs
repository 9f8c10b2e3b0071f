//! The view-independent pass of twopass, with two solvers behind one interface ([`Solver`]):
//! - progressive-refinement radiosity (Cohen, Chen, Wallace & Greenberg 1988) with exact
//!   differential-area-to-polygon form factors and ray-traced visibility at the receiving
//!   vertices (Wallace, Elmquist & Haines 1989), patch/element substructuring with conforming
//!   adaptive subdivision (Cohen et al. 1986) and a dense reference solve ([`ProgressiveSolver`]);
//!   Each shot also carries the shooter's light through mirrors and glass to the diffuse
//!   surfaces it lands on ([`specular`]: the paths L S+ D and D S+ D);
//! - hierarchical radiosity with clustering (Hanrahan, Salzman & Aupperle 1991; Smits, Arvo &
//!   Greenberg 1994; Sillion 1994) for large scenes ([`HierarchicalSolver`]).
//!
//! Both keep the ambient term for partial solutions and power bookkeeping, and stop on one
//! convergence measure: the residual (unshot) power as a fraction of the emitted power. It
//! computes only: files and file formats (the bake file, glTF, PLY) are twopass-bake's.
//!
//! Units: radiosity B and irradiance in W/m^2 per RGB channel with areas in the scene's units,
//! radiance L = B / pi in W/(m^2 sr). Emitters are one-sided with exitance E = pi L_e. Lamps
//! (point, spot, directional) light every element vertex directly and exactly, I(w) cos / r^2
//! or E cos with a shadow ray, and both solvers carry that light on as they carry a shot's;
//! their power counts in the emitted power. The sky (and its sun) lights every vertex the same
//! way, its irradiance estimated by stratified shadow rays keyed by the seed and the vertex;
//! its power is what crosses the scene's bounding sphere.
//!
//! ```no_run
//! use twopass_radiosity::{Options, Solver};
//! use twopass_scene::DiffuseRadiance;
//! let (scene, _) = twopass_scene::load("scenes/cornell-box.toml")?;
//! let mut solver = Solver::new(&scene, Options::default())?;
//! let finish = solver.run(|progress| {
//!     eprintln!("residual {:.2e}", progress.unshot_fraction);
//!     std::ops::ControlFlow::Continue(())
//! });
//! let solution = solver.solution();
//! let l = solution.radiance(0, [1.0 / 3.0; 3]); // W/(m^2 sr) leaving triangle 0's centre
//! # let _ = (finish, l);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod albedo;
mod ambient;
mod close;
pub mod cluster;
pub mod element;
mod error;
mod escape;
pub mod form_factor;
pub mod hidden;
mod hierarchical;
mod lamps;
mod mesh_error;
mod options;
mod progressive;
mod report;
mod solution;
mod solver;
pub mod specular;
mod specular_receivers;
pub mod triangle_rule;

pub use close::{CloseLight, close_lights};
pub use error::SolveError;
pub use form_factor::VisibilityRays;
pub use hierarchical::HierarchicalSolver;
pub use mesh_error::{InvalidMesh, MeshPart};
pub use options::{
    AdaptiveOptions, HierarchicalOptions, MAX_VISIBILITY_RAYS, MIN_LINK_TOLERANCE, Method, Options,
    SpecularOptions, Stop,
};
pub use progressive::{
    MAX_DENSE_VERTICES, MAX_ELEMENTS, MAX_SWEEP_FORM_FACTORS, ProgressiveSolver, dense_solve,
};
pub use report::{ENERGY_TOLERANCE, Energy, Finish, Residuals, SolveProgress};
pub use solution::Solution;
pub use solver::Solver;
