//! The view-dependent pass of twopass: the integrators and the render loop.
//!
//! - [`Whitted`]: Whitted-style ray tracing alone (shadow rays to the area emitters and the
//!   lamps, the local models of twopass-brdf, the Phong ambient term in place of
//!   interreflection, mirror reflection and refraction followed recursively).
//! - [`hybrid::radiosity_only`], [`hybrid::gathered`] (the hybrid: a final gather over the
//!   solution per pixel, [`gather`]), [`hybrid::hybrid`] (the classic hybrids, with
//!   [`hybrid::DirectLight`]): the radiosity-based methods, reading a solution through
//!   [`twopass_scene::DiffuseRadiance`] only.
//! - [`Reference`]: a path tracer with next-event estimation, MIS and Russian roulette, the
//!   ground truth.
//! - [`render()`]: the one render loop (tiles, rayon, per-(seed, pixel, sample) random streams,
//!   progress, non-finite sample counting), producing named linear RGB [`Layer`]s that sum to
//!   the image.
//!
//! Every integrator shows the sky ([`twopass_scene::Sky`]) on rays that leave the scene and
//! samples its sun and dome with shadow rays ([`sky`]).
//!
//! Units: radiance in W/(m^2 sr) per linear RGB channel with areas in the scene's units (the
//! emitters' L_e is given that way); BRDF values in 1/sr; pixel positions in pixels from the
//! top-left corner.
//!
//! ```no_run
//! use twopass_trace::{RenderProgress, RenderSettings, Whitted, WhittedSettings, render};
//! let (scene, _) = twopass_scene::load("scenes/cornell-spheres.toml")?;
//! let camera = scene.camera.with_resolution(Some(64), None);
//! let ambient = twopass_trace::whitted::ambient_estimate(&scene);
//! let whitted = Whitted::new(&scene, ambient, WhittedSettings::default());
//! let out = render(&scene, &camera, &whitted, &RenderSettings::default(), &RenderProgress::new());
//! let image = out.layers.composite();
//! eprintln!("{} rays/s, {} non-finite samples", out.stats.rays_per_second(), out.stats.non_finite);
//! # let _ = image;
//! # Ok::<(), twopass_scene::SceneError>(())
//! ```

pub mod budget;
pub mod counters;
pub mod diffuse;
pub mod emitters;
pub mod film;
pub mod gather;
pub mod hybrid;
pub mod integrator;
pub mod light_plan;
pub mod light_tracing;
pub mod photons;
pub mod reference;
pub mod render;
pub mod sampler;
pub mod sky;
pub mod split_plan;
pub mod whitted;

pub use budget::{BUDGET_FLOOR, BUDGET_SMOOTHING, SampleBudget};
pub use film::{Layer, LayerImages, Radiance};
pub use render::{
    AdaptiveSampling, LightShare, RenderOutput, RenderSettings, RenderStats, ShareOutput,
    TileShare, add_light, light_image, render, render_budgeted, render_share, tile_origins,
};

pub use counters::{RenderProgress, Tally};
pub use emitters::Lights;
pub use integrator::{Integrator, SampleState};
pub use light_plan::LightPlan;
pub use light_tracing::{
    CausticScope, LightImage, LightPaths, LightTracer, LightTracingSettings, Splat,
};
pub use reference::{Caustics, Reference, ReferenceSettings};
pub use sampler::Sampler;
pub use split_plan::{PathSplits, SplitPlan};
pub use whitted::{Whitted, WhittedSettings};
