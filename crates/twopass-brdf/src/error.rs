//! The one error type of this crate: a model parameter outside its valid range.

use std::fmt;

/// A model parameter outside its valid range. Carries which parameter, the offending value and
/// the range it must lie in, so callers can attach a file and line.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ParamError {
    /// The parameter's name as written in a scene file (`diffuse`, `roughness`, ...).
    pub parameter: &'static str,
    /// The offending value (for RGB parameters, the first offending channel).
    pub value: f64,
    /// The valid range in words, for example `"in [0, 1)"`.
    pub expected: &'static str,
}

impl ParamError {
    /// A parameter error for `parameter` whose `value` is not `expected`.
    pub fn new(parameter: &'static str, value: f64, expected: &'static str) -> Self {
        Self {
            parameter,
            value,
            expected,
        }
    }
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "parameter `{}` = {} must be {}",
            self.parameter, self.value, self.expected
        )
    }
}

impl std::error::Error for ParamError {}
