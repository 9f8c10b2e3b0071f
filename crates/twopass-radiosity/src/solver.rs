//! [`Solver`]: one interface over both radiosity solvers, running the method the options (or
//! the scene's size) choose: progressive refinement ([`ProgressiveSolver`]) or hierarchical
//! radiosity with clustering ([`HierarchicalSolver`]).

use std::ops::ControlFlow;

use twopass_scene::Scene;

use crate::element::ElementMesh;
use crate::error::SolveError;
use crate::hierarchical::HierarchicalSolver;
use crate::options::{Method, Options};
use crate::progressive::ProgressiveSolver;
use crate::report::{ENERGY_TOLERANCE, Finish, Residuals, SolveProgress};
use crate::solution::Solution;

/// A radiosity solve of a scene by the method [`Options::method`] names: one interface for
/// the commands and tools that solve, whatever the method.
pub enum Solver<'s> {
    /// Progressive refinement.
    Progressive(Box<ProgressiveSolver<'s>>),
    /// Hierarchical radiosity with clustering.
    Hierarchical(Box<HierarchicalSolver<'s>>),
}

impl<'s> Solver<'s> {
    /// Sets up the solve: [`Method::Auto`] picks the method by the scene's size.
    pub fn new(scene: &'s Scene, options: Options) -> Result<Self, SolveError> {
        let (method, _) = options.method.choose(scene);
        Ok(match method {
            Method::Hierarchical => {
                Self::Hierarchical(Box::new(HierarchicalSolver::new(scene, options)?))
            }
            _ => Self::Progressive(Box::new(ProgressiveSolver::new(scene, options)?)),
        })
    }

    /// Runs to the stop criteria; `observer` sees the progress after every shot (progressive)
    /// or gather iteration (hierarchical) and may stop the solve early by returning `Break`.
    /// The solution is usable whenever this returns.
    ///
    /// Each shot runs a parallel loop on rayon's global pool. Called from a thread outside the
    /// pool, every loop is handed over and waited for, thousands of times; call it from inside the
    /// pool (`rayon::scope(|_| solver.run(..))`, as the CLI does) to avoid that.
    pub fn run(&mut self, mut observer: impl FnMut(&SolveProgress) -> ControlFlow<()>) -> Finish {
        match self {
            Self::Progressive(p) => p.run(|s| observer(&s.progress())),
            Self::Hierarchical(h) => h.run(|s| observer(&s.progress())),
        }
    }

    /// The method that runs.
    pub fn method(&self) -> Method {
        match self {
            Self::Progressive(_) => Method::Progressive,
            Self::Hierarchical(_) => Method::Hierarchical,
        }
    }

    /// Where the solve stands.
    pub fn progress(&self) -> SolveProgress {
        match self {
            Self::Progressive(p) => p.progress(),
            Self::Hierarchical(h) => h.progress(),
        }
    }

    /// The current solution (with the ambient term of a partial solve).
    pub fn solution(&self) -> Solution {
        match self {
            Self::Progressive(p) => p.solution(),
            Self::Hierarchical(h) => h.solution(),
        }
    }

    /// The energy balance as an invariant: an error when the solve so far created more than
    /// [`ENERGY_TOLERANCE`] of the emitted power ([`Energy::created_fraction`]), which happens
    /// where surfaces are closer than the element mesh resolves. Call it after
    /// [`Solver::run`] and before using the solution.
    ///
    /// [`Energy::created_fraction`]: crate::report::Energy::created_fraction
    pub fn check_energy(&self) -> Result<(), SolveError> {
        let created = self.progress().energy.created_fraction();
        // Written so that a NaN fails too.
        if created <= ENERGY_TOLERANCE {
            Ok(())
        } else {
            Err(SolveError::EnergyCreated {
                solver: self.method().name(),
                created,
                tolerance: ENERGY_TOLERANCE,
            })
        }
    }

    /// Consistency checks on up to `samples` sampled vertices, elements and node pairs, and the
    /// power lost ([`Residuals::energy_lost`], from 64 rays at each of `4 samples` points);
    /// their cost is bounded by the samples, not by the scene.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        let solution = self.solution();
        self.residuals_of(samples, &solution)
    }

    /// [`Solver::residuals`] with the lost power sampled over `solution`, this solver's
    /// [`Solver::solution`], for a caller that has it already (building it again would copy
    /// the element mesh).
    pub fn residuals_of(&mut self, samples: usize, solution: &Solution) -> Residuals {
        let mut residuals = match self {
            Self::Progressive(p) => p.residuals(samples),
            Self::Hierarchical(h) => h.residuals(samples),
        };
        let (scene, seed) = match &*self {
            Self::Progressive(p) => (p.scene(), p.options().seed),
            Self::Hierarchical(h) => (h.scene(), h.options().seed),
        };
        let energy = self.progress().energy;
        if let Some((lost, error)) =
            crate::escape::lost_fraction(scene, solution, &energy, 4 * samples, seed)
        {
            residuals.energy_lost = Some(lost);
            residuals.energy_lost_error = Some(error);
        }
        residuals
    }

    /// The element mesh.
    pub fn mesh(&self) -> &ElementMesh {
        match self {
            Self::Progressive(p) => p.mesh(),
            Self::Hierarchical(h) => h.mesh(),
        }
    }
}
