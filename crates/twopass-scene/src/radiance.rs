//! The boundary between the radiosity solver and the ray tracer: diffuse light leaving a
//! surface point, as a precomputed solution provides it. The tracer takes `&dyn
//! DiffuseRadiance`; `twopass_radiosity::Solution` implements it.

use twopass_brdf::Rgb;

/// Diffuse (view-independent) light leaving the front side of scene surfaces.
pub trait DiffuseRadiance: Sync {
    /// Radiance L = B / pi, W/(m^2 sr) per channel, leaving triangle `triangle` at
    /// `barycentric` toward any direction on its front side: emission plus all reflected
    /// diffuse light, direct and indirect. Zero on triangles the solution does not cover.
    fn radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb;

    /// The indirect part only: diffuse light reflected after two or more bounces from the
    /// emitters, and light that reached the surface through mirrors or glass (no emission, no
    /// direct light: none of what a shadow ray to an emitter finds). A renderer that computes
    /// direct light per pixel adds this to avoid counting the direct light twice.
    fn indirect_radiance(&self, triangle: u32, barycentric: [f32; 3]) -> Rgb;

    /// Whether [`DiffuseRadiance::focused_caustic_radiance`] is known (the solution separated
    /// it); `false` by default.
    fn separates_focused_caustics(&self) -> bool {
        false
    }

    /// The focused caustic part of [`DiffuseRadiance::radiance`] and of
    /// [`DiffuseRadiance::indirect_radiance`], W/(m^2 sr): light that left an emitter and reached
    /// the surface through at least one refraction (L S+ D with a refraction in S+), which an
    /// element mesh shows blurred by the size of its elements; a renderer that shows it per pixel
    /// (light tracing) subtracts this where it does. Zero unless
    /// [`DiffuseRadiance::separates_focused_caustics`].
    fn focused_caustic_radiance(&self, _triangle: u32, _barycentric: [f32; 3]) -> Rgb {
        Rgb::ZERO
    }
}

/// Diffuse light leaving one surface point, estimated there (a final gather) rather than read
/// from a precomputed solution: what a bake fills its lightmap texels and vertices with.
///
/// The light is reflected with the material's own diffuse reflectance (a texture's factor),
/// so that E / pi is recovered by dividing by it whatever the texture holds there: the radiance
/// of a textured surface is [`RadianceEstimate::tinted`] by the texture's value at the point
/// ([`crate::Scene::albedo_tint`]).
/// `twopass_trace::gather::Gatherer` implements it over a [`DiffuseRadiance`] solution.
pub trait RadianceEstimator: Sync {
    /// The estimate at barycentrics `barycentric` of triangle `triangle`, toward any direction
    /// on its front side. `key` names the point's random sequence: the same key, the same
    /// estimate, whichever thread or process computes it and whatever else it computes.
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate;
}

/// One point's estimate of [`RadianceEstimator::estimate`]: radiance in W/(m^2 sr) per
/// channel, split into its parts (emission + direct + indirect = the total).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RadianceEstimate {
    /// Emitted radiance L_e of the surface's front side.
    pub emitted: Rgb,
    /// Light reflected once from the emitters (what shadow rays find).
    pub direct: Rgb,
    /// Every other reflected diffuse light (two or more bounces, through mirrors and glass).
    pub indirect: Rgb,
    /// Standard error of `indirect`'s luminance, W/(m^2 sr): the noise left in it.
    pub indirect_error: f32,
    /// Of the gather rays that hit a surface, the fraction whose first hit was the back of an
    /// opaque surface, in [0, 1]: near 1 for a point inside a closed object (a lightmap
    /// texel whose centre lies where another object intersects its surface), whose value is
    /// meaningless and must not be shown.
    pub back_faces: f32,
    /// Closest-hit rays traced for the estimate.
    pub rays: u64,
    /// Occlusion (shadow) rays traced for the estimate.
    pub shadow_rays: u64,
}

impl RadianceEstimate {
    /// The estimate with its reflected parts (direct, indirect and the error) multiplied by
    /// `tint`, a base colour texture's value at the point; emission unchanged.
    pub fn tinted(self, tint: Rgb) -> Self {
        Self {
            direct: self.direct * tint,
            indirect: self.indirect * tint,
            indirect_error: self.indirect_error * crate::texture::max_channel(tint),
            ..self
        }
    }

    /// Emission + direct + indirect, W/(m^2 sr).
    pub fn total(&self) -> Rgb {
        self.emitted + self.direct + self.indirect
    }
}
