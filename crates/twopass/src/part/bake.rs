pub fn merge(
    _: &super::set::PartSet,
    _: &crate::context::Context,
    _: std::time::Instant,
) -> Result<(), crate::error::CliError> {
    todo!()
}
