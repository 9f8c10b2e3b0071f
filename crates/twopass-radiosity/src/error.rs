//! Why a solve cannot start ([`SolveError`]).

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
        /// [`Options::memory_limit`](crate::options::Options::memory_limit), bytes.
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
