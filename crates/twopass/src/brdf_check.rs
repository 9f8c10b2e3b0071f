//! `twopass brdf-check`: the plausibility table of every reflection model over a grid of
//! parameters (positivity, reciprocity error, energy albedo from 0 to 89.9 degrees), and polar
//! plots of the lobes in the plane of incidence as PNG.

use std::io::Write as _;
use std::path::Path;

use clap::Args;
use glam::Vec3;
use plotters::prelude::*;
use rayon::prelude::*;
use serde_json::json;
use twopass_brdf::check::{self, CheckOptions, INCIDENCE_DEG, Plausibility};
use twopass_brdf::quadrature::Quadrature;
use twopass_brdf::{
    BlinnPhongParams, Brdf, BrdfModel, ComplexIor, CookTorranceParams, FresnelModel, Material,
    ParamError, PhongParams, Rgb,
};

use crate::context::Context;
use crate::error::CliError;
use crate::figure;

/// Options of `twopass brdf-check`.
#[derive(Debug, Args)]
pub struct BrdfCheckArgs {
    /// Only models whose name contains this text (lambert, phong, modified_phong, blinn_phong,
    /// blinn_phong_normalized, cook_torrance).
    #[arg(long)]
    pub model: Option<String>,
    /// Incidence angles (degrees, in [0, 90)) of the lobe plots.
    #[arg(long, value_delimiter = ',', default_values_t = vec![0.0, 30.0, 60.0, 80.0])]
    pub angles: Vec<f32>,
    /// Quadrature cells along the polar angle (the azimuth gets a quarter as many); the default
    /// is the resolution proven accurate to 1e-3 by the brdf crate's tests.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=16384))]
    pub resolution: u32,
    /// Skip the PNG plots.
    #[arg(long)]
    pub no_plots: bool,
}

/// Allowed excess over albedo 1: the proven accuracy of the quadrature.
const ALBEDO_TOLERANCE: f32 = 1e-3;
/// Largest relative reciprocity error counted as reciprocal (f32 rounding).
const RECIPROCITY_TOLERANCE: f32 = 1e-6;

struct Case {
    params: String,
    model: BrdfModel,
}

fn phong(rho: f32, ks: f32, n: f32, normalized: bool) -> Result<BrdfModel, ParamError> {
    material_model(Material::phong(PhongParams {
        diffuse: Rgb::splat(rho),
        specular: Rgb::splat(ks),
        exponent: n,
        ambient: Rgb::ZERO,
        normalized,
    })?)
}

fn blinn(rho: f32, ks: f32, n: f32, normalized: bool) -> Result<BrdfModel, ParamError> {
    material_model(Material::blinn_phong(BlinnPhongParams {
        diffuse: Rgb::splat(rho),
        specular: Rgb::splat(ks),
        exponent: n,
        normalized,
    })?)
}

fn cook(m: f32, ior: ComplexIor, fresnel: FresnelModel) -> Result<BrdfModel, ParamError> {
    material_model(Material::cook_torrance(CookTorranceParams {
        diffuse: Rgb::ZERO,
        specular: Rgb::ONE,
        roughness: m,
        ior,
        fresnel,
    })?)
}

fn material_model(m: Material) -> Result<BrdfModel, ParamError> {
    m.model()
        .ok_or(ParamError::new("lobe", 0.0, "a glossy (non-delta) lobe"))
}

/// The parameter grid of the table.
fn cases() -> Result<Vec<Case>, ParamError> {
    let mut v = Vec::new();
    let mut push = |params: String, model: BrdfModel| v.push(Case { params, model });
    for rho in [0.5f32, 0.9] {
        push(
            format!("rho {rho}"),
            material_model(Material::lambert(Rgb::splat(rho))?)?,
        );
    }
    for n in [1.0f32, 10.0, 100.0] {
        push(format!("rho 0.4 ks 0.6 n {n}"), phong(0.4, 0.6, n, false)?);
    }
    for n in [0.0f32, 1.0, 10.0, 100.0, 1e4] {
        push(format!("rho 0.4 ks 0.6 n {n}"), phong(0.4, 0.6, n, true)?);
    }
    for n in [4.0f32, 40.0, 400.0] {
        push(format!("rho 0.4 ks 0.6 n' {n}"), blinn(0.4, 0.6, n, false)?);
    }
    for n in [0.0f32, 4.0, 40.0, 400.0, 4e4] {
        push(format!("rho 0.4 ks 0.6 n' {n}"), blinn(0.4, 0.6, n, true)?);
    }
    let glass = ComplexIor::dielectric(1.5)?;
    let gold = ComplexIor::conductor("gold").ok_or(ParamError::new("ior", 0.0, "a known metal"))?;
    let white = ComplexIor::new(Rgb::ONE, Rgb::splat(1e3))?;
    for m in [0.05f32, 0.2, 0.5, 1.0, 2.0] {
        push(
            format!("m {m} F=1 (k 1e3)"),
            cook(m, white, FresnelModel::Exact)?,
        );
    }
    for m in [0.05f32, 0.2, 0.5, 1.0] {
        push(
            format!("m {m} glass 1.5"),
            cook(m, glass, FresnelModel::Exact)?,
        );
        push(format!("m {m} gold"), cook(m, gold, FresnelModel::Exact)?);
    }
    push(
        "m 0.2 gold Schlick".to_owned(),
        cook(0.2, gold, FresnelModel::Schlick)?,
    );
    Ok(v)
}

struct ModelRow {
    name: &'static str,
    params: String,
    result: Plausibility,
}

impl ModelRow {
    fn plausible(&self) -> bool {
        self.result.non_finite == 0
            && self.result.min_value >= 0.0
            && self.result.reciprocity_error <= RECIPROCITY_TOLERANCE
            && self.result.max_albedo() <= 1.0 + ALBEDO_TOLERANCE
    }
}

/// Runs `twopass brdf-check`.
pub fn run(args: &BrdfCheckArgs, ctx: &Context) -> Result<(), CliError> {
    if let Some(bad) = args.angles.iter().find(|a| !(0.0..90.0).contains(*a)) {
        return Err(CliError::Input(format!(
            "--angles: {bad} is not an incidence angle in [0, 90) degrees"
        )));
    }
    let wanted = |name: &str| args.model.as_deref().is_none_or(|m| name.contains(m));
    let cases: Vec<Case> = cases()
        .map_err(|e| CliError::Input(format!("built-in parameter grid: {e}")))?
        .into_iter()
        .filter(|c| wanted(c.model.name()))
        .collect();
    if cases.is_empty() {
        return Err(CliError::Input(format!(
            "--model {:?} matches none of lambert, phong, modified_phong, blinn_phong, blinn_phong_normalized, cook_torrance",
            args.model.as_deref().unwrap_or("")
        )));
    }
    let n_theta = args.resolution as usize & !1;
    let options = CheckOptions {
        incidence_deg: INCIDENCE_DEG.to_vec(),
        quadrature: Quadrature {
            n_theta,
            n_phi: (n_theta / 4).max(8),
        },
        grid: 12,
    };
    let bar = ctx.progress(cases.len() as u64, "brdf-check");
    let rows: Vec<ModelRow> = cases
        .par_iter()
        .map(|c| {
            let result = check::plausibility(&c.model, &options);
            bar.inc(1);
            ModelRow {
                name: c.model.name(),
                params: c.params.clone(),
                result,
            }
        })
        .collect();
    bar.finish_and_clear();

    let out_dir = ctx.output_or(Path::new("brdf-check")).to_path_buf();
    let mut plots = Vec::new();
    if !args.no_plots {
        for (file, title, model) in plot_models()? {
            if !wanted(model.name()) {
                continue;
            }
            let path = out_dir.join(file);
            plot_lobe(&path, title, &model, &args.angles)?;
            plots.push(path);
        }
    }

    if ctx.json {
        let table: Vec<_> = rows
            .iter()
            .map(|r| {
                json!({
                    "model": r.name,
                    "parameters": r.params,
                    "plausible_by_design": cases.iter().find(|c| c.params == r.params && c.model.name() == r.name).map(|c| c.model.is_plausible_by_design()),
                    "min_value": r.result.min_value,
                    "non_finite": r.result.non_finite,
                    "reciprocity_error": r.result.reciprocity_error,
                    "max_albedo": r.result.max_albedo(),
                    "plausible": r.plausible(),
                    "albedo": r.result.albedo.iter().map(|a| json!({
                        "incidence_deg": a.incidence_deg,
                        "rgb": a.albedo.to_array(),
                    })).collect::<Vec<_>>(),
                })
            })
            .collect();
        let summary = json!({
            "quadrature": { "n_theta": options.quadrature.n_theta, "n_phi": options.quadrature.n_phi },
            "albedo_tolerance": ALBEDO_TOLERANCE,
            "reciprocity_tolerance": RECIPROCITY_TOLERANCE,
            "models": table,
            "plots": plots,
        });
        let mut out = std::io::stdout().lock();
        match writeln!(out, "{summary:#}") {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                return Err(CliError::io("<stdout>", e));
            }
            _ => {}
        }
    } else if ctx.chatty() {
        print_table(&rows)?;
        for p in &plots {
            outln!("wrote {}", p.display());
        }
    }
    Ok(())
}

fn print_table(rows: &[ModelRow]) -> Result<(), CliError> {
    outln!(
        "{:<23} {:<22} {:>9} {:>9} {:>7} {:>7} {:>7} {:>7} {:>7}  verdict",
        "model",
        "parameters",
        "min f",
        "recip err",
        "a(0)",
        "a(60)",
        "a(85)",
        "a(89.9)",
        "max a"
    );
    let at = |r: &ModelRow, deg: f32| {
        r.result
            .albedo
            .iter()
            .find(|a| a.incidence_deg == deg)
            .map_or(f32::NAN, |a| a.albedo.max_element())
    };
    for r in rows {
        outln!(
            "{:<23} {:<22} {:>9.2e} {:>9.2e} {:>7.4} {:>7.4} {:>7.4} {:>7.4} {:>7.4}  {}",
            r.name,
            r.params,
            r.result.min_value,
            r.result.reciprocity_error,
            at(r, 0.0),
            at(r, 60.0),
            at(r, 85.0),
            at(r, 89.9),
            r.result.max_albedo(),
            if r.plausible() {
                "plausible"
            } else {
                "NOT plausible"
            }
        );
    }
    outln!(
        "albedo = energy albedo for light from the given incidence (integral of f cos over the outgoing hemisphere), max over RGB;"
    );
    outln!(
        "plausible = f >= 0, reciprocity error <= {RECIPROCITY_TOLERANCE:e}, albedo <= 1 (+{ALBEDO_TOLERANCE:e} quadrature accuracy) at every incidence."
    );
    Ok(())
}

fn plot_models() -> Result<Vec<(&'static str, &'static str, BrdfModel)>, CliError> {
    let e = |e: ParamError| CliError::Input(format!("built-in plot parameters: {e}"));
    let gold =
        ComplexIor::conductor("gold").ok_or(CliError::Input("no gold in the table".into()))?;
    let glass = ComplexIor::dielectric(1.5).map_err(e)?;
    let lambert = Material::lambert(Rgb::splat(0.8)).and_then(material_model);
    use FresnelModel::Exact;
    // One row per plot: file, title, model.
    #[rustfmt::skip]
    let models = [
        ("lambert.png", "Lambert, rho 0.8", lambert),
        ("phong.png", "Phong as published, rho 0.2, ks 0.8, n 10", phong(0.2, 0.8, 10.0, false)),
        ("modified_phong.png", "Modified Phong, rho 0.2, ks 0.8, n 10", phong(0.2, 0.8, 10.0, true)),
        ("blinn_phong.png", "Blinn-Phong classic, rho 0.2, ks 0.8, n' 40", blinn(0.2, 0.8, 40.0, false)),
        ("blinn_phong_normalized.png", "Blinn-Phong normalized, rho 0.2, ks 0.8, n' 40", blinn(0.2, 0.8, 40.0, true)),
        ("cook_torrance_gold.png", "Cook-Torrance, gold, m 0.2", cook(0.2, gold, Exact)),
        ("cook_torrance_glass.png", "Cook-Torrance, glass 1.5, m 0.5", cook(0.5, glass, Exact)),
    ];
    models
        .into_iter()
        .map(|(file, title, model)| Ok((file, title, model.map_err(e)?)))
        .collect()
}

/// The polar plot's axes: the lobe's extent across and up, scaled to its peak.
const LOBE_AXES: figure::Axes = figure::Axes {
    x: "r sin(theta_o), r = f cos(theta_o) / peak  (mirror side left)",
    y: "r cos(theta_o)",
    desc_size: 15,
    grid: 235,
};

/// A polar plot of f(wo, wi) cos(theta_o) in the plane of incidence (wi at azimuth 0, so the
/// mirror direction is on the left), one curve per incidence angle, each scaled to its peak.
fn plot_lobe(path: &Path, title: &str, model: &BrdfModel, angles: &[f32]) -> Result<(), CliError> {
    const W: u32 = 720;
    const H: u32 = 420; // about equal scales on both axes, so the unit circle looks round
    figure::png(path, W, H, |root| {
        let mut chart = figure::titled(root, title)
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(52)
            .build_cartesian_2d(-1.1f32..1.1f32, 0f32..1.1f32)
            .map_err(|e| e.to_string())?;
        LOBE_AXES.draw(&mut chart)?;
        let circle: Vec<(f32, f32)> = (0..=180)
            .map(|i| {
                let t = (i as f32 - 90.0).to_radians();
                (t.sin(), t.cos())
            })
            .collect();
        chart
            .draw_series(LineSeries::new(circle, RGBColor(190, 190, 190)))
            .map_err(|e| e.to_string())?;
        let palette = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
            RGBColor(148, 103, 189),
            RGBColor(255, 127, 14),
            RGBColor(23, 190, 207),
        ];
        for (k, &deg) in angles.iter().enumerate() {
            let color = palette[k % palette.len()];
            let (s, c) = deg.to_radians().sin_cos();
            let wi = Vec3::new(s, 0.0, c);
            let samples: Vec<(f32, f32)> = (0..=1800)
                .map(|i| {
                    let t = (i as f32 / 10.0 - 90.0).to_radians();
                    let wo = Vec3::new(t.sin(), 0.0, t.cos().max(0.0));
                    (t, model.eval(wo, wi).max_element() * wo.z)
                })
                .collect();
            let peak = samples.iter().map(|s| s.1).fold(0.0f32, f32::max);
            let scale = if peak > 0.0 { 1.0 / peak } else { 0.0 };
            let curve = samples
                .iter()
                .map(|&(t, v)| (v * scale * t.sin(), v * scale * t.cos()));
            chart
                .draw_series(LineSeries::new(curve, color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(format!("theta_i {deg} deg, peak f cos = {peak:.3} /sr"))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], color.stroke_width(2))
                });
            chart
                .draw_series(LineSeries::new(
                    [(0.0, 0.0), (s, c)],
                    color.mix(0.5).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?;
        }
        figure::legend(&mut chart, SeriesLabelPosition::UpperRight, 13)?;
        Ok(())
    })
}
