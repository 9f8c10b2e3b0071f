//! Preetham, Shirley & Smits 1999, "A practical analytic model for daylight": the clear sky's
//! luminance and chromaticity by the Perez et al. distribution, with the paper's fits in
//! turbidity T (appendix A.2), converted from CIE Yxy to linear Rec. 709 RGB; and the sun's
//! colour and brightness through the atmosphere, from the paper's transmittances (appendix
//! A.4: Rayleigh and Angstrom's aerosol law with turbidity) at one wavelength per channel,
//! applied to the sun's illuminance above the atmosphere.

use glam::DVec3;

/// The Perez et al. five coefficients (A..E) of one quantity (Y, x or y).
type Perez = [f64; 5];

/// Preetham's model for one turbidity and sun zenith angle: the zenith values and the Perez
/// coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Preetham {
    /// Zenith luminance Y_z, kcd/m^2, and chromaticity x_z, y_z.
    zenith: DVec3,
    /// Perez coefficients of Y, x, y.
    perez: [Perez; 3],
    /// Sun zenith angle theta_s, radians (at most pi / 2).
    theta_s: f64,
}

/// The sun's illuminance above the atmosphere on a surface facing it, lux (the solar constant
/// in photometric units, about 128 klx; Darula, Kittler & Gueymard 2005 give 133 klx, older
/// tables 127.5-128).
pub(crate) const SUN_ILLUMINANCE_OUTSIDE: f64 = 128_000.0;

/// The wavelengths (micrometres) at which the sun's transmittance is taken for the red, green
/// and blue channels: near the peaks of the Rec. 709 primaries' matching functions.
const CHANNEL_WAVELENGTHS: [f64; 3] = [0.61, 0.55, 0.465];

impl Preetham {
    /// The model for turbidity `t` (the paper fits T in [2, 10]) and sun zenith angle
    /// `theta_s` (radians; clamped to pi / 2, where the fits end).
    pub(crate) fn new(t: f64, theta_s: f64) -> Self {
        let theta_s = theta_s.clamp(0.0, std::f64::consts::FRAC_PI_2);
        let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * theta_s);
        let y_z = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
        let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let tt = [t * t, t, 1.0];
        #[rustfmt::skip]
        let mx = [
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ];
        #[rustfmt::skip]
        let my = [
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ];
        let poly = |m: &[[f64; 4]; 3]| -> f64 {
            (0..3)
                .map(|i| tt[i] * (0..4).map(|j| m[i][j] * th[j]).sum::<f64>())
                .sum()
        };
        #[rustfmt::skip]
        let perez = [
            [0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703],
            [-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989, -0.0033 * t + 0.0452],
            [-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537, -0.0109 * t + 0.0529],
        ];
        Self {
            zenith: DVec3::new(y_z, poly(&mx), poly(&my)),
            perez,
            theta_s,
        }
    }

    /// The Perez distribution F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) +
    /// E cos^2 gamma), with cos theta kept off zero (the horizon's limit, B < 0).
    fn f(p: &Perez, cos_theta: f64, gamma: f64) -> f64 {
        let [a, b, c, d, e] = *p;
        let cg = gamma.cos();
        (1.0 + a * (b / cos_theta.max(1e-3)).exp()) * (1.0 + c * (d * gamma).exp() + e * cg * cg)
    }

    /// CIE Y (kcd/m^2), x, y of the sky in the direction of zenith angle theta (by its
    /// cosine) at angle `gamma` (radians) from the sun.
    pub(crate) fn yxy(&self, cos_theta: f64, gamma: f64) -> DVec3 {
        let v = |i: usize, z: f64| {
            z * Self::f(&self.perez[i], cos_theta, gamma)
                / Self::f(&self.perez[i], 1.0, self.theta_s)
        };
        DVec3::new(
            v(0, self.zenith.x),
            v(1, self.zenith.y),
            v(2, self.zenith.z),
        )
    }

    /// The zenith luminance Y_z, kcd/m^2.
    pub(crate) fn zenith_luminance(&self) -> f64 {
        self.zenith.x
    }
}

/// Linear Rec. 709 RGB (clamped at zero) of CIE luminance `y` with chromaticity (x, y), in
/// the unit of `y`: the luminance of the result (Rec. 709 weights) is `y`.
pub(crate) fn rgb_of_yxy(c: DVec3) -> DVec3 {
    let (big_y, x, y) = (c.x, c.y, c.z);
    if y <= 0.0 || big_y <= 0.0 {
        return DVec3::ZERO;
    }
    let big_x = x * big_y / y;
    let big_z = (1.0 - x - y) * big_y / y;
    DVec3::new(
        3.240_454_2 * big_x - 1.537_138_5 * big_y - 0.498_531_4 * big_z,
        -0.969_266_0 * big_x + 1.876_010_8 * big_y + 0.041_556_0 * big_z,
        0.055_643_4 * big_x - 0.204_025_9 * big_y + 1.057_225_2 * big_z,
    )
    .max(DVec3::ZERO)
}

/// The sun's transmittance through the atmosphere per channel at zenith angle `theta_s`
/// (radians, below pi / 2) and turbidity `t`: Rayleigh exp(-0.008735 lambda^-4.08 m) times the
/// aerosols' exp(-beta lambda^-1.3 m) with beta = 0.04608 T - 0.04586 (Preetham et al.'s
/// appendix A.4), m the relative optical mass of Kasten (1966) as the paper uses it.
pub(crate) fn sun_transmittance(t: f64, theta_s: f64) -> DVec3 {
    let deg = theta_s.to_degrees();
    let m = 1.0 / (theta_s.cos() + 0.15 * (93.885 - deg).powf(-1.253));
    let beta = 0.04608 * t - 0.04586;
    let tau = |lambda: f64| {
        (-0.008735 * lambda.powf(-4.08) * m).exp() * (-beta * lambda.powf(-1.3) * m).exp()
    };
    DVec3::from_array(CHANNEL_WAVELENGTHS.map(tau))
}
