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
