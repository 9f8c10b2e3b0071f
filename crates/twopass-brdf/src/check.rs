//! Plausibility probes for any [`Brdf`]: positivity, reciprocity error and directional albedo
//! (the albedo integrals of [`crate::interface`] over the hemisphere quadrature of
//! [`crate::quadrature`]), plus a reusable chi-square goodness-of-fit harness for samplers
//! (the design of Mitsuba's `chi2.py`).
//!
//! # Chi-square
//! [`chi2_test`] draws seeded samples, bins them on the (phi, cos theta) domain of the upper
//! hemisphere (equal-area cells), integrates the claimed density over each cell, pools cells
//! expecting fewer than 5 samples, and rejects at the given significance with the Sidak
//! correction for the number of tests run. The tables are returned for dumping on failure.

use std::f64::consts::PI as PI64;
use std::fmt::Write as _;

use glam::{DVec3, Vec2, Vec3};

use crate::Rgb;
use crate::frame::{reflect, spherical_direction};
use crate::interface::{Brdf, incident_albedo};
use crate::quadrature::{Quadrature, integrate_hemisphere};
pub use crate::random::Pcg32;

/// Integral over the hemisphere of `brdf.pdf(wo, .)`: the probability that `sample` succeeds.
pub fn pdf_integral<B: Brdf + ?Sized>(brdf: &B, wo: Vec3, q: Quadrature) -> f64 {
    integrate_hemisphere(reflect(wo), q, |wi| f64::from(brdf.pdf(wo, wi)))
}

/// The local direction at polar angle `deg` (degrees) from the normal in the xz-plane.
pub fn direction_at_deg(deg: f32) -> Vec3 {
    let (s, c) = deg.to_radians().sin_cos();
    Vec3::new(s, 0.0, c)
}

/// The incidence angles (degrees) at which [`plausibility`] measures the albedo by default.
pub const INCIDENCE_DEG: [f32; 13] = [
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 75.0, 80.0, 85.0, 89.0, 89.9,
];

/// What [`plausibility`] measures and how finely.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckOptions {
    /// Incidence angles (degrees, in [0, 90)) for the albedo.
    pub incidence_deg: Vec<f32>,
    /// Quadrature for the albedo integrals.
    pub quadrature: Quadrature,
    /// Directions per axis of the positivity and reciprocity grid (`n` polar angles up to
    /// 89.9 degrees times `2n` azimuths; all pairs are compared).
    pub grid: usize,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            incidence_deg: INCIDENCE_DEG.to_vec(),
            quadrature: Quadrature::default(),
            grid: 12,
        }
    }
}

/// The albedo measured at one incidence angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlbedoRow {
    /// Incidence angle theta_i (degrees).
    pub incidence_deg: f32,
    /// Energy albedo for light from that angle ([`incident_albedo`]), per channel.
    pub albedo: Rgb,
}

/// The plausibility of one model, as measured by [`plausibility`].
#[derive(Debug, Clone, PartialEq)]
pub struct Plausibility {
    /// The smallest value of any channel of f over the grid (1/sr); negative is implausible.
    pub min_value: f32,
    /// Number of NaN or infinite values met on the grid and in the quadrature (0 if total).
    pub non_finite: usize,
    /// Largest relative reciprocity error max |f(i,o) - f(o,i)| / max(f(i,o), f(o,i)) over all
    /// pairs of grid directions and channels (dimensionless; 0 for a reciprocal model).
    pub reciprocity_error: f32,
    /// The energy albedo at each incidence angle.
    pub albedo: Vec<AlbedoRow>,
}

impl Plausibility {
    /// The largest albedo over every angle and channel.
    pub fn max_albedo(&self) -> f32 {
        self.albedo
            .iter()
            .map(|r| r.albedo.max_element())
            .fold(0.0, f32::max)
    }

    /// The smallest albedo over every angle and channel.
    pub fn min_albedo(&self) -> f32 {
        self.albedo
            .iter()
            .map(|r| r.albedo.min_element())
            .fold(f32::INFINITY, f32::min)
    }
}

/// The deterministic direction grid of [`CheckOptions::grid`]: polar angles from 0 to 89.9
/// degrees (both included) and azimuths over the circle.
pub fn direction_grid(n: usize) -> Vec<Vec3> {
    let n = n.max(2);
    let mut dirs = Vec::with_capacity(2 * n * n);
    for i in 0..n {
        let deg = 89.9 * i as f32 / (n - 1) as f32;
        let (s, c) = deg.to_radians().sin_cos();
        for j in 0..2 * n {
            let phi = std::f32::consts::TAU * (j as f32 + 0.25) / (2 * n) as f32;
            dirs.push(spherical_direction(s, c, phi));
        }
    }
    dirs
}

/// Measures positivity, reciprocity and the energy albedo of `brdf` (see [`Plausibility`]).
pub fn plausibility<B: Brdf + ?Sized>(brdf: &B, options: &CheckOptions) -> Plausibility {
    let dirs = direction_grid(options.grid);
    let mut min_value = f32::INFINITY;
    let mut non_finite = 0;
    let mut reciprocity_error = 0.0f32;
    for (a, &wo) in dirs.iter().enumerate() {
        for &wi in &dirs[a..] {
            let f = brdf.eval(wo, wi);
            let r = brdf.eval(wi, wo);
            for (x, y) in f.to_array().into_iter().zip(r.to_array()) {
                if !(x.is_finite() && y.is_finite()) {
                    non_finite += 1;
                    continue;
                }
                min_value = min_value.min(x).min(y);
                let scale = x.abs().max(y.abs());
                if scale > 0.0 {
                    reciprocity_error = reciprocity_error.max((x - y).abs() / scale);
                }
            }
        }
    }
    let albedo = options
        .incidence_deg
        .iter()
        .map(|&deg| {
            let a = incident_albedo(brdf, direction_at_deg(deg), options.quadrature);
            if !a.is_finite() {
                non_finite += 1;
            }
            AlbedoRow {
                incidence_deg: deg,
                albedo: a,
            }
        })
        .collect();
    Plausibility {
        min_value,
        non_finite,
        reciprocity_error,
        albedo,
    }
}

/// Settings of the chi-square test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chi2Options {
    /// Cells along cos theta in [0, 1] (odd).
    pub cos_theta_res: usize,
    /// Cells along phi in [0, 2 pi) (odd).
    pub phi_res: usize,
    /// Number of samples drawn.
    pub samples: usize,
    /// Seed of the sample sequence.
    pub seed: u64,
    /// Significance level of the whole family of tests (before the Sidak correction).
    pub significance: f64,
    /// How many tests the family holds (Sidak: each uses 1 - (1 - significance)^(1/tests)).
    pub tests: usize,
    /// Cells expecting fewer samples than this are pooled together.
    pub min_expected: f64,
    /// Sub-cells per axis when integrating the density over a cell (midpoint rule).
    pub integration_res: usize,
}

impl Default for Chi2Options {
    fn default() -> Self {
        Self {
            cos_theta_res: 51,
            phi_res: 101,
            samples: 1_000_000,
            seed: 0x2ba5_5b2f,
            significance: 0.01,
            tests: 1,
            min_expected: 5.0,
            integration_res: 6,
        }
    }
}

/// The outcome of [`chi2_test`], with the tables for inspection.
#[derive(Debug, Clone, PartialEq)]
pub struct Chi2Report {
    /// The options used.
    pub options: Chi2Options,
    /// Observed counts per cell, row-major (cos theta rows, phi columns).
    pub observed: Vec<f64>,
    /// Expected counts per cell (density integrated over the cell times the sample count).
    pub expected: Vec<f64>,
    /// Samples that were rejected (`None`), i.e. fell below the horizon.
    pub rejected: usize,
    /// The chi-square statistic after pooling.
    pub chi2: f64,
    /// Degrees of freedom after pooling.
    pub dof: usize,
    /// The p-value: probability of a statistic at least this large if the sampler is right.
    pub p_value: f64,
    /// The per-test significance after the Sidak correction.
    pub threshold: f64,
    /// Whether the test accepts the sampler.
    pub passed: bool,
    /// Why the test failed, or a summary when it passed.
    pub message: String,
}

impl Chi2Report {
    /// The observed and expected tables and the summary, as text (for `target/chi2/`).
    pub fn tables_text(&self) -> String {
        let (rows, cols) = (self.options.cos_theta_res, self.options.phi_res);
        let mut s = String::new();
        let _ = writeln!(s, "# {}", self.message);
        let _ = writeln!(
            s,
            "# rows: cos theta in [0, 1] ({rows} cells, top row cos = 0); columns: phi in [0, 2 pi) ({cols} cells)"
        );
        for (name, table) in [("observed", &self.observed), ("expected", &self.expected)] {
            let _ = writeln!(s, "\n## {name}");
            for r in 0..rows {
                let line: Vec<String> = (0..cols)
                    .map(|c| format!("{:.1}", table[r * cols + c]))
                    .collect();
                let _ = writeln!(s, "{}", line.join(" "));
            }
        }
        s
    }
}

fn cell_of(w: Vec3, rows: usize, cols: usize) -> Option<usize> {
    if !(w.is_finite() && w.z > 0.0) {
        return None;
    }
    let r = ((w.z.min(1.0) * rows as f32) as usize).min(rows - 1);
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += std::f32::consts::TAU;
    }
    let c = ((phi / std::f32::consts::TAU * cols as f32) as usize).min(cols - 1);
    Some(r * cols + c)
}

/// Chi-square goodness of fit of a sampler against its claimed density.
///
/// `sample(u)` maps `u` in [0, 1)^2 to a direction (`None` = rejected sample); `pdf(w)` is the
/// claimed solid-angle density (1/sr) of the accepted directions. Both must describe the upper
/// hemisphere; a sample with z <= 0 or a non-finite component fails the test outright, as does
/// any sample in a cell whose expected count is zero.
pub fn chi2_test(
    mut sample: impl FnMut(Vec2) -> Option<Vec3>,
    mut pdf: impl FnMut(Vec3) -> f64,
    options: Chi2Options,
) -> Chi2Report {
    let (rows, cols) = (options.cos_theta_res.max(1), options.phi_res.max(1));
    let n_cells = rows * cols;
    let mut observed = vec![0.0; n_cells];
    let mut rejected = 0;
    let mut invalid = 0;
    let mut rng = Pcg32::new(options.seed, 0x5eed);
    for _ in 0..options.samples {
        match sample(rng.next_vec2()) {
            None => rejected += 1,
            Some(w) => match cell_of(w, rows, cols) {
                Some(c) => observed[c] += 1.0,
                None => invalid += 1,
            },
        }
    }
    // Expected counts: midpoint rule over k x k sub-cells in (phi, cos theta), where
    // d omega = d phi d cos theta.
    let k = options.integration_res.max(1);
    let dmu = 1.0 / (rows * k) as f64;
    let dphi = 2.0 * PI64 / (cols * k) as f64;
    let mut expected = vec![0.0; n_cells];
    for r in 0..rows {
        for c in 0..cols {
            let mut acc = 0.0;
            for a in 0..k {
                let mu = ((r * k + a) as f64 + 0.5) * dmu;
                let sin = (1.0 - mu * mu).max(0.0).sqrt();
                for b in 0..k {
                    let phi = ((c * k + b) as f64 + 0.5) * dphi;
                    let w = DVec3::new(sin * phi.cos(), sin * phi.sin(), mu).as_vec3();
                    let p = pdf(w);
                    if p.is_finite() && p > 0.0 {
                        acc += p;
                    }
                }
            }
            expected[r * cols + c] = acc * dmu * dphi * options.samples as f64;
        }
    }
    let threshold = 1.0 - (1.0 - options.significance).powf(1.0 / options.tests.max(1) as f64);
    let mut report = Chi2Report {
        options,
        observed,
        expected,
        rejected,
        chi2: 0.0,
        dof: 0,
        p_value: 0.0,
        threshold,
        passed: false,
        message: String::new(),
    };
    if invalid > 0 {
        report.message = format!("{invalid} samples were below the horizon or not finite");
        return report;
    }
    let zero_cells: f64 = (0..n_cells)
        .filter(|&i| report.expected[i] == 0.0)
        .map(|i| report.observed[i])
        .sum();
    if zero_cells > 0.0 {
        report.message = format!("{zero_cells} samples fell in cells where the density is zero");
        return report;
    }
    let mut order: Vec<usize> = (0..n_cells).collect();
    order.sort_by(|&a, &b| report.expected[a].total_cmp(&report.expected[b]));
    let (mut pooled_obs, mut pooled_exp, mut pooled_in) = (0.0, 0.0, 0usize);
    let (mut chi2, mut dof) = (0.0, 0usize);
    for &i in &order {
        let (o, e) = (report.observed[i], report.expected[i]);
        if e == 0.0 && o == 0.0 {
            continue;
        }
        if e < options.min_expected || (pooled_in > 0 && pooled_exp < options.min_expected) {
            pooled_obs += o;
            pooled_exp += e;
            pooled_in += 1;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pooled_exp > 0.0 {
        chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        dof += 1;
    }
    let dof = dof.saturating_sub(1);
    report.chi2 = chi2;
    report.dof = dof;
    report.p_value = chi2_survival(chi2, dof as f64);
    report.passed = dof > 0 && report.p_value >= threshold;
    report.message = format!(
        "chi2 = {chi2:.1}, dof = {dof}, p = {:.4} ({} at corrected significance {threshold:.2e}; {} of {} samples rejected)",
        report.p_value,
        if report.passed {
            "accepted"
        } else {
            "REJECTED"
        },
        rejected,
        options.samples
    );
    report
}

/// [`chi2_test`] of `brdf.sample(wo, .)` against `brdf.pdf(wo, .)`.
pub fn chi2_test_brdf<B: Brdf + ?Sized>(brdf: &B, wo: Vec3, options: Chi2Options) -> Chi2Report {
    chi2_test(
        |u| brdf.sample(wo, u).map(|s| s.wi),
        |w| f64::from(brdf.pdf(wo, w)),
        options,
    )
}

/// P(X >= x) for X chi-square distributed with `dof` degrees of freedom: the regularized upper
/// incomplete gamma function Q(dof / 2, x / 2).
pub fn chi2_survival(x: f64, dof: f64) -> f64 {
    if dof.is_nan() || dof <= 0.0 {
        return 0.0;
    }
    if x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * dof, 0.5 * x)
}

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9; relative error below 1e-14).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI64 / (PI64 * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI64).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized upper incomplete gamma Q(a, x): series for x < a + 1, continued fraction
/// (modified Lentz) otherwise.
fn gamma_q(a: f64, x: f64) -> f64 {
    let lg = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        let p = sum * (-x + a * x.ln() - lg).exp();
        (1.0 - p).clamp(0.0, 1.0)
    } else {
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        ((-x + a * x.ln() - lg).exp() * h).clamp(0.0, 1.0)
    }
}
