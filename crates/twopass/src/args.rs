//! Value parsers of the command-line options: a number of the option's type, then a range
//! check whose message names the value and what the option needs.

use std::fmt::Display;
use std::str::FromStr;

/// Parses `s` as a `T` and keeps it when `ok` holds; otherwise the error is the value followed
/// by `needs` (such as "must be 1 to 64").
pub fn checked<T>(s: &str, ok: impl Fn(&T) -> bool, needs: &str) -> Result<T, String>
where
    T: FromStr + Display,
    T::Err: Display,
{
    let x: T = s.parse().map_err(|e: T::Err| e.to_string())?;
    if ok(&x) {
        Ok(x)
    } else {
        Err(format!("{x} {needs}"))
    }
}

/// Whether `x` is finite and above zero.
pub fn positive_finite<T: Into<f64> + Copy>(x: &T) -> bool {
    let x: f64 = (*x).into();
    x.is_finite() && x > 0.0
}
