//! The radiosity-based methods: radiosity alone, the two-pass hybrid (Wallace, Cohen &
//! Greenberg 1987) and the hybrid with per-pixel direct light (Chen et al. 1991), all on the
//! Whitted shading core of [`crate::whitted`] with a different source of diffuse light.
//!
//! **No double counting** (ARCHITECTURE.md, "The physics, in brief"): the radiosity solution holds all diffuse light, direct
//! and indirect, and emission. The hybrid adds only what radiosity cannot hold: glossy lobes
//! against the emitters and delta reflection and refraction paths, whose rays take the
//! radiosity where they land. On a scene whose materials are all Lambertian none of those terms
//! exists, no shadow ray is traced and the hybrid computes exactly what radiosity alone does
//! (the same floating-point operations: the images are bit-identical, and a test says so).
//!
//! The solution is read only through [`DiffuseRadiance`]; this crate does not depend on the
//! solver.

use twopass_brdf::Rgb;
use twopass_scene::{DiffuseRadiance, Scene};

use crate::film::{Layer, Radiance};
use crate::integrator::{Lights, Shading};
use crate::whitted::{Whitted, WhittedSettings};

/// Where the diffuse light at a hit comes from.
#[derive(Clone, Copy)]
pub enum DiffuseSource<'a> {
    /// Classic Whitted: direct light by shadow rays plus the ambient term k_a I_amb, with
    /// `ambient` = I_amb in W/(m^2 sr) per channel.
    Ambient {
        /// I_amb, W/(m^2 sr) per channel.
        ambient: Rgb,
    },
    /// All diffuse light and emission from the solution (radiosity alone, hybrid).
    Radiosity(&'a dyn DiffuseRadiance),
    /// Direct diffuse light by shadow rays, the indirect part from the solution
    /// (hybrid with per-pixel direct light).
    RadiosityIndirect(&'a dyn DiffuseRadiance),
}

impl DiffuseSource<'_> {
    /// Adds the emission and the diffuse light this source provides at `s` to `r`; returns
    /// whether the direct diffuse light must still be added with shadow rays.
    pub(crate) fn diffuse(&self, s: &Shading<'_>, r: &mut Radiance) -> bool {
        match *self {
            DiffuseSource::Ambient { ambient } => {
                r.add(Layer::Emission, s.emitted);
                if s.hit.front_face {
                    r.add(Layer::Ambient, s.material.ambient() * ambient);
                }
                true
            }
            DiffuseSource::Radiosity(solution) => {
                if s.hit.front_face {
                    // The solution's radiance includes the emission L_e = E / pi: split it off
                    // so the layers say which is which (and still sum to the solution).
                    let l = solution.radiance(s.hit.point.triangle, s.hit.barycentric);
                    let diffuse = (l - s.emitted).max(Rgb::ZERO);
                    r.add(Layer::Emission, l - diffuse);
                    r.add(Layer::Diffuse, diffuse);
                }
                false
            }
            DiffuseSource::RadiosityIndirect(solution) => {
                r.add(Layer::Emission, s.emitted);
                if s.hit.front_face {
                    r.add(
                        Layer::Diffuse,
                        solution.indirect_radiance(s.hit.point.triangle, s.hit.barycentric),
                    );
                }
                true
            }
        }
    }
}

/// Radiosity alone, for rendering `scene`: camera rays shaded with the solution (interpolated per vertex); mirrors and
/// glass show as their diffuse part, as in the classic picture. No shadow or secondary rays.
pub fn radiosity_only<'a>(scene: &Scene, solution: &'a dyn DiffuseRadiance) -> Whitted<'a> {
    Whitted {
        lights: Lights::new(scene),
        source: DiffuseSource::Radiosity(solution),
        view_dependent: false,
        settings: WhittedSettings::default(),
        name: "radiosity",
    }
}

/// The two-pass hybrid: the solution for all diffuse light, plus the glossy lobes against the
/// emitters (shadow rays) and delta reflection and refraction paths.
pub fn hybrid<'a>(
    scene: &Scene,
    solution: &'a dyn DiffuseRadiance,
    settings: WhittedSettings,
) -> Whitted<'a> {
    Whitted {
        lights: Lights::new(scene),
        source: DiffuseSource::Radiosity(solution),
        view_dependent: true,
        settings,
        name: "hybrid",
    }
}

/// The hybrid with per-pixel direct light (Chen et al. 1991): direct diffuse light with shadow
/// rays at every shading point (sharp shadows without a finer mesh), the solution's
/// [`DiffuseRadiance::indirect_radiance`] for the rest, plus the hybrid's view-dependent terms.
pub fn hybrid_direct<'a>(
    scene: &Scene,
    solution: &'a dyn DiffuseRadiance,
    settings: WhittedSettings,
) -> Whitted<'a> {
    Whitted {
        lights: Lights::new(scene),
        source: DiffuseSource::RadiosityIndirect(solution),
        view_dependent: true,
        settings,
        name: "hybrid-direct",
    }
}
