//! Local illumination models for twopass: Lambert, Phong (as published and normalized),
//! Blinn-Phong, Cook-Torrance (Beckmann D, V-cavity G, exact Fresnel with a complex index of
//! refraction) and the delta lobes of the Whitted tracer (mirror, smooth dielectric, smooth
//! conductor), with importance sampling and numerical plausibility checks.
//!
//! The crate depends on glam only and never sees a ray or a scene. Directions live in a local
//! shading frame whose +z axis is the surface normal ([`frame`]), both pointing away from the
//! surface (`wo` to the viewer, `wi` to the light). Colours are linear RGB ([`Rgb`]),
//! reflectances are dimensionless, BRDF values are in 1/sr and **exclude** the cosine factor,
//! densities are per steradian.
//!
//! A [`Material`] is built from validated parameters and splits into what each pass reads: the
//! diffuse reflectance that radiosity reads ([`Material::diffuse_albedo`]), the non-diffuse
//! part that the ray tracer adds ([`Material::eval_non_diffuse`], [`Material::delta`]) and
//! whether there is any ([`Material::has_non_diffuse`]).
//!
//! ```
//! use twopass_brdf::{Brdf, CookTorranceParams, FresnelModel, Material, ComplexIor, Rgb};
//! use twopass_brdf::{check, interface, quadrature::Quadrature};
//! use glam::{Vec2, Vec3};
//!
//! let white = Material::lambert(Rgb::new(0.725, 0.71, 0.68)).unwrap();
//! assert_eq!(white.diffuse_albedo(), Rgb::new(0.725, 0.71, 0.68));
//! assert!(!white.has_non_diffuse());
//! assert!(Material::lambert(Rgb::new(1.2, 0.5, 0.5)).is_err());
//!
//! let gold = Material::cook_torrance(CookTorranceParams {
//!     diffuse: Rgb::ZERO,
//!     specular: Rgb::ONE,
//!     roughness: 0.2,
//!     ior: ComplexIor::conductor("gold").unwrap(),
//!     fresnel: FresnelModel::Exact,
//! })
//! .unwrap();
//! let (wo, wi) = (Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.6, 0.0, 0.8));
//! let f = gold.eval(wo, wi); // 1/sr, without the cosine
//! assert!(f.x > f.z); // gold reflects red more than blue
//! assert_eq!(gold.eval_diffuse(wo, wi), Rgb::ZERO); // nothing for radiosity
//! let s = gold.sample(wo, Vec2::new(0.3, 0.7)).unwrap();
//! assert!(s.wi.z > 0.0 && s.pdf > 0.0);
//! // energy albedo for light from 30 degrees, by quadrature: at most 1
//! let model = gold.model().unwrap();
//! let a = interface::incident_albedo(&model, check::direction_at_deg(30.0), Quadrature::default());
//! assert!(a.max_element() <= 1.0);
//! ```

pub mod beckmann;
pub mod blinn_phong;
pub mod check;
pub mod colour;
pub mod cook_torrance;
pub mod delta;
mod error;
pub mod frame;
pub mod fresnel;
pub mod interface;
pub mod ior;
pub mod lambert;
mod material;
pub mod model;
pub mod modified_phong;
mod param;
pub mod phong;
pub mod quadrature;
pub mod random;
pub mod sample;
pub mod v_cavity;

pub use colour::Rgb;
pub use error::ParamError;
pub use fresnel::FresnelModel;
pub use ior::ComplexIor;
pub use material::{BlinnPhongParams, CookTorranceParams, Lobe, Material, PhongParams};
pub use model::{Brdf, BrdfModel, BrdfSample, SampleKind};
