//! Why a solve cannot start, or its result cannot be used ([`SolveError`]).

/// Why a solve cannot start, or why its result cannot be used.
#[derive(Debug, Clone, PartialEq)]
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
        /// [`Options::memory_limit`](crate::options::Options::memory_limit), bytes.
        limit: u64,
    },
    /// The solve created power: its absorbed plus escaped power exceeds the emitted by more
    /// than [`ENERGY_TOLERANCE`](crate::report::ENERGY_TOLERANCE)
    /// ([`crate::Solver::check_energy`]).
    EnergyCreated {
        /// The solver that ran, as the command line names it (`progressive`, `hierarchical`).
        solver: &'static str,
        /// [`Energy::created_fraction`](crate::report::Energy::created_fraction): power
        /// created, as a fraction of the emitted.
        created: f64,
        /// The tolerance it exceeds, a fraction of the emitted power.
        tolerance: f64,
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
            Self::EnergyCreated {
                solver,
                created,
                tolerance,
            } => write!(
                f,
                "the {solver} solver created {:.1} % of the emitted power (absorbed plus escaped \
                 exceed the emitted by more than the {:.0} % tolerated): surfaces closer than \
                 the element mesh resolves, such as a light almost touching a wall or coincident \
                 copies of a surface; its solution is refused. Move them apart, or remove the \
                 copies",
                100.0 * created,
                100.0 * tolerance
            ),
        }
    }
}

impl std::error::Error for SolveError {}
