//! The radiosity-based methods: radiosity alone, the two-pass hybrid (Wallace, Cohen &
//! Greenberg 1987) and the hybrid with per-pixel direct light (Chen et al. 1991), all on the
//! Whitted shading core of [`crate::whitted`] with a different source of diffuse light.
//!
//! **No double counting** (ARCHITECTURE.md, "The physics, in brief" and "Specular transfer"): the
//! radiosity solution holds all diffuse light, direct and indirect, and emission, including the
//! light that reached a diffuse surface through mirrors and glass (L S+ D, D S+ D: the radiosity
//! pass's specular transfer). The hybrid adds only what radiosity cannot hold: glossy lobes
//! against the emitters and delta reflection and refraction paths from the eye (E S+ D), whose
//! rays take the radiosity where they land. Shadow rays stop at mirrors and glass (they are
//! occluders), so they never add a path through them again; the per-pixel direct light of
//! hybrid-direct replaces only the solution's direct part, which holds no such path either. On a scene whose materials are all Lambertian none of those
//! terms exists, no shadow ray is traced and the hybrid computes exactly what radiosity alone does
//! (the same floating-point operations: the images are bit-identical, and a test says so).
//!
//! **Per-pixel caustics.** Light that an emitter sends through glass onto a diffuse surface
//! (L S+ D with a refraction) is focused more sharply than the element mesh can show. When the
//! solution separates it ([`DiffuseRadiance::separates_focused_caustics`]) and the scene has a
//! refracting surface, the hybrids show, where the camera sees a diffuse surface first, the
//! solution without that part, and the render loop adds a light tracing pass of exactly those
//! paths ([`crate::light_tracing::CausticScope::Focused`],
//! [`WhittedSettings::caustic_paths`] light paths per camera sample): counted once, per pixel.
//! Seen through a mirror or glass (deeper in the recursion) the solution is shown whole.
//!
//! The solution is read only through [`DiffuseRadiance`]; this crate does not depend on the
//! solver.

use twopass_scene::{DiffuseRadiance, Scene};

use crate::diffuse::DiffuseSource;
use crate::emitters::Lights;
use crate::light_tracing::{CausticScope, LightTracer, LightTracingSettings};
use crate::whitted::{Whitted, WhittedSettings};

/// Radiosity alone, for rendering `scene`: camera rays shaded with the solution (interpolated per
/// vertex); mirrors and glass show as their diffuse part, as in the classic picture. No shadow or
/// secondary rays.
pub fn radiosity_only<'a>(scene: &Scene, solution: &'a dyn DiffuseRadiance) -> Whitted<'a> {
    let settings = WhittedSettings::default();
    radiosity_based(
        scene,
        DiffuseSource::Radiosity(solution),
        false,
        settings,
        "radiosity",
    )
}

/// Where the two-pass hybrid takes direct diffuse light from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DirectLight {
    /// From the solution, which holds all diffuse light: the hybrid (`hybrid`).
    FromSolution,
    /// From shadow rays at every shading point (Chen et al. 1991; sharp shadows without a
    /// finer mesh), the solution's [`DiffuseRadiance::indirect_radiance`] for the rest: the
    /// hybrid with per-pixel direct light (`hybrid-direct`).
    PerPixel,
}

/// The two-pass hybrid: the solution's diffuse light (all of it, or its indirect part with
/// `direct` light per pixel), plus the glossy lobes against the emitters (shadow rays) and
/// delta reflection and refraction paths.
pub fn hybrid<'a>(
    scene: &Scene,
    solution: &'a dyn DiffuseRadiance,
    direct: DirectLight,
    settings: WhittedSettings,
) -> Whitted<'a> {
    let (source, name) = match direct {
        DirectLight::FromSolution => (DiffuseSource::Radiosity(solution), "hybrid"),
        DirectLight::PerPixel => (DiffuseSource::RadiosityIndirect(solution), "hybrid-direct"),
    };
    radiosity_based(scene, source, true, settings, name)
}

/// The Whitted core lighting `scene` with diffuse light from `source`, with the view-dependent
/// terms (glossy lobes, delta paths) or without.
fn radiosity_based<'a>(
    scene: &Scene,
    source: DiffuseSource<'a>,
    view_dependent: bool,
    settings: WhittedSettings,
    name: &'static str,
) -> Whitted<'a> {
    // Per-pixel focused caustics: only where the view-dependent terms are traced, the solution
    // separates that light, and the scene has a refracting surface to focus it.
    let caustics = (view_dependent
        && settings.caustic_paths > 0.0
        && source.separates_focused_caustics()
        && scene.objects.iter().any(|o| {
            scene.materials[o.material as usize]
                .material
                .is_dielectric()
        }))
    .then(|| {
        LightTracer::new(
            scene,
            LightTracingSettings {
                paths_per_sample: settings.caustic_paths,
                max_depth: settings.max_depth,
                ..LightTracingSettings::new(CausticScope::Focused)
            },
        )
    })
    .flatten();
    Whitted {
        lights: Lights::new(scene),
        source,
        view_dependent,
        settings,
        name,
        caustics,
    }
}
