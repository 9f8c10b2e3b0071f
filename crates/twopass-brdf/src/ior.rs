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

/// Measured complex indices of refraction of common metals at [`WAVELENGTHS_NM`].
pub const CONDUCTORS: &[Conductor] = &[
    Conductor {
        name: "gold",
        ior: ComplexIor {
            n: Rgb::new(0.143, 0.374, 1.442),
            k: Rgb::new(3.983, 2.385, 1.603),
        },
    },
    Conductor {
        name: "silver",
        ior: ComplexIor {
            n: Rgb::new(0.155, 0.117, 0.138),
            k: Rgb::new(4.828, 3.122, 2.147),
        },
    },
    Conductor {
        name: "copper",
        ior: ComplexIor {
            n: Rgb::new(0.200, 0.924, 1.102),
            k: Rgb::new(3.912, 2.452, 2.142),
        },
    },
    Conductor {
        name: "aluminium",
        ior: ComplexIor {
            n: Rgb::new(1.657, 0.880, 0.521),
            k: Rgb::new(9.224, 6.270, 4.837),
        },
    },
];
