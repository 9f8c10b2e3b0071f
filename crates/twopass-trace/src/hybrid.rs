//! The radiosity-based methods: radiosity alone, the gathered hybrid (Chen et al. 1991's
//! multi-pass method: a final gather over the solution per pixel), the classic two-pass hybrid
//! (Wallace, Cohen & Greenberg 1987) and the hybrid with per-pixel direct light, all on the
//! Whitted shading core of [`crate::whitted`] with a different source of diffuse light.
//!
//! | method | function | diffuse light at a shading point |
//! | --- | --- | --- |
//! | `radiosity` | [`radiosity_only`] | the solution there, nothing traced |
//! | `hybrid` | [`gathered`] | shadow rays to the emitters (chosen per ray by importance), plus gather rays that read the solution where they land ([`crate::gather`]) |
//! | `hybrid-classic` | [`hybrid`] with [`DirectLight::FromSolution`] | the solution there |
//! | `hybrid-direct` | [`hybrid`] with [`DirectLight::PerPixel`] | shadow rays, plus the solution's indirect part there |
//!
//! All but radiosity alone add the glossy lobes against the emitters (shadow rays) and follow
//! delta reflection and refraction from the eye (E S+), shading every surface reached the
//! same way as the camera's first hit.
//!
//! **No double counting** (ARCHITECTURE.md, "The physics, in brief", "The final gather" and
//! "Specular transfer"). The radiosity solution holds all diffuse light, direct and indirect,
//! and emission, including the light that reached a diffuse surface through mirrors and glass
//! (L S+ D, D S+ D: the radiosity pass's specular transfer). Shadow rays stop at mirrors and
//! glass (they are occluders), so they never add a path through them. Which estimator counts
//! which path class (Heckbert's notation from the light; x the diffuse point being shaded, seen
//! from the eye directly or through mirrors and glass):
//!
//! | path class | `hybrid` (gathered) | `hybrid-classic` | `hybrid-direct` |
//! | --- | --- | --- | --- |
//! | L x: emission of x | x's emission | solution at x | x's emission |
//! | L x: direct light | shadow rays at x | solution at x | shadow rays at x |
//! | L ... D y x, y farther than the near distance | gather rays: the solution at y less y's emission | solution at x | solution's indirect part at x |
//! | L ... D y x, y near x | gather rays: more bounces near x (a shadow ray and a ray each, [`crate::gather::NEAR_BOUNCES`] at most), then the solution less emission | solution at x | solution's indirect part at x |
//! | L ... D y S+ x: diffuse light through mirrors and glass | gather rays: the delta path followed, the solution less emission where it ends | solution at x | solution's indirect part at x |
//! | L S+ x, x the camera's first hit | light tracer ([`CausticScope::FirstDiffuse`]); the gather rays leave the emission at a delta path's end out | with glass in S+: light tracer ([`CausticScope::Focused`]), the solution's focused part left out at x; with mirrors only: solution at x | as hybrid-classic, in the indirect part |
//! | L S+ x, x seen through mirrors or glass | caustic photons ([`crate::photons`]); the gather rays leave the emission at a delta path's end out | solution at x (the blurred caustic shown whole) | solution's indirect part at x |
//! | L ... S+ E: seen in mirrors and glass | Whitted recursion, then the above at x | Whitted recursion, then the above | Whitted recursion, then the above |
//! | L G E: glossy highlights | shadow rays | shadow rays | shadow rays |
//! | L ... D G E, L ... S G E | not shown | not shown | not shown |
//!
//! In the gathered hybrid the solution's own value at x is never used: its blockiness and
//! its leaks along contacts never reach the image, and its errors reach it only through one
//! bounce, scaled by rho and averaged over the hemisphere. The gather rays per camera sample
//! ([`WhittedSettings::gather_rays`]) are stratified over the pixel's samples. Their noise is
//! the price: highest where the solution holds small bright patches (a caustic's focus), which
//! few gather rays find. Where the camera sees a diffuse point through mirrors and glass, the
//! light a small emitter sends onto it through a delta path would be found by few gather rays
//! too (fireflies), and no light path can connect to the eye through the delta surface: a
//! caustic photon map ([`crate::photons::CausticPhotons`], built once per integrator) gives
//! that light there, blurred over its nearest photons (at most half an element edge). On a scene whose materials are all Lambertian the classic hybrid
//! traces nothing and computes exactly what radiosity alone does (the same floating-point
//! operations: the images are bit-identical, and a test says so).
//!
//! **Per-pixel caustics.** Light that an emitter sends through mirrors and glass onto a diffuse
//! surface (L S+ D) is focused more sharply than the element mesh can show, and gather rays
//! find it only by chance. Where the camera sees a diffuse surface first, the render loop adds
//! a light tracing pass of those paths ([`WhittedSettings::caustic_paths`] light paths per
//! camera sample): all of them for the gathered hybrid ([`CausticScope::FirstDiffuse`], when
//! the scene has a mirror or glass), those through glass for the classic hybrids
//! ([`CausticScope::Focused`], when the scene has glass and the solution separates that
//! light, [`DiffuseRadiance::separates_focused_caustics`]); the hybrids leave that light out
//! there, as the table says.
//!
//! The solution is read only through [`DiffuseRadiance`]; this crate does not depend on the
//! solver.

use std::sync::Arc;

use twopass_scene::{DiffuseRadiance, Scene};

use crate::diffuse::DiffuseSource;
use crate::emitters::Lights;
use crate::gather::{GatherSettings, Gatherer};
use crate::light_tracing::{CausticScope, LightPaths, LightTracer, LightTracingSettings};
use crate::photons::PhotonSettings;
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
    /// From the solution, which holds all diffuse light: the classic hybrid
    /// (`hybrid-classic`).
    FromSolution,
    /// From shadow rays at every shading point (Chen et al. 1991; sharp shadows without a
    /// finer mesh), the solution's [`DiffuseRadiance::indirect_radiance`] for the rest: the
    /// hybrid with per-pixel direct light (`hybrid-direct`).
    PerPixel,
}

/// The gathered hybrid (`hybrid`): at every diffuse shading point (the camera's first hit and
/// every one reached through mirrors and glass), direct light by shadow rays to the emitters
/// ([`crate::integrator::direct_light`]: the grid's rays shared by all, each ray's emitter
/// chosen by its importance there) and the indirect light by [`WhittedSettings::gather_rays`] gather rays per camera sample
/// that read `solution` where they land ([`Gatherer`], the final gather of the bakes), plus
/// the glossy lobes against the emitters and delta reflection and refraction paths.
pub fn gathered<'a>(
    scene: &'a Scene,
    solution: &'a dyn DiffuseRadiance,
    settings: WhittedSettings,
) -> Whitted<'a> {
    let gatherer = Gatherer::new(
        scene,
        solution,
        GatherSettings {
            max_depth: settings.max_depth,
            // The caustics at the diffuse points seen through mirrors and glass (where the
            // light tracer cannot connect) exist only when delta paths are followed.
            photons: (settings.max_depth > 0).then(PhotonSettings::default),
            ..GatherSettings::default()
        },
    );
    let source = DiffuseSource::Gather {
        gatherer: Arc::new(gatherer),
        rays: settings.gather_rays,
    };
    radiosity_based(scene, source, true, settings, "hybrid")
}

/// The classic two-pass hybrids: the solution's diffuse light (all of it, or its indirect part with
/// `direct` light per pixel), plus the glossy lobes against the emitters (shadow rays) and
/// delta reflection and refraction paths.
pub fn hybrid<'a>(
    scene: &Scene,
    solution: &'a dyn DiffuseRadiance,
    direct: DirectLight,
    settings: WhittedSettings,
) -> Whitted<'a> {
    let (source, name) = match direct {
        DirectLight::FromSolution => (DiffuseSource::Radiosity(solution), "hybrid-classic"),
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
    // Per-pixel caustics: only where the view-dependent terms are traced, the source can
    // leave that light out, and the scene has a surface to send it: glass for the focused
    // caustics, a mirror or glass for all of them (the light tracer needs a specular target).
    let caustics = source
        .caustics_to_leave()
        .filter(|&scope| {
            view_dependent
                && settings.caustic_paths > 0.0
                && (scope != CausticScope::Focused
                    || scene.objects.iter().any(|o| {
                        scene.materials[o.material as usize]
                            .material
                            .is_dielectric()
                    }))
        })
        .and_then(|scope| {
            LightTracer::new(
                scene,
                LightTracingSettings {
                    paths: LightPaths::PerSample(settings.caustic_paths),
                    max_depth: settings.max_depth,
                    ..LightTracingSettings::new(scope)
                },
            )
        });
    Whitted {
        lights: Lights::new(scene),
        source,
        view_dependent,
        settings,
        name,
        caustics,
    }
}
