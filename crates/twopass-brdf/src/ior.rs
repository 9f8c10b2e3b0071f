//! Complex indices of refraction, per RGB channel, and a table of measured metals.

use crate::{ParamError, Rgb};

/// A relative index of refraction eta = n + i k per RGB channel (dimensionless).
/// Dielectrics have k = 0; conductors have k > 0 and reflect in their own colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComplexIor {
    /// Real part n, per channel (> 0).
    pub n: Rgb,
    /// Extinction coefficient k, per channel (>= 0).
    pub k: Rgb,
}

impl ComplexIor {
    /// A validated index: every n finite and > 0, every k finite and >= 0.
    pub fn new(n: Rgb, k: Rgb) -> Result<Self, ParamError> {
        for c in n.to_array() {
            if !(c.is_finite() && c > 0.0) {
                return Err(ParamError::new("ior", c.into(), "finite and > 0"));
            }
        }
        for c in k.to_array() {
            if !(c.is_finite() && c >= 0.0) {
                return Err(ParamError::new("k", c.into(), "finite and >= 0"));
            }
        }
        Ok(Self { n, k })
    }

    /// A real (dielectric) index, the same on every channel.
    pub fn dielectric(n: f32) -> Result<Self, ParamError> {
        Self::new(Rgb::splat(n), Rgb::ZERO)
    }

    /// The measured index of a named metal from [`CONDUCTORS`], if the name is known.
    pub fn conductor(name: &str) -> Option<Self> {
        CONDUCTORS
            .iter()
            .find(|c| c.name.eq_ignore_ascii_case(name))
            .map(|c| c.ior)
    }
}

/// One measured metal: its name as written in scene files and its complex index at the
/// three RGB wavelengths of [`WAVELENGTHS_NM`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conductor {
    /// Name used in scene files (`"gold"`, ...).
    pub name: &'static str,
    /// Complex index of refraction at the RGB wavelengths.
    pub ior: ComplexIor,
}

/// The wavelengths (nm) at which the RGB channels of [`CONDUCTORS`] were sampled.
pub const WAVELENGTHS_NM: [f32; 3] = [650.0, 550.0, 450.0];

/// Measured complex indices of refraction of common metals at [`WAVELENGTHS_NM`]
/// (650, 550, 450 nm), each linearly interpolated in wavelength between the two nearest
/// tabulated points of the published data, as transcribed in the refractiveindex.info database
/// (`data-nk/main/<metal>/<page>.yml`):
///
/// | metal | source | n (R, G, B) | k (R, G, B) | R at normal incidence |
/// | --- | --- | --- | --- | --- |
/// | gold | Johnson & Christy, Phys. Rev. B 6, 4370 (1972) | 0.1556, 0.4241, 1.3831 | 3.6024, 2.4721, 1.9155 | 0.957, 0.792, 0.408 |
/// | silver | Johnson & Christy, Phys. Rev. B 6, 4370 (1972) | 0.0522, 0.0596, 0.0400 | 4.4094, 3.5974, 2.6484 | 0.990, 0.983, 0.980 |
/// | copper | Johnson & Christy, Phys. Rev. B 6, 4370 (1972) | 0.2378, 1.0066, 1.2404 | 3.6264, 2.5823, 2.3929 | 0.935, 0.624, 0.538 |
/// | aluminium | Rakic, Appl. Opt. 34, 4755 (1995) | 1.5580, 1.0152, 0.6332 | 7.7124, 6.6273, 5.4544 | 0.906, 0.915, 0.922 |
///
/// Johnson & Christy give n to two decimals, so silver's n (about 0.05) carries a relative
/// uncertainty of about 20%; its effect on the reflectance is about 0.2%.
pub const CONDUCTORS: &[Conductor] = &[
    Conductor {
        name: "gold",
        ior: ComplexIor {
            n: Rgb::new(0.1556, 0.4241, 1.3831),
            k: Rgb::new(3.6024, 2.4721, 1.9155),
        },
    },
    Conductor {
        name: "silver",
        ior: ComplexIor {
            n: Rgb::new(0.0522, 0.0596, 0.0400),
            k: Rgb::new(4.4094, 3.5974, 2.6484),
        },
    },
    Conductor {
        name: "copper",
        ior: ComplexIor {
            n: Rgb::new(0.2378, 1.0066, 1.2404),
            k: Rgb::new(3.6264, 2.5823, 2.3929),
        },
    },
    Conductor {
        name: "aluminium",
        ior: ComplexIor {
            n: Rgb::new(1.5580, 1.0152, 0.6332),
            k: Rgb::new(7.7124, 6.6273, 5.4544),
        },
    },
];
