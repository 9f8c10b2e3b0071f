//! Where the diffuse light at a hit comes from: the ambient term of classic Whitted, a
//! radiosity solution read through [`DiffuseRadiance`] (all of it, or its indirect part), or a
//! final gather over the solution per camera sample. The Whitted shading core
//! ([`crate::whitted`]) asks it at every hit; the radiosity-based methods ([`crate::hybrid`])
//! choose which one.

use std::sync::Arc;

use twopass_brdf::Rgb;
use twopass_scene::DiffuseRadiance;

use crate::counters::Tally;
use crate::film::{Layer, Radiance};
use crate::gather::Gatherer;
use crate::integrator::Shading;
use crate::light_tracing::CausticScope;
use crate::sampler::Sampler;

/// Where the diffuse light at a hit comes from.
#[derive(Clone)]
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
    /// Direct diffuse light by shadow rays, the indirect part by `rays` gather rays per camera
    /// sample that read the solution where they land ([`Gatherer`]; the gathered hybrid).
    Gather {
        /// The gather over the solution, shared with the bakes' per-texel gather.
        gatherer: Arc<Gatherer<'a>>,
        /// Gather rays per camera sample and shading point.
        rays: u32,
    },
}

/// Where in a camera sample a shading point lies, for the sources that draw numbers of their
/// own there (the per-pixel gather).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SampleSite<'s> {
    /// The camera sample's numbers.
    pub sampler: &'s Sampler,
    /// The shading point's place in the sample's delta recursion ([`Sampler::fork`]).
    pub site: u64,
}

impl DiffuseSource<'_> {
    /// The caustics the source can leave to a light tracer where the camera sees a diffuse
    /// surface, if any: the focused ones (light through glass) for a solution that separates
    /// them, every one (light through mirrors and glass) for the gather, which then leaves out
    /// the emission its rays reach through a delta path.
    pub(crate) fn caustics_to_leave(&self) -> Option<CausticScope> {
        match self {
            DiffuseSource::Ambient { .. } => None,
            DiffuseSource::Radiosity(solution) | DiffuseSource::RadiosityIndirect(solution) => {
                solution
                    .separates_focused_caustics()
                    .then_some(CausticScope::Focused)
            }
            DiffuseSource::Gather { .. } => Some(CausticScope::FirstDiffuse),
        }
    }

    /// Adds the emission and the diffuse light this source provides at `s` to `r`; returns
    /// whether the direct diffuse light must still be added with shadow rays. With
    /// `without_focused`, the caustics of [`DiffuseSource::caustics_to_leave`] are left out (a
    /// light tracing pass shows them per pixel instead). `at` and `tally` serve the sources that trace rays.
    pub(crate) fn diffuse(
        &self,
        s: &Shading<'_>,
        without_focused: bool,
        at: SampleSite<'_>,
        tally: &mut Tally,
        r: &mut Radiance,
    ) -> bool {
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
            DiffuseSource::Gather { ref gatherer, rays } => {
                r.add(Layer::Emission, s.emitted);
                // The light tracer connects its paths only at surfaces without a delta lobe
                // (at one with a lobe it follows the lobe instead) that the camera sees
                // directly; elsewhere the caustic photons, when there are any, give that
                // light, and the gather rays find it only by chance (fireflies) otherwise.
                let traced = without_focused && s.material.delta().is_none();
                let photons = !traced && gatherer.has_caustic_photons();
                let indirect = gatherer.indirect_per_sample(
                    s,
                    rays,
                    traced || photons,
                    (at.sampler, at.site),
                    tally,
                );
                r.add(Layer::Diffuse, indirect);
                if photons {
                    r.add(Layer::Diffuse, gatherer.caustic_radiance(s));
                }
                true
            }
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
