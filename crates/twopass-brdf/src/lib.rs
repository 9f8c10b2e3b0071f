//! Local illumination models for twopass: Lambert, Phong (as published and normalized),
//! Blinn-Phong, Cook-Torrance (Beckmann D, V-cavity G, exact Fresnel with a complex index of
//! refraction) and the delta lobes of the Whitted tracer (mirror, smooth dielectric, smooth
//! conductor).
//!
//! The crate depends on glam only and never sees a ray or a scene. Directions live in a local
//! shading frame whose +z axis is the surface normal. Colours are linear RGB ([`Rgb`]),
//! reflectances are dimensionless and BRDF values are in 1/sr.
//!
//! A [`Material`] is built from validated parameters and splits into what each pass reads: the
//! diffuse reflectance that radiosity reads ([`Material::diffuse_albedo`]) and the non-diffuse
//! lobe that the ray tracer adds ([`Material::has_non_diffuse`]).
//!
//! ```
//! use twopass_brdf::{Material, Rgb};
//! let white = Material::lambert(Rgb::new(0.725, 0.71, 0.68)).unwrap();
//! assert_eq!(white.diffuse_albedo(), Rgb::new(0.725, 0.71, 0.68));
//! assert!(!white.has_non_diffuse());
//! assert!(Material::lambert(Rgb::new(1.2, 0.5, 0.5)).is_err());
//! ```

mod error;
pub mod ior;
mod material;

pub use error::ParamError;
pub use ior::ComplexIor;
pub use material::{
    BlinnPhongParams, CookTorranceParams, FresnelModel, Lobe, Material, PhongParams,
};

/// Linear RGB triple, one value per channel (reflectance, radiance or power depending on use).
pub type Rgb = glam::Vec3;
