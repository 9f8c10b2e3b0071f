//! The tradeoff plot: relative RMSE against wall-clock time, log-log, one colour per method,
//! each method's own front drawn as a curve, the front of all methods as a thick dashed line,
//! the presets labelled, and the reference's own noise as the floor.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::report::SweepRow;
use crate::error::CliError;
use crate::figure::{self, FONT, draw_error};
use crate::preset::Preset;

const W: u32 = 960;
const H: u32 = 640;

/// Time against error, both on log scales.
const AXES: figure::Axes = figure::Axes {
    x: "wall-clock time, radiosity solve included (s)",
    y: "relative RMSE vs converged reference (%)",
    desc_size: 16,
    grid: 236,
};

/// A method's colour (the same in every plot).
fn colour(method: &str) -> RGBColor {
    match method {
        "reference" => RGBColor(90, 90, 90),
        "whitted" => RGBColor(214, 39, 40),
        "radiosity" => RGBColor(31, 119, 180),
        "radiosity-gathered" => RGBColor(23, 190, 207),
        "hybrid" => RGBColor(255, 127, 14),
        "hybrid-classic" => RGBColor(148, 103, 189),
        _ => RGBColor(44, 160, 44), // hybrid-direct
    }
}

/// Draws the plot and writes it as a PNG (atomically).
pub fn plot(
    path: &Path,
    title: &str,
    rows: &[SweepRow],
    presets: &[Preset],
    noise_floor: f64,
) -> Result<(), CliError> {
    let finite = || {
        rows.iter()
            .filter(|r| r.total_seconds > 0.0 && r.rel_rmse > 0.0)
            .filter(|r| r.total_seconds.is_finite() && r.rel_rmse.is_finite())
    };
    let (t0, t1) = finite().fold((f64::INFINITY, 0.0f64), |(a, b), r| {
        (a.min(r.total_seconds), b.max(r.total_seconds))
    });
    let (e0, e1) = finite().fold((noise_floor.max(1e-6), 0.0f64), |(a, b), r| {
        (a.min(r.rel_rmse), b.max(r.rel_rmse))
    });
    if !(t0.is_finite() && t1 > 0.0 && e1 > 0.0) {
        return Err(draw_error(path)(
            "no run with a positive time and error to plot".into(),
        ));
    }
    // Percent on the error axis; a little room around the points.
    let (x0, x1) = (t0 / 1.6, t1 * 1.6);
    let (y0, y1) = (100.0 * e0 / 1.4, 100.0 * e1 * 1.4);
    figure::png(path, W, H, |root| {
        let mut chart = figure::titled(root, title)
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| e.to_string())?;
        AXES.draw(&mut chart)?;

        // The reference's own noise: no error below it can be told apart.
        let floor = 100.0 * noise_floor;
        if floor > y0 {
            chart
                .draw_series(LineSeries::new(
                    [(x0, floor), (x1, floor)],
                    RGBColor(160, 160, 160).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?
                .label(format!("reference noise {floor:.2} %"))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RGBColor(160, 160, 160)));
        }

        let mut methods: Vec<&str> = Vec::new();
        for r in rows {
            if !methods.contains(&r.method) {
                methods.push(r.method);
            }
        }
        for &m in &methods {
            let c = colour(m);
            let mine = || finite().filter(move |r| r.method == m);
            chart
                .draw_series(
                    mine()
                        .map(|r| Circle::new((r.total_seconds, 100.0 * r.rel_rmse), 3, c.filled())),
                )
                .map_err(|e| e.to_string())?
                .label(m.to_owned())
                .legend(move |(x, y)| Circle::new((x + 9, y), 4, c.filled()));
            let mut curve: Vec<(f64, f64)> = mine()
                .filter(|r| r.method_pareto)
                .map(|r| (r.total_seconds, 100.0 * r.rel_rmse))
                .collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(curve, c.stroke_width(2)))
                .map_err(|e| e.to_string())?;
        }

        // The front of all methods: a staircase (each point is best until the next one).
        let mut front: Vec<(f64, f64)> = finite()
            .filter(|r| r.pareto)
            .map(|r| (r.total_seconds, 100.0 * r.rel_rmse))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut stairs = Vec::with_capacity(2 * front.len());
        for (k, &(t, e)) in front.iter().enumerate() {
            stairs.push((t, e));
            if let Some(&(next, _)) = front.get(k + 1) {
                stairs.push((next, e));
            }
        }
        if let Some(&(_, e)) = front.last() {
            stairs.push((x1, e));
        }
        chart
            .draw_series(DashedLineSeries::new(stairs, 7, 5, BLACK.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label("Pareto front (all methods)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(2)));
        chart
            .draw_series(
                front
                    .iter()
                    .map(|&p| Circle::new(p, 6, BLACK.stroke_width(2))),
            )
            .map_err(|e| e.to_string())?;

        // Presets sharing a run share one label.
        let mut labels: Vec<((f64, f64), String)> = Vec::new();
        for p in presets {
            let at = (p.measured_seconds, 100.0 * p.measured_rel_rmse);
            match labels.iter_mut().find(|(q, _)| *q == at) {
                Some((_, names)) => names.push_str(&format!(", {}", p.name)),
                None => labels.push((at, p.name.clone())),
            }
        }
        for (at, names) in labels {
            let method = presets
                .iter()
                .find(|p| (p.measured_seconds, 100.0 * p.measured_rel_rmse) == at)
                .map_or("", |p| p.method.name());
            // Labels right of their point, or left of it in the right third of the plot.
            let right_third = at.0.ln() > x0.ln() + 2.0 * (x1.ln() - x0.ln()) / 3.0;
            let (offset, h) = if right_third {
                ((-8, -6), HPos::Right)
            } else {
                ((8, -6), HPos::Left)
            };
            let style = (FONT, 15)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(h, VPos::Bottom));
            chart
                .draw_series([
                    EmptyElement::at(at) + Text::new(format!("{names} ({method})"), offset, style)
                ])
                .map_err(|e| e.to_string())?;
        }
        figure::legend(&mut chart, SeriesLabelPosition::LowerLeft, 14)?;
        Ok(())
    })
}
