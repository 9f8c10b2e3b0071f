//! The options of `twopass bench tradeoff` and the preset names its `--targets` map to.

use std::path::PathBuf;

use clap::Args;

use crate::pipeline::RenderMethod;

/// Arguments of `twopass bench tradeoff`.
#[derive(Debug, Args)]
pub struct TradeoffArgs {
    /// Scene file (.toml) or mesh (.obj).
    pub scene: PathBuf,
    /// A small sweep at 48 pixels wide for smoke tests (seconds, not minutes); its presets mean
    /// little.
    #[arg(long)]
    pub quick: bool,
    /// Samples per pixel of the converged reference [default: 8192; 256 with --quick].
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=10_000_000))]
    pub reference_spp: Option<u32>,
    /// Directory of the cached converged references [default: OUTPUT/cache].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Relative RMSE targets of the presets draft, preview and final, in that order, comma
    /// separated (`0.10,0.026,0.014`).
    #[arg(long, value_delimiter = ',', default_values_t = [0.10, 0.026, 0.014], value_parser = parse_target)]
    pub targets: Vec<f64>,
    /// Methods to sweep, comma separated [default: every method the scene calls for].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Vec<RenderMethod>,
    /// Also write the presets beside the scene (`<stem>.presets.toml`), where `--preset`
    /// looks for them.
    #[arg(long)]
    pub install_presets: bool,
}

fn parse_target(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|e| format!("`{s}`: {e}"))?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(format!(
            "{x}: a target relative RMSE must be finite and > 0"
        ))
    }
}

/// Names of the presets, in the order of `--targets`.
pub(super) const PRESET_NAMES: [&str; 3] = ["draft", "preview", "final"];
