//! The closed set of glossy reflection models ([`BrdfModel`], pbrt's tagged union), dispatching
//! to each model's [`Brdf`] implementation. The interface and its conventions are in
//! [`crate::interface`].

use glam::{Vec2, Vec3};

use crate::Rgb;
use crate::blinn_phong::BlinnPhong;
use crate::cook_torrance::CookTorrance;
pub use crate::interface::{Brdf, BrdfSample, SampleKind};
use crate::lambert::Lambert;
use crate::modified_phong::ModifiedPhong;
use crate::phong::Phong;

/// The closed set of glossy reflection models (pbrt's tagged union): dispatch without trait
/// objects. Delta lobes are not BRDFs with a value and live in [`crate::delta`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BrdfModel {
    /// Lambert, rho / pi.
    Lambert(Lambert),
    /// Phong as published (1975): not reciprocal, not energy conserving.
    Phong(Phong),
    /// Normalized modified Phong (Lafortune & Willems 1994).
    ModifiedPhong(ModifiedPhong),
    /// Blinn-Phong (1977), classic or normalized.
    BlinnPhong(BlinnPhong),
    /// Cook-Torrance (1981) with Beckmann D, V-cavity G and Fresnel.
    CookTorrance(CookTorrance),
}

impl BrdfModel {
    /// A short name for tables: `lambert`, `phong`, `modified_phong`, `blinn_phong`,
    /// `blinn_phong_normalized`, `cook_torrance`.
    pub fn name(&self) -> &'static str {
        match self {
            BrdfModel::Lambert(_) => "lambert",
            BrdfModel::Phong(_) => "phong",
            BrdfModel::ModifiedPhong(_) => "modified_phong",
            BrdfModel::BlinnPhong(b) if b.normalized() => "blinn_phong_normalized",
            BrdfModel::BlinnPhong(_) => "blinn_phong",
            BrdfModel::CookTorrance(_) => "cook_torrance",
        }
    }

    /// Whether the model is designed to be physically plausible (reciprocal and energy
    /// conserving): false for the published Phong and the classic Blinn-Phong.
    pub fn is_plausible_by_design(&self) -> bool {
        match self {
            BrdfModel::Phong(_) => false,
            BrdfModel::BlinnPhong(b) => b.normalized(),
            _ => true,
        }
    }
}

macro_rules! dispatch {
    ($self:ident, $m:ident => $e:expr) => {
        match $self {
            BrdfModel::Lambert($m) => $e,
            BrdfModel::Phong($m) => $e,
            BrdfModel::ModifiedPhong($m) => $e,
            BrdfModel::BlinnPhong($m) => $e,
            BrdfModel::CookTorrance($m) => $e,
        }
    };
}

impl Brdf for BrdfModel {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        dispatch!(self, m => m.eval(wo, wi))
    }
    fn sample(&self, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
        dispatch!(self, m => m.sample(wo, u))
    }
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        dispatch!(self, m => m.pdf(wo, wi))
    }
    fn albedo(&self, wo: Vec3) -> Rgb {
        dispatch!(self, m => m.albedo(wo))
    }
}
