//! What the radiosity examples share: their command line.

/// The examples' two positional arguments: the scene path (default the Cornell box) and the
/// unshot fraction to stop at (default 1e-3).
pub fn scene_and_unshot() -> Result<(String, f64), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "scenes/cornell-box.toml".into());
    let unshot: f64 = args.next().map_or(Ok(1e-3), |s| s.parse())?;
    Ok((path, unshot))
}
