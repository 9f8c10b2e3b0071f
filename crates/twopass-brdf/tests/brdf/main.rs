//! Integration tests of twopass-brdf (one binary, one link step): golden values, quadrature
//! accuracy, plausibility, sampling (chi-square), extremes and property tests.

mod extremes;
mod golden;
mod plausibility;
mod sampling;

use glam::Vec3;
use twopass_brdf::{
    BlinnPhongParams, BrdfModel, ComplexIor, CookTorranceParams, FresnelModel, Material,
    PhongParams, Rgb,
};

pub(crate) fn lambert(rho: f32) -> BrdfModel {
    Material::lambert(Rgb::splat(rho)).unwrap().model().unwrap()
}

pub(crate) fn phong(rho: f32, ks: f32, n: f32, normalized: bool) -> BrdfModel {
    Material::phong(PhongParams {
        diffuse: Rgb::splat(rho),
        specular: Rgb::splat(ks),
        exponent: n,
        ambient: Rgb::ZERO,
        normalized,
    })
    .unwrap()
    .model()
    .unwrap()
}

pub(crate) fn blinn(rho: f32, ks: f32, n: f32, normalized: bool) -> BrdfModel {
    Material::blinn_phong(BlinnPhongParams {
        diffuse: Rgb::splat(rho),
        specular: Rgb::splat(ks),
        exponent: n,
        normalized,
    })
    .unwrap()
    .model()
    .unwrap()
}

pub(crate) fn cook(rho: f32, s: f32, m: f32, ior: ComplexIor, fresnel: FresnelModel) -> BrdfModel {
    Material::cook_torrance(CookTorranceParams {
        diffuse: Rgb::splat(rho),
        specular: Rgb::splat(s),
        roughness: m,
        ior,
        fresnel,
    })
    .unwrap()
    .model()
    .unwrap()
}

/// The measured complex index of the metal `name` (see [`ComplexIor::conductor`]).
pub(crate) fn conductor(name: &str) -> ComplexIor {
    ComplexIor::conductor(name).unwrap()
}

/// The real index `eta` of a dielectric, as a complex index.
pub(crate) fn dielectric(eta: f32) -> ComplexIor {
    ComplexIor::dielectric(eta).unwrap()
}

/// An index whose Fresnel reflectance is 1 to within 4e-6 at every angle: isolates D and G.
pub(crate) fn white_ior() -> ComplexIor {
    ComplexIor::new(Rgb::ONE, Rgb::splat(1e3)).unwrap()
}

pub(crate) fn dir_deg(theta: f32, phi: f32) -> Vec3 {
    let (st, ct) = theta.to_radians().sin_cos();
    let (sp, cp) = phi.to_radians().sin_cos();
    Vec3::new(st * cp, st * sp, ct)
}

/// Where failing tests dump their tables: `<target dir>/chi2/` (the test binary lives in
/// `<target dir>/<profile>/deps/`).
pub(crate) fn chi2_dir() -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap();
    exe.ancestors().nth(3).unwrap().join("chi2")
}
