//! The settings of a radiosity solve, shared by both solvers: [`Options`] and its parts
//! ([`Stop`], [`AdaptiveOptions`], [`HierarchicalOptions`], [`SpecularOptions`]), the
//! [`Method`] that runs, the limits the options must keep, and which objects take part.

use std::time::Duration;

use smart_default::SmartDefault;
use twopass_scene::Scene;

use crate::error::SolveError;
use crate::form_factor::VisibilityRays;

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
    /// Light carried through mirrors and glass onto diffuse surfaces (both solvers), or `None` to
    /// treat specular objects as absorbers. It runs only where [`crate::specular::decide`] says the
    /// scene needs it.
    #[default(Some(SpecularOptions::default()))]
    pub specular: Option<SpecularOptions>,
}

/// Smallest [`HierarchicalOptions::link_tolerance`]: f32's relative precision (`f32::EPSILON`,
/// about 1.2e-7). A link's transport and error are stored as f32 and summed into its
/// receiver in f32 steps, so an error below this fraction of the emitted power is below the
/// rounding of the very quantities the oracle compares: refining for it changes nothing the
/// solution can show, while the links grow toward every pair of the smallest elements
/// (quadratic in their number, without end in practice).
pub const MIN_LINK_TOLERANCE: f64 = f32::EPSILON as f64;

/// Settings of the hierarchical solver.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct HierarchicalOptions {
    /// A link is refined while its estimated transport error, in power, exceeds this fraction
    /// of the emitted power (luminance), default 2e-5: the BF refinement oracle. At least
    /// [`MIN_LINK_TOLERANCE`].
    #[default(2e-5)]
    pub link_tolerance: f64,
    /// Elements are not split below this longest edge, scene units; default the scene's
    /// diagonal / 200.
    pub min_element_size: Option<f32>,
}

/// Settings of the specular transfer ([`crate::Options::specular`]).
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpecularOptions {
    /// Rays a shot of the whole emitted power casts toward the specular objects (progressive
    /// refinement; the hierarchical solver spreads as many over the leaves whose exitance grew
    /// since it last shot, in proportion to that growth); a shot of a
    /// fraction of it casts that fraction (at least [`SpecularOptions::MIN_RAYS`]), so every
    /// ray carries about the same power. Rounded up to a square number per shot.
    #[default(1 << 20)]
    pub rays: u32,
    /// Most delta bounces a ray follows (reflections and refractions) before it is dropped.
    #[default(16)]
    pub max_depth: u32,
}

impl SpecularOptions {
    /// Fewest rays a shot casts toward the specular objects (a 4 x 4 grid).
    pub const MIN_RAYS: u32 = 16;
    /// Most rays one shot may cast (a 2048 x 2048 grid).
    pub const MAX_RAYS: u32 = 1 << 22;
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
        let n = (0..scene.mesh.triangle_count() as u32)
            .filter(|&t| takes_part[scene.mesh.object_of(t) as usize])
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

/// Most shadow rays one visibility estimate may take ([`VisibilityRays::max`], a 64 x 64
/// grid): beyond this the estimate's noise is far below the discretization error, and the
/// solve's time would only grow. Both solvers refuse options above it
/// ([`SolveError::Option`]); front ends check their settings against it.
pub const MAX_VISIBILITY_RAYS: u32 = 4096;

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
