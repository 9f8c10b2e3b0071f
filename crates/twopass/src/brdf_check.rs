//! `twopass brdf-check` (being written).
use clap::Args;
/// Arguments.
#[derive(Debug, Args)]
pub struct BrdfCheckArgs {}
/// Runs.
pub fn run(_: &BrdfCheckArgs, _: &crate::context::Context) -> Result<(), crate::error::CliError> {
    Err(crate::error::CliError::Input(
        "brdf-check is not built yet".into(),
    ))
}
