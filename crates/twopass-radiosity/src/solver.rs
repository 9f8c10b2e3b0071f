//! What every radiosity solve shares: the settings, the stop criteria, the errors, the
//! progress and consistency reports, and [`Solver`], which runs the method the options (or the
//! scene's size) choose: progressive refinement ([`ProgressiveSolver`]) or hierarchical radiosity
//! with clustering ([`HierarchicalSolver`]).

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::DVec3;
use smart_default::SmartDefault;
use twopass_scene::Scene;

use crate::element::ElementMesh;
use crate::form_factor::VisibilityRays;
use crate::hierarchical::HierarchicalSolver;
use crate::progressive::ProgressiveSolver;
use crate::solution::Solution;
use crate::specular::SpecularOptions;

/// When the solver stops. The first criterion met ends the solve.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct Stop {
    /// The convergence measure both solvers stop on: the residual power (light received and
    /// reflected but not yet passed on: the unshot power of progressive refinement, the change
    /// of the last gather iteration of the hierarchical solver) as a fraction of the emitted
    /// power (sums over channels), default 1e-3.
    #[default(1e-3)]
    pub unshot_fraction: f64,
    /// Most shots (progressive) or gather iterations (hierarchical) in all, if set.
    pub max_shots: Option<u64>,
    /// Wall-clock budget, if set.
    pub time_budget: Option<Duration>,
}

/// Adaptive subdivision of elements where the radiosity changes fast.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveOptions {
    /// Split an element when its vertices' luminances differ by more than this fraction of
    /// the scene's mean luminance.
    #[default(0.2)]
    pub threshold: f32,
    /// Never split an element whose longest edge is shorter than twice this (scene units);
    /// `None`: an eighth of the element size.
    pub min_element_size: Option<f32>,
    /// Refinement rounds, each followed by shooting down to `at_unshot_fraction`.
    #[default(3)]
    pub rounds: u32,
    /// Unshot fraction at which each round looks at the solution.
    #[default(1e-2)]
    pub at_unshot_fraction: f64,
}

/// Everything the solver can be told. Defaults suit the Cornell box; sizes default to
/// fractions of the scene's bounding-box diagonal.
#[derive(SmartDefault, Debug, Clone, PartialEq)]
pub struct Options {
    /// Longest patch edge (shooters), scene units; default diagonal / 8.
    pub patch_size: Option<f32>,
    /// Longest element edge (receivers) before adaptive subdivision; default diagonal / 24.
    pub element_size: Option<f32>,
    /// Adaptive subdivision, or `None` for a fixed mesh.
    #[default(Some(AdaptiveOptions::default()))]
    pub adaptive: Option<AdaptiveOptions>,
    /// Shadow rays per visibility estimate.
    pub visibility: VisibilityRays,
    /// Measure visibility with shadow rays; `false` treats every pair as unoccluded (exact only
    /// for scenes where no surface hides another, such as one convex room).
    #[default(true)]
    pub occlusion: bool,
    /// Skip the shadow rays between a receiver and a shooter that nothing in the scene can
    /// come between (shaft culling, progressive refinement): their visibility is 1. Off, every
    /// pair casts its rays, as a check and to measure what culling saves.
    #[default(true)]
    pub shaft_culling: bool,
    /// Stop criteria.
    pub stop: Stop,
    /// Seed of the visibility sampling.
    pub seed: u64,
    /// Memory allowed for cached vertex-to-patch form factors, bytes (default 1 GiB).
    #[default(1 << 30)]
    pub cache_bytes: usize,
    /// Which solver runs.
    #[default(Method::Auto)]
    pub method: Method,
    /// Settings of the hierarchical solver.
    pub hierarchical: HierarchicalOptions,
    /// Memory the solve may take, bytes (default 16 GiB): a mesh or link structure estimated
    /// to need more is refused before it is built ([`SolveError::TooLarge`]), and the
    /// hierarchical solver stops refining links when it reaches it.
    #[default(16 << 30)]
    pub memory_limit: u64,
    /// Light carried through mirrors and glass onto diffuse surfaces (both solvers), or `None`
    /// to treat specular objects as absorbers. It runs only where [`crate::specular::decide`] says the scene needs it.
    #[default(Some(SpecularOptions::default()))]
    pub specular: Option<SpecularOptions>,
}

/// Why a solve cannot start.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum SolveError {
    /// Nothing in the scene emits light: there is nothing to solve.
    NoEmitters,
    /// No surface reflects diffusely or emits: radiosity has nothing to compute.
    NothingTakesPart,
    /// An option is out of range.
    Option {
        /// The option's name.
        name: &'static str,
        /// Why.
        problem: String,
    },
    /// The mesh the options ask for would not fit in the memory limit.
    TooLarge {
        /// What was estimated, in words (elements and their sizes).
        what: String,
        /// Estimated bytes.
        bytes: u64,
        /// [`Options::memory_limit`], bytes.
        limit: u64,
    },
}

impl std::fmt::Display for SolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoEmitters => write!(
                f,
                "nothing in the scene emits light, so there is no radiosity to solve"
            ),
            Self::NothingTakesPart => write!(
                f,
                "no surface reflects diffusely or emits, so radiosity has nothing to compute"
            ),
            Self::Option { name, problem } => write!(f, "radiosity option `{name}`: {problem}"),
            Self::TooLarge { what, bytes, limit } => write!(
                f,
                "{what} would need about {:.1} GiB, more than the memory limit of {:.1} GiB; \
                 use a larger element size or the hierarchical solver",
                *bytes as f64 / f64::from(1u32 << 30),
                *limit as f64 / f64::from(1u32 << 30)
            ),
        }
    }
}

impl std::error::Error for SolveError {}

/// Power bookkeeping, W per channel (scene units): emitted = absorbed + escaped + unshot +
/// remeshing, exactly up to rounding.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Energy {
    /// Total emitted power.
    pub emitted: DVec3,
    /// Absorbed by surfaces (the (1 - rho) part of what arrived).
    pub absorbed: DVec3,
    /// Shot but not received by any element: left through openings, or the discretization
    /// error of the vertex form factors (can then be slightly negative).
    pub escaped: DVec3,
    /// Received and reflected but not shot yet.
    pub unshot: DVec3,
    /// Change of the unshot estimate when adaptive subdivision re-estimated patch radiosities.
    pub remeshing: DVec3,
}

impl Energy {
    /// Largest relative imbalance over the channels, |emitted - (sum of the rest)| / emitted.
    pub fn imbalance(&self) -> f64 {
        let rest = self.absorbed + self.escaped + self.unshot + self.remeshing;
        let d = (self.emitted - rest).abs();
        let e = self.emitted.max(DVec3::splat(f64::MIN_POSITIVE));
        (d / e).max_element()
    }
}

/// What both solvers keep alike about a solve: its refinement rounds, its clock and its power
/// bookkeeping, reported in [`SolveProgress`]. Crate-private; its fields are the solvers' own.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bookkeeping {
    /// Refinement rounds done (adaptive subdivision, or link refinement).
    pub rounds: u32,
    /// When the solver was created.
    pub started: Instant,
    /// Time spent building the mesh.
    pub meshing: Duration,
    /// Time spent refining.
    pub refining: Duration,
    /// Power bookkeeping, W per channel.
    pub energy: Energy,
    /// Largest relative energy imbalance seen after any step.
    pub worst_imbalance: f64,
}

impl Bookkeeping {
    /// Nothing done yet: the solver started at `started` and spent `meshing` building its mesh.
    pub(crate) fn new(started: Instant, meshing: Duration) -> Self {
        Self {
            rounds: 0,
            started,
            meshing,
            refining: Duration::ZERO,
            energy: Energy::default(),
            worst_imbalance: 0.0,
        }
    }

    /// Notes the current energy imbalance in [`Bookkeeping::worst_imbalance`].
    pub(crate) fn note_imbalance(&mut self) {
        self.worst_imbalance = self.worst_imbalance.max(self.energy.imbalance());
    }

    /// A progress report of `method` with these figures; the solver sets its own counts.
    pub(crate) fn progress(&self, method: Method) -> SolveProgress {
        SolveProgress {
            method,
            shots: 0,
            iterations: 0,
            links: 0,
            clusters: 0,
            unshot_fraction: 0.0,
            rays: 0,
            elements: 0,
            vertices: 0,
            patches: 0,
            refinement_rounds: self.rounds,
            elapsed: self.started.elapsed(),
            meshing: self.meshing,
            refining: self.refining,
            energy: self.energy,
            worst_imbalance: self.worst_imbalance,
        }
    }
}

/// Where a solve stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveProgress {
    /// The solver that runs (never [`Method::Auto`]).
    pub method: Method,
    /// Shots so far (progressive refinement; 0 for the hierarchical solver).
    pub shots: u64,
    /// Gather iterations so far (hierarchical; 0 for progressive refinement).
    pub iterations: u64,
    /// Links between hierarchy nodes (hierarchical; 0 for progressive refinement).
    pub links: usize,
    /// Clusters above the surfaces (hierarchical; 0 for progressive refinement).
    pub clusters: usize,
    /// The convergence measure: residual (unshot) power / emitted power, sums over channels.
    pub unshot_fraction: f64,
    /// Rays cast so far: shadow rays, and the specular transfer's rays (progressive).
    pub rays: u64,
    /// Elements (leaves) now.
    pub elements: usize,
    /// Vertices now.
    pub vertices: usize,
    /// Patches (shooters).
    pub patches: usize,
    /// Adaptive rounds (progressive) or link refinement rounds (hierarchical) done.
    pub refinement_rounds: u32,
    /// Wall-clock time since the solver was created.
    pub elapsed: Duration,
    /// Time spent building the patch and element mesh.
    pub meshing: Duration,
    /// Time spent in adaptive subdivision (including the new vertices' gathering), or in link
    /// refinement (hierarchical).
    pub refining: Duration,
    /// Power bookkeeping.
    pub energy: Energy,
    /// Largest energy imbalance seen after any step.
    pub worst_imbalance: f64,
}

/// Consistency figures of a solve (see [`Solver::residuals`]). Serializable (serde derives, no
/// format here) so that the bake manifest records them field by field.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Residuals {
    /// Largest relative energy imbalance seen after any shot.
    pub energy_imbalance: f64,
    /// Smallest sampled vertex form-factor row sum.
    pub row_sum_min: f64,
    /// Mean sampled row sum.
    pub row_sum_mean: f64,
    /// Largest sampled row sum.
    pub row_sum_max: f64,
    /// Patch pairs with a non-zero form factor among those sampled.
    pub reciprocity_pairs: usize,
    /// Largest |A_p F_pq - A_q F_qp| / max of the two over the sampled pairs. Large for pairs
    /// seen through small gaps, where a few vertices and shadow rays sample visibility.
    pub reciprocity_spread: f64,
    /// The same, weighted: sum of |A_p F_pq - A_q F_qp| over sum of the larger of the two.
    pub reciprocity_mean: f64,
}

impl Residuals {
    /// The report from its samples: the worst energy imbalance, the sampled row sums, and
    /// pairs (A_p F_pq, A_q F_qp) of power transfers that reciprocity says are equal.
    pub fn from_samples(
        energy_imbalance: f64,
        row_sums: &[f64],
        pairs: impl IntoIterator<Item = (f64, f64)>,
    ) -> Self {
        let (mut spread, mut diff, mut scale, mut n) = (0.0f64, 0.0, 0.0, 0);
        for (a, b) in pairs {
            if a.max(b) > 0.0 {
                spread = spread.max((a - b).abs() / a.max(b));
                diff += (a - b).abs();
                scale += a.max(b);
                n += 1;
            }
        }
        Self {
            energy_imbalance,
            row_sum_min: row_sums.iter().copied().fold(f64::INFINITY, f64::min),
            row_sum_mean: row_sums.iter().sum::<f64>() / row_sums.len().max(1) as f64,
            row_sum_max: row_sums.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            reciprocity_pairs: n,
            reciprocity_spread: spread,
            reciprocity_mean: diff / scale.max(f64::MIN_POSITIVE),
        }
    }
}

/// Why [`Solver::run`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finish {
    /// The convergence measure fell below the threshold.
    Converged,
    /// The shot (or iteration) limit was reached.
    MaxShots,
    /// The time budget ran out.
    TimeBudget,
    /// The observer asked to stop.
    Cancelled,
    /// No patch had unshot power left (progressive), or the iterations stopped changing the
    /// solution (hierarchical).
    Exhausted,
}

/// Which radiosity solver runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Progressive refinement (Cohen et al. 1988): shoots the brightest patch to every vertex;
    /// its cost grows as shooters x receivers, so it suits small scenes.
    Progressive,
    /// Hierarchical radiosity with clustering (Hanrahan et al. 1991, Smits et al. 1994):
    /// links between nodes of a hierarchy refined where the transport error is large; its
    /// cost grows about linearly with the scene.
    Hierarchical,
    /// Chosen by the scene's size ([`Method::choose`]).
    Auto,
}

impl Method {
    /// Participating triangles above which [`Method::Auto`] picks the hierarchical solver.
    pub const AUTO_TRIANGLES: usize = 2048;

    /// The solver's name as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Progressive => "progressive",
            Self::Hierarchical => "hierarchical",
            Self::Auto => "auto",
        }
    }

    /// The method that runs for `scene` (itself unless `Auto`), and why, in words.
    pub fn choose(self, scene: &Scene) -> (Self, String) {
        let takes_part = participating(scene);
        let n = scene
            .mesh
            .triangle_object
            .iter()
            .filter(|&&o| takes_part[o as usize])
            .count();
        match self {
            Self::Auto if n > Self::AUTO_TRIANGLES => (
                Self::Hierarchical,
                format!(
                    "{n} triangles take part (more than {}): progressive refinement's cost \
                     grows as shooters x receivers, the hierarchical solver's about linearly",
                    Self::AUTO_TRIANGLES
                ),
            ),
            Self::Auto => (
                Self::Progressive,
                format!(
                    "{n} triangles take part (at most {}): progressive refinement, exact \
                     vertex form factors",
                    Self::AUTO_TRIANGLES
                ),
            ),
            m => (m, "chosen by the options".into()),
        }
    }
}

/// Checks the options both solvers share.
pub(crate) fn check_common(options: &Options) -> Result<(), SolveError> {
    if options.stop.unshot_fraction.is_nan() || options.stop.unshot_fraction < 0.0 {
        return Err(SolveError::Option {
            name: "unshot_fraction",
            problem: "must be >= 0".into(),
        });
    }
    if options.visibility.min == 0 || options.visibility.max < options.visibility.min {
        return Err(SolveError::Option {
            name: "visibility",
            problem: "needs 1 <= min <= max rays".into(),
        });
    }
    if options.visibility.max > MAX_VISIBILITY_RAYS {
        return Err(SolveError::Option {
            name: "visibility",
            problem: format!(
                "{} rays per estimate is more than the {MAX_VISIBILITY_RAYS} that help",
                options.visibility.max
            ),
        });
    }
    Ok(())
}

/// Most shadow rays one visibility estimate may take: beyond this the estimate's noise is
/// far below the discretization error, and the solve's time would only grow.
pub const MAX_VISIBILITY_RAYS: u32 = 4096;

/// Per object: whether it takes part in radiosity (it emits or reflects diffusely); the others
/// only cast shadows.
pub(crate) fn participating(scene: &Scene) -> Vec<bool> {
    scene
        .objects
        .iter()
        .map(|o| {
            o.emission.max_element() > 0.0
                || scene.materials[o.material as usize]
                    .material
                    .reflects_diffusely()
        })
        .collect()
}

/// Settings of the hierarchical solver.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct HierarchicalOptions {
    /// A link is refined while its estimated transport error, in power, exceeds this fraction
    /// of the emitted power (luminance), default 2e-5: the BF refinement oracle.
    #[default(2e-5)]
    pub link_tolerance: f64,
    /// Elements are not split below this longest edge, scene units; default the scene's
    /// diagonal / 200.
    pub min_element_size: Option<f32>,
}

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
    /// pool, every loop is handed over and waited for (tens of microseconds each, thousands of
    /// shots); call it from inside the pool (`rayon::scope(|_| solver.run(..))`, as the CLI
    /// does) to avoid that.
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

    /// Consistency checks on up to `samples` sampled vertices, elements and node pairs; their
    /// cost is bounded by the samples, not by the scene.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        match self {
            Self::Progressive(p) => p.residuals(samples),
            Self::Hierarchical(h) => h.residuals(samples),
        }
    }

    /// The element mesh.
    pub fn mesh(&self) -> &ElementMesh {
        match self {
            Self::Progressive(p) => p.mesh(),
            Self::Hierarchical(h) => h.mesh(),
        }
    }
}
