//! Named quality presets (draft, preview, final) measured by `twopass bench tradeoff`.
//!
//! A preset is not a guess: it is the cheapest setting the tradeoff sweep measured to reach an
//! error target (relative RMSE against a converged reference) on one scene. The sweep writes
//! them to `<stem>.presets.toml`; `twopass render --preset NAME` and `twopass bake --preset
//! NAME` read that file from beside the scene (or from `--presets FILE`).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use twopass_radiosity::MAX_VISIBILITY_RAYS;
use twopass_trace::{AdaptiveSampling, RenderSettings, WhittedSettings};

use crate::error::CliError;
use crate::pipeline::{MAX_DEPTH, RenderMethod};
use crate::solve::SolveArgs;

/// The arguments a preset sets, which conflict with `--preset`.
pub const PRESET_SETS: [&str; 13] = [
    "method",
    "spp",
    "adaptive",
    "depth",
    "shadow_grid",
    "gather_rays",
    "unshot",
    "max_shots",
    "time_budget",
    "patch_size",
    "element_size",
    "no_adaptive",
    "visibility_rays",
];

/// The tracer's knobs of one measured setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderKnobs {
    /// Samples per pixel (stratified anti-aliasing; the path tracer's paths per pixel).
    pub spp: u32,
    /// Recursion depth of mirror and refraction paths (Whitted and the hybrids).
    pub depth: u32,
    /// Shadow rays per hit as an N x N grid over all the emitters, each ray's emitter chosen by
    /// its importance at the hit (Whitted and the hybrids).
    pub shadow_grid: u32,
    /// Adaptive anti-aliasing: samples per pixel of a first pass everywhere, `spp` only where
    /// a pixel's samples or its neighbours disagree ([`twopass_trace::AdaptiveSampling`]);
    /// absent for `spp` everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<u32>,
    /// Gather rays per camera sample and diffuse shading point of the gathered hybrid
    /// ([`WhittedSettings::gather_rays`]); absent in a presets file: the default.
    #[serde(default = "default_gather_rays")]
    pub gather_rays: u32,
}

/// The gathered hybrid's default gather rays per camera sample, for presets files that
/// predate the knob or do not set it.
pub fn default_gather_rays() -> u32 {
    WhittedSettings::default().gather_rays
}

/// Most gather rays per camera sample `--gather-rays` and a presets file accept: past this,
/// more samples per pixel cost the same and also anti-alias.
pub const MAX_GATHER_RAYS: u32 = 1024;

impl RenderKnobs {
    /// The render loop's settings these knobs ask for, with the run's `seed`.
    pub fn settings(&self, seed: u64) -> RenderSettings {
        RenderSettings {
            adaptive: self.adaptive.map(|base| AdaptiveSampling {
                base,
                ..AdaptiveSampling::default()
            }),
            ..crate::pipeline::render_settings(self.spp, seed)
        }
    }

    /// The Whitted-family settings these knobs ask for.
    pub fn whitted(&self) -> WhittedSettings {
        WhittedSettings {
            max_depth: self.depth,
            shadow_grid: self.shadow_grid,
            gather_rays: self.gather_rays,
            ..WhittedSettings::default()
        }
    }
}

/// The radiosity solver's knobs of one measured setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiosityKnobs {
    /// Longest element edge before adaptive subdivision, scene units.
    pub element_size: f32,
    /// Unshot fraction the solve stops at (of the emitted power).
    pub unshot: f64,
    /// Shadow rays of the first visibility estimate.
    pub visibility_min: u32,
    /// Shadow rays where the first estimate is partial or the receiver close.
    pub visibility_max: u32,
    /// Adaptive subdivision where the light changes fast.
    pub adaptive: bool,
}

impl RadiosityKnobs {
    /// The solver settings these knobs ask for; the others (patch size, shot and time limits)
    /// at their defaults.
    pub fn solve_args(&self) -> SolveArgs {
        let k = self;
        SolveArgs {
            unshot: k.unshot,
            element_size: Some(k.element_size),
            no_adaptive: !k.adaptive,
            visibility_rays: twopass_radiosity::VisibilityRays {
                min: k.visibility_min,
                max: k.visibility_max,
            },
            ..SolveArgs::default()
        }
    }
}

/// One named preset: the setting and what it measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    /// Its name: draft, preview or final.
    pub name: String,
    /// The error it was chosen to reach: relative RMSE against the reference, unitless.
    pub target_rel_rmse: f64,
    /// Whether any measured setting reached the target (if not, this is the most accurate one).
    pub reached: bool,
    /// Relative RMSE measured for this setting, unitless.
    pub measured_rel_rmse: f64,
    /// Wall-clock seconds measured for this setting, radiosity solve included.
    pub measured_seconds: f64,
    /// The method.
    pub method: RenderMethod,
    /// The tracer's knobs.
    pub render: RenderKnobs,
    /// The solver's knobs, for the radiosity-based methods.
    pub radiosity: Option<RadiosityKnobs>,
}

/// A presets file: where and how the presets were measured, and the presets by name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PresetFile {
    /// The command that measured them.
    pub measured_by: String,
    /// Image size of the measurement, pixels.
    pub width: u32,
    /// Image height of the measurement, pixels.
    pub height: u32,
    /// Worker threads of the measurement.
    pub threads: usize,
    /// The presets, cheapest first.
    pub presets: Vec<Preset>,
}

impl PresetFile {
    /// The preset called `name`.
    pub fn get(&self, name: &str) -> Option<&Preset> {
        self.presets.iter().find(|p| p.name == name)
    }

    /// The presets file of a scene: `<dir>/<stem>.presets.toml` beside it.
    pub fn beside(scene: &Path) -> PathBuf {
        let stem = scene
            .file_stem()
            .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());
        scene.with_file_name(format!("{stem}.presets.toml"))
    }

    /// Reads a presets file, naming the file in every error.
    pub fn read(path: &Path) -> Result<Self, CliError> {
        let text = crate::output::read_text(path).map_err(|e| {
            CliError::Input(format!(
                "{}: cannot read the presets ({e}); `twopass bench tradeoff SCENE \
                 --install-presets` measures and writes them",
                path.display()
            ))
        })?;
        toml::from_str(&text).map_err(|e| CliError::Input(format!("{}: {e}", path.display())))
    }

    /// The file as TOML, with a header comment saying what it is.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string_pretty(self).expect("presets serialize to TOML");
        format!(
            "# Quality presets measured by `twopass bench tradeoff`: each is the cheapest\n\
             # setting measured to reach its target relative RMSE. Regenerate, don't edit.\n{body}"
        )
    }
}

/// The preset `name` for `scene`, from `presets` or the file beside the scene.
pub fn load(scene: &Path, presets: Option<&Path>, name: &str) -> Result<Preset, CliError> {
    let path = presets.map_or_else(|| PresetFile::beside(scene), Path::to_path_buf);
    let file = PresetFile::read(&path)?;
    let preset = file.get(name).cloned().ok_or_else(|| {
        let names: Vec<&str> = file.presets.iter().map(|p| p.name.as_str()).collect();
        CliError::Input(format!(
            "{}: no preset `{name}` (it has {})",
            path.display(),
            names.join(", ")
        ))
    })?;
    preset.check().map_err(|problem| {
        CliError::Input(format!("{}: preset `{name}`: {problem}", path.display()))
    })?;
    Ok(preset)
}

impl Preset {
    /// Checks the knobs against the ranges the command-line options accept, so a presets file
    /// cannot ask for what `--spp`, `--depth`, `--shadow-grid`, `--element-size`, `--unshot`
    /// or `--visibility-rays` would refuse.
    pub fn check(&self) -> Result<(), String> {
        let r = &self.render;
        if !(1..=1_000_000).contains(&r.spp) {
            return Err(format!("spp {} must be 1 to 1000000", r.spp));
        }
        if r.depth > MAX_DEPTH {
            return Err(format!("depth {} must be at most {}", r.depth, MAX_DEPTH));
        }
        if !(1..=64).contains(&r.shadow_grid) {
            return Err(format!("shadow_grid {} must be 1 to 64", r.shadow_grid));
        }
        if !(1..=MAX_GATHER_RAYS).contains(&r.gather_rays) {
            return Err(format!(
                "gather_rays {} must be 1 to {MAX_GATHER_RAYS}",
                r.gather_rays
            ));
        }
        if let Some(k) = &self.radiosity {
            if !(k.element_size.is_finite() && k.element_size > 0.0) {
                return Err(format!(
                    "element_size {} must be finite and > 0",
                    k.element_size
                ));
            }
            if !(0.0..1.0).contains(&k.unshot) {
                return Err(format!("unshot {} must be >= 0 and < 1", k.unshot));
            }
            let max = MAX_VISIBILITY_RAYS;
            if k.visibility_min == 0
                || k.visibility_max < k.visibility_min
                || k.visibility_max > max
            {
                return Err(format!(
                    "visibility rays {},{} need 1 <= min <= max <= {max}",
                    k.visibility_min, k.visibility_max
                ));
            }
        }
        Ok(())
    }
}
