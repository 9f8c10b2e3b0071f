//! Parameter validation shared by every model and by [`crate::Material`]: each constructor
//! checks its parameters here and returns a [`ParamError`] naming the parameter, the value and
//! the range, so evaluation never has to.

use crate::{ParamError, Rgb};

/// Largest accepted Phong-family exponent.
const EXPONENT_MAX: f32 = 1e6;

/// Every channel of `v` finite and `ok`, else an error naming `name` and `expected`.
fn check_rgb(
    name: &'static str,
    v: Rgb,
    ok: impl Fn(f32) -> bool,
    expected: &'static str,
) -> Result<(), ParamError> {
    match v
        .to_array()
        .into_iter()
        .find(|&c| !(c.is_finite() && ok(c)))
    {
        Some(c) => Err(ParamError::new(name, c.into(), expected)),
        None => Ok(()),
    }
}

/// A diffuse reflectance: every channel in [0, 1).
pub(crate) fn check_diffuse(v: Rgb) -> Result<(), ParamError> {
    check_rgb("diffuse", v, |c| (0.0..1.0).contains(&c), "in [0, 1)")
}

/// A reflectance named `name`: every channel in [0, 1].
pub(crate) fn check_unit(name: &'static str, v: Rgb) -> Result<(), ParamError> {
    check_rgb(name, v, |c| (0.0..=1.0).contains(&c), "in [0, 1]")
}

/// A lobe exponent in [0, 1e6].
pub(crate) fn check_exponent(n: f32) -> Result<(), ParamError> {
    if n.is_finite() && (0.0..=EXPONENT_MAX).contains(&n) {
        Ok(())
    } else {
        Err(ParamError::new("exponent", n.into(), "in [0, 1e6]"))
    }
}

/// A plausible model must not reflect more than it receives: diffuse + specular <= 1.
pub(crate) fn check_sum(diffuse: Rgb, specular: Rgb) -> Result<(), ParamError> {
    let sum = diffuse + specular;
    check_rgb(
        "specular",
        sum,
        |c| c <= 1.0,
        "such that diffuse + specular <= 1 on every channel",
    )
}
