//! The radiosity solver's settings: on the command line (`--solver`, `--unshot`,
//! `--element-size`, ...) and the one home of the solver options every command that solves
//! derives from a scene (`render`, `bake`, `compare`, `bench radiosity`, `bench render`,
//! `bench tradeoff` and the preset files all go through [`SolveArgs::options`]), and the
//! progress bar of a solve.

use std::ops::ControlFlow;
use std::time::Duration;

use clap::{Args, ValueEnum};
use twopass_radiosity::{
    AdaptiveOptions, Finish, HierarchicalOptions, MAX_VISIBILITY_RAYS, MIN_LINK_TOLERANCE, Method,
    Options, SolveError, Solver, SpecularOptions, Stop, VisibilityRays,
};
use twopass_scene::Scene;

use crate::args::{checked, positive_finite};
use crate::context::Context;

/// A radiosity solver, as the command line names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverChoice {
    /// Progressive refinement: exact vertex form factors, cost grows as shooters x receivers.
    Progressive,
    /// Hierarchical radiosity with clustering: cost grows about linearly with the scene.
    Hierarchical,
    /// Hierarchical above a few thousand participating triangles, progressive below.
    Auto,
}

impl SolverChoice {
    /// The library's method.
    pub fn method(self) -> Method {
        match self {
            Self::Progressive => Method::Progressive,
            Self::Hierarchical => Method::Hierarchical,
            Self::Auto => Method::Auto,
        }
    }
}

/// The radiosity solver's settings, shared by every command that solves.
#[derive(Debug, Clone, Args)]
pub struct SolveArgs {
    /// The radiosity solver [default: auto, by the scene's size; `twopass info` says which].
    #[arg(long, value_enum, default_value = "auto")]
    pub solver: SolverChoice,
    /// Stop when the residual (unshot) power falls below this fraction of the emitted power:
    /// the convergence measure of both solvers.
    #[arg(long, default_value_t = Stop::default().unshot_fraction, value_name = "FRACTION", value_parser = parse_fraction)]
    pub unshot: f64,
    /// Hierarchical solver: refine a link while its estimated transport error exceeds this
    /// fraction of the emitted power.
    /// At least 1.2e-7 (f32's precision, `twopass_radiosity::MIN_LINK_TOLERANCE`).
    #[arg(long, default_value_t = HierarchicalOptions::default().link_tolerance, value_name = "FRACTION", value_parser = parse_link_tolerance)]
    pub link_tolerance: f64,
    /// Stop after this many shots (progressive) or gather iterations (hierarchical).
    #[arg(long, value_name = "N")]
    pub max_shots: Option<u64>,
    /// Stop after this much wall-clock time, seconds: for `bake`, the whole process (loading,
    /// the solve, the residual report and the files); the result is usable but not
    /// deterministic then. For `render` without `--spp`, the solve stops at it too and the
    /// planner gives the image the samples per pixel it measures to fit what is left.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_budget: Option<Duration>,
    /// Longest patch (shooter) edge, scene units [default: scene diagonal / 8].
    #[arg(long, value_name = "LENGTH", value_parser = parse_length)]
    pub patch_size: Option<f32>,
    /// Longest element (receiver) edge before adaptive subdivision, scene units
    /// [default: scene diagonal / 24; / 12 for `render`'s gathered hybrid].
    #[arg(long, value_name = "LENGTH", value_parser = parse_length)]
    pub element_size: Option<f32>,
    /// Keep the element mesh fixed: no adaptive subdivision where the light changes fast.
    #[arg(long)]
    pub no_adaptive: bool,
    /// Shadow rays per visibility estimate: a first estimate of MIN, up to MAX where the
    /// visibility is partial or the receiver is close.
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_rays, default_value_t = VisibilityRays::default())]
    pub visibility_rays: VisibilityRays,
    /// Cast the visibility rays of every receiver-shooter pair, also those nothing in the scene
    /// can come between (progressive refinement skips them by default: shaft culling).
    #[arg(long)]
    pub no_shaft_culling: bool,
    /// Specular transfer (progressive refinement, scenes with mirrors or glass that face
    /// diffuse surfaces; `info` says whether a scene has them): rays a shot of the whole
    /// emitted power traces through the specular surfaces, later shots in proportion to their
    /// power; 0 treats mirrors and glass as absorbers in the radiosity pass.
    #[arg(long, value_name = "N", default_value_t = SpecularOptions::default().rays,
          value_parser = clap::value_parser!(u32).range(0..=i64::from(SpecularOptions::MAX_RAYS)))]
    pub specular_rays: u32,
}

impl Default for SolveArgs {
    /// The command line's defaults (the library's, with the machine's memory limit added by
    /// [`SolveArgs::options`]).
    fn default() -> Self {
        Self {
            solver: SolverChoice::Auto,
            unshot: Stop::default().unshot_fraction,
            link_tolerance: HierarchicalOptions::default().link_tolerance,
            max_shots: None,
            time_budget: None,
            patch_size: None,
            element_size: None,
            no_adaptive: false,
            visibility_rays: VisibilityRays::default(),
            no_shaft_culling: false,
            specular_rays: SpecularOptions::default().rays,
        }
    }
}

impl SolveArgs {
    /// `compare`'s shared solve: with `quick`, a coarse mesh (elements of the scene diagonal
    /// / 16) to an unshot fraction of 1e-2; without, the default mesh to 1e-4.
    pub fn compare(scene: &Scene, quick: bool) -> Self {
        Self {
            element_size: quick.then_some(scene.bounds.diagonal() / 16.0),
            unshot: if quick { 1e-2 } else { 1e-4 },
            ..Self::default()
        }
    }

    /// `bench radiosity`'s fixed mesh of about `elements` elements over the scene's area, to
    /// `unshot`: no adaptive subdivision, and patches (default diagonal / 8) no smaller than
    /// the elements.
    pub fn element_count(scene: &Scene, elements: u32, unshot: f64) -> Self {
        // Bisection leaves are right triangles of area about L^2 / 4 for a longest edge L.
        let element_size = (4.0 * scene.total_area() / f64::from(elements.max(1))).sqrt() as f32;
        Self {
            element_size: Some(element_size),
            patch_size: Some((scene.bounds.diagonal() / 8.0).max(element_size)),
            no_adaptive: true,
            unshot,
            ..Self::default()
        }
    }

    /// The solver options these arguments ask for, the library's defaults for the rest and
    /// the machine's memory limit ([`crate::context::memory_limit`]).
    pub fn options(&self, seed: u64) -> Options {
        Options {
            patch_size: self.patch_size,
            element_size: self.element_size,
            adaptive: (!self.no_adaptive).then(AdaptiveOptions::default),
            visibility: self.visibility_rays,
            shaft_culling: !self.no_shaft_culling,
            stop: Stop {
                unshot_fraction: self.unshot,
                max_shots: self.max_shots,
                time_budget: self.time_budget,
            },
            seed,
            method: self.solver.method(),
            hierarchical: HierarchicalOptions {
                link_tolerance: self.link_tolerance,
                ..HierarchicalOptions::default()
            },
            memory_limit: crate::context::memory_limit(),
            specular: (self.specular_rays > 0).then(|| SpecularOptions {
                rays: self.specular_rays,
                ..SpecularOptions::default()
            }),
            ..Options::default()
        }
    }

    /// Runs `solver` to its stop criteria with a progress bar over the unshot fraction, then
    /// checks its energy balance ([`Solver::check_energy`]): a solve that created power is an
    /// error, its solution unused.
    pub fn run(&self, solver: &mut Solver<'_>, ctx: &Context) -> Result<Finish, SolveError> {
        let bar = ctx.progress(STEPS, "radiosity");
        let finish = solver.run(|p| {
            bar.set_position(bar_position(p.unshot_fraction, self.unshot));
            bar.set_message(format!("residual {:.1e}", p.unshot_fraction));
            ControlFlow::Continue(())
        });
        bar.finish_and_clear();
        solver.check_energy()?;
        Ok(finish)
    }
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    let secs: f64 = checked(s, positive_finite, "must be a finite number of seconds > 0")?;
    Duration::try_from_secs_f64(secs).map_err(|e| e.to_string())
}

fn parse_rays(s: &str) -> Result<VisibilityRays, String> {
    let (min, max) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}`: expected MIN,MAX such as 4,16"))?;
    let parse = |x: &str| x.trim().parse::<u32>().map_err(|e| format!("`{x}`: {e}"));
    let (min, max) = (parse(min)?, parse(max)?);
    if min == 0 || max < min || max > MAX_VISIBILITY_RAYS {
        return Err(format!(
            "{min},{max}: needs 1 <= MIN <= MAX <= {MAX_VISIBILITY_RAYS}"
        ));
    }
    Ok(VisibilityRays { min, max })
}

/// A fraction in [0, 1) (the unshot power at which to stop).
pub fn parse_fraction(s: &str) -> Result<f64, String> {
    checked(
        s,
        |x| (0.0..1.0).contains(x),
        "must be a fraction >= 0 and < 1",
    )
}

/// A link tolerance: finite and at least [`MIN_LINK_TOLERANCE`] (below it the refinement
/// grows toward every pair of the smallest elements for errors under f32's rounding).
pub(crate) fn parse_link_tolerance(s: &str) -> Result<f64, String> {
    let x: f64 = s
        .parse()
        .map_err(|e: std::num::ParseFloatError| e.to_string())?;
    if x.is_finite() && x >= MIN_LINK_TOLERANCE {
        return Ok(x);
    }
    // In exponent form: a subnormal written out in full is hundreds of digits.
    Err(format!(
        "{x:e} must be finite and at least {MIN_LINK_TOLERANCE:e} (f32's precision: a \
         smaller link error is below the rounding of what is compared)"
    ))
}

/// A length in scene units: finite and > 0 (whether it fits the scene is checked by the
/// solver, which knows the scene's area).
pub(crate) fn parse_length(s: &str) -> Result<f32, String> {
    checked(
        s,
        positive_finite,
        "must be a finite length > 0 scene units",
    )
}

/// Bar position of an unshot fraction on a log scale: 0 at 1, `STEPS` at the target.
const STEPS: u64 = 1000;

fn bar_position(unshot: f64, target: f64) -> u64 {
    let target = target.clamp(1e-15, 0.5);
    let x = unshot.max(1e-300).ln() / target.ln();
    (x.clamp(0.0, 1.0) * STEPS as f64).round() as u64
}

/// Share of the emitted power above which the power that form factors summing above one
/// would have created ([`twopass_radiosity::Residuals::energy_excess`]) is a warning: the
/// vertex form factors of an ordinary mesh overshoot by well under this.
const ENERGY_EXCESS_WARNING: f64 = 0.01;

/// Share of the emitted power whose loss in the solve ([`twopass_radiosity::Residuals::energy_lost`],
/// less three standard errors) is a warning: the hierarchical solver's discretization loses
/// up to 1.4 % in the bench's closed rooms, a light 1e-3 of the room from a wall 10 %.
const ENERGY_LOST_WARNING: f64 = 0.025;

/// Warns of what the residual report found a solve of `scene` (by `method`) did not conserve:
/// power its form factors would have created, or power it lost.
pub fn warn_energy(
    scene: &std::path::Path,
    residuals: &twopass_radiosity::Residuals,
    method: twopass_radiosity::Method,
) {
    if residuals.energy_excess > ENERGY_EXCESS_WARNING {
        errln!(
            "warning: {}: form factors summing above one would have created {:.1} % of the \
             emitted power ({}): surfaces closer than the element mesh resolves, such as a light \
             almost touching a wall; the light near them is not to be trusted",
            scene.display(),
            100.0 * residuals.energy_excess,
            match method {
                twopass_radiosity::Method::Progressive => "kept out of the shots",
                _ => "in the solution",
            }
        );
    }
    if let (Some(lost), Some(error)) = (residuals.energy_lost, residuals.energy_lost_error) {
        if lost - 3.0 * error > ENERGY_LOST_WARNING {
            errln!(
                "warning: {}: the solve lost {:.1} % of the emitted power (booked as escaped, \
                 but rays from the lit surfaces find it does not leave the scene): surfaces \
                 closer than the element mesh resolves, such as a light almost touching a wall; \
                 the light near them is too dark",
                scene.display(),
                100.0 * lost
            );
        } else if lost + 3.0 * error < -ENERGY_LOST_WARNING {
            errln!(
                "warning: {}: rays from the lit surfaces leave the scene with {:.1} % of the \
                 emitted power that the solve kept: surfaces closer than rays resolve (a gap \
                 near the floating-point precision of the scene's coordinates); neither the \
                 solve nor a render is to be trusted near them",
                scene.display(),
                -100.0 * lost
            );
        }
    }
}

/// Warns of each light that faces a surface closer than that surface's elements
/// ([`twopass_radiosity::close_lights`]): energy is kept, but the elements its outline
/// crosses send the light trapped under it out beside it.
pub fn warn_close_lights(
    path: &std::path::Path,
    scene: &twopass_scene::Scene,
    mesh: &twopass_radiosity::element::ElementMesh,
) {
    for c in twopass_radiosity::close_lights(scene, mesh) {
        errln!(
            "warning: {}: light `{}` faces `{}` {:.3e} away over {:.0} % of its area, closer \
             than that surface's elements ({:.3e}): the elements its outline crosses send the \
             light trapped under it out beside it, so the surfaces around it come out too \
             bright (`render --method reference` shows them without the element mesh)",
            path.display(),
            c.light,
            c.facing,
            c.gap,
            100.0 * c.share,
            c.element,
        );
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        solve: SolveArgs,
    }

    #[test]
    fn the_default_settings_are_the_command_lines() {
        let parsed = Cli::parse_from(["twopass"]).solve;
        assert_eq!(format!("{parsed:?}"), format!("{:?}", SolveArgs::default()));
        let options = parsed.options(7);
        assert_eq!(options.memory_limit, crate::context::memory_limit());
        let library = Options {
            seed: 7,
            memory_limit: options.memory_limit,
            ..Options::default()
        };
        assert_eq!(options, library);
    }
}
