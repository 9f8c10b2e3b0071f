//! How radiance becomes glTF `COLOR_0`.

use glam::Vec3;
use serde::{Deserialize, Serialize};
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance;
use twopass_radiosity::Solution;

/// How radiance becomes glTF `COLOR_0`, a linear multiplier that engines expect in [0, 1]:
/// `COLOR_0 = min(1, exposure * L)` per linear RGB channel, with `L = B / pi` the radiance
/// leaving the surface in W/(m^2 sr). Negative values (rounding) become 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColorMapping {
    /// Multiplier on radiance, sr m^2 / W (1 / the radiance that maps to white).
    pub exposure: f32,
}

/// Percentile of the vertices' radiance luminance that [`ColorMapping::auto`] maps to 1.
pub const AUTO_EXPOSURE_PERCENTILE: f64 = 0.99;

impl ColorMapping {
    /// An exposure that maps the 99th percentile (over vertices) of the displayed radiance's
    /// luminance (Rec. 709 weights) to 1, so that only the brightest percent (typically the
    /// emitters) saturates. 1 when everything is black.
    pub fn auto(solution: &Solution) -> Self {
        let mut lum: Vec<f32> = solution
            .vertex_radiosity()
            .iter()
            .map(|b| luminance(*b) * std::f32::consts::FRAC_1_PI)
            .filter(|l| l.is_finite() && *l > 0.0)
            .collect();
        if lum.is_empty() {
            return Self { exposure: 1.0 };
        }
        let k = ((lum.len() - 1) as f64 * AUTO_EXPOSURE_PERCENTILE).round() as usize;
        let (_, &mut at, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
        Self { exposure: 1.0 / at }
    }

    /// `COLOR_0` of a radiance `l` (W/(m^2 sr)), and whether a channel was clipped at 1.
    pub fn color(&self, l: Rgb) -> (Rgb, bool) {
        let c = (l * self.exposure).max(Vec3::ZERO);
        (c.min(Vec3::ONE), c.max_element() > 1.0)
    }

    /// `COLOR_0` of each radiance in `radiance`, counting the vertices with a clipped channel
    /// in `clamped`.
    pub fn colors(&self, radiance: &[Rgb], clamped: &mut usize) -> Vec<Rgb> {
        radiance
            .iter()
            .map(|l| {
                let (c, clipped) = self.color(*l);
                *clamped += usize::from(clipped);
                c
            })
            .collect()
    }

    /// The mapping as a formula, as recorded in the manifest and the glTF asset extras.
    pub const FORMULA: &'static str = "COLOR_0 = min(1, exposure * L) per linear RGB channel, \
         L = B / pi the radiance leaving the surface in W/(m^2 sr)";
}

/// The radiance a solution displays at each element-mesh vertex, W/(m^2 sr) per linear RGB
/// channel, HDR, with its parts: `radiance = (B + ambient) / pi` (what [`ColorMapping`] maps),
/// `direct` the light reflected once from the emitters, `indirect` the light reflected two or
/// more times or carried through mirrors and glass, plus the ambient estimate of a partial
/// solve (as
/// [`DiffuseRadiance::indirect_radiance`](twopass_scene::DiffuseRadiance::indirect_radiance)).
/// `radiance - direct - indirect` is the emitted radiance (zero off the emitters).
#[derive(Debug, Clone, PartialEq)]
pub struct RadianceParts {
    /// Total displayed radiance per vertex.
    pub radiance: Vec<Rgb>,
    /// Once-reflected part per vertex.
    pub direct: Vec<Rgb>,
    /// Part reflected two or more times (ambient included) per vertex.
    pub indirect: Vec<Rgb>,
}

impl RadianceParts {
    /// The parts of `solution`, from its per-vertex radiosity split (W/m^2) divided by pi.
    pub fn of(solution: &Solution) -> Self {
        let to_l = std::f32::consts::FRAC_1_PI;
        Self {
            radiance: solution
                .vertex_radiosity()
                .iter()
                .map(|b| *b * to_l)
                .collect(),
            direct: solution.direct().iter().map(|b| *b * to_l).collect(),
            indirect: solution
                .indirect()
                .iter()
                .zip(solution.ambient())
                .map(|(i, a)| (*i + *a) * to_l)
                .collect(),
        }
    }
}
