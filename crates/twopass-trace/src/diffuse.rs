//! Where the diffuse light at a hit comes from: the ambient term of classic Whitted, or a
//! radiosity solution read through [`DiffuseRadiance`] (all of it, or its indirect part). The
//! Whitted shading core ([`crate::whitted`]) asks it at every hit; the radiosity-based methods
//! ([`crate::hybrid`]) choose which one.

use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;

use crate::film::{Layer, Radiance};
use crate::integrator::Shading;

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
    /// Whether the source is a solution that separates its focused caustic part.
    pub(crate) fn separates_focused_caustics(&self) -> bool {
        match *self {
            DiffuseSource::Ambient { .. } => false,
            DiffuseSource::Radiosity(solution) | DiffuseSource::RadiosityIndirect(solution) => {
                solution.separates_focused_caustics()
            }
        }
    }

    /// Adds the emission and the diffuse light this source provides at `s` to `r`; returns
    /// whether the direct diffuse light must still be added with shadow rays. With
    /// `without_focused`, the solution's focused caustic part is left out (a light tracing
    /// pass shows it per pixel instead).
    pub(crate) fn diffuse(&self, s: &Shading<'_>, without_focused: bool, r: &mut Radiance) -> bool {
        // Leaves the focused part out of `l` when asked (never below zero).
        let less_focused = |solution: &dyn DiffuseRadiance, l: Rgb| {
            if without_focused {
                let f = solution.focused_caustic_radiance(s.hit.point.triangle, s.hit.barycentric);
                (l - f).max(Rgb::ZERO)
            } else {
                l
            }
        };
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
                    r.add(Layer::Diffuse, less_focused(solution, diffuse));
                }
                false
            }
            DiffuseSource::RadiosityIndirect(solution) => {
                r.add(Layer::Emission, s.emitted);
                if s.hit.front_face {
                    let indirect =
                        solution.indirect_radiance(s.hit.point.triangle, s.hit.barycentric);
                    r.add(Layer::Diffuse, less_focused(solution, indirect));
                }
                true
            }
        }
    }
}
