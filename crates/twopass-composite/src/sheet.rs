//! Comparison sheets: rows of panels with a caption under each, an optional colour bar at the
//! end of a row, a title on top and a footer (say how the panels were tone mapped), as one 8-bit
//! image; plus the layout, so tests and callers know where every panel went.
//!
//! [`Sheet`] is the general tool. [`comparison`] builds the usual sheet (a row of renders, a
//! row of false-colour differences against the reference) with one exposure and one error
//! scale, and returns the metrics it printed.

use smart_default::SmartDefault;

use crate::error::Result;
use crate::false_colour::{ErrorKind, ErrorMap, Palette, Scale};
use crate::image::{Image, Rect, Rgb8Image};
use crate::metric::{Metrics, compare};
use crate::text;
use crate::tonemap::{Curve, ToneMap};

/// Space around the sheet, pixels.
pub const MARGIN: u32 = 16;
/// Space between columns and between rows, pixels.
pub const GAP: u32 = 12;
/// Space between a panel and its caption, pixels.
pub const CAPTION_PAD: u32 = 4;
/// Height of one caption line, pixels.
pub const LINE: u32 = 19;
/// Caption font size, pixels per em.
pub const CAPTION_PX: f32 = 15.0;
/// Footer font size, pixels per em.
pub const FOOTER_PX: f32 = 13.0;
/// Height of the title line, pixels.
pub const TITLE_LINE: u32 = 28;
/// Title font size, pixels per em.
pub const TITLE_PX: f32 = 20.0;
/// Colour bar width, pixels.
pub const BAR_WIDTH: u32 = 16;
/// Width of the area right of the bars for tick labels, pixels.
pub const BAR_LABELS: u32 = 84;
/// Sheet background.
pub const BACKGROUND: [u8; 3] = [255, 255, 255];
/// Text colour.
pub const INK: [u8; 3] = [20, 20, 20];

/// One panel: an 8-bit image and the caption lines drawn under it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Panel {
    /// The pixels, placed unchanged on the sheet.
    pub image: Rgb8Image,
    /// Caption lines (method, time, error...).
    pub caption: Vec<String>,
}

/// A row of cells (`None` leaves a cell empty, keeping the columns aligned) and an optional
/// colour bar after the last cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The cells, left to right.
    pub cells: Vec<Option<Panel>>,
    /// The scale to show as a colour bar with min/max labels at the end of the row.
    pub bar: Option<Scale>,
}

/// A sheet to draw.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Sheet {
    /// Title line on top, if any.
    pub title: Option<String>,
    /// Rows, top to bottom.
    pub rows: Vec<Row>,
    /// Footer lines at the bottom (for example [`ToneMap::describe`]).
    pub footer: Vec<String>,
}

/// Where everything went on a sheet, in sheet pixels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SheetLayout {
    /// Sheet width.
    pub width: u32,
    /// Sheet height.
    pub height: u32,
    /// Per row, per cell: the panel's rectangle (the size of its image), `None` for empty cells.
    pub panels: Vec<Vec<Option<Rect>>>,
    /// Per row, per cell: the caption area under the panel.
    pub captions: Vec<Vec<Option<Rect>>>,
    /// Per row: the colour bar's rectangle.
    pub bars: Vec<Option<Rect>>,
}

impl Sheet {
    /// Computes the layout: columns as wide as their widest panel, rows as tall as their
    /// tallest panel plus as many caption lines as the longest caption on the sheet; panels at
    /// the top left of their cells.
    pub fn layout(&self) -> SheetLayout {
        let ncols = self.rows.iter().map(|r| r.cells.len()).max().unwrap_or(0);
        let mut col_w = vec![0u32; ncols];
        for row in &self.rows {
            for (c, cell) in row.cells.iter().enumerate() {
                if let Some(p) = cell {
                    col_w[c] = col_w[c].max(p.image.width());
                }
            }
        }
        let lines = self
            .rows
            .iter()
            .flat_map(|r| r.cells.iter().flatten())
            .map(|p| p.caption.len() as u32)
            .max()
            .unwrap_or(0);
        let caption_h = if lines > 0 {
            CAPTION_PAD + lines * LINE
        } else {
            0
        };
        let any_bar = self.rows.iter().any(|r| r.bar.is_some());
        let cols_w: u32 = col_w.iter().sum::<u32>() + GAP * (ncols.saturating_sub(1) as u32);
        let bar_x = MARGIN + cols_w + GAP;
        let mut width = MARGIN
            + cols_w
            + if any_bar {
                GAP + BAR_WIDTH + BAR_LABELS
            } else {
                0
            }
            + MARGIN;
        // The title and footer lines are not clipped: the sheet widens to hold them.
        if let Ok(font) = text::font() {
            let lines = self.title.iter().map(|t| (TITLE_PX, t));
            let lines = lines.chain(self.footer.iter().map(|t| (FOOTER_PX, t)));
            for (px, t) in lines {
                width = width.max(2 * MARGIN + text::width(&font, px, t).ceil() as u32);
            }
        }

        let mut y = MARGIN + if self.title.is_some() { TITLE_LINE } else { 0 };
        let (mut panels, mut captions, mut bars) = (Vec::new(), Vec::new(), Vec::new());
        for (r, row) in self.rows.iter().enumerate() {
            if r > 0 {
                y += GAP;
            }
            let panel_h = row
                .cells
                .iter()
                .flatten()
                .map(|p| p.image.height())
                .max()
                .unwrap_or(0);
            let (mut pr, mut cr) = (Vec::new(), Vec::new());
            let mut x = MARGIN;
            for (c, cell) in row.cells.iter().enumerate() {
                pr.push(
                    cell.as_ref()
                        .map(|p| Rect::new(x, y, p.image.width(), p.image.height())),
                );
                cr.push(cell.as_ref().map(|_| {
                    Rect::new(
                        x,
                        y + panel_h + CAPTION_PAD,
                        col_w[c],
                        caption_h.saturating_sub(CAPTION_PAD),
                    )
                }));
                x += col_w[c] + GAP;
            }
            panels.push(pr);
            captions.push(cr);
            bars.push(
                row.bar
                    .map(|_| Rect::new(bar_x, y, BAR_WIDTH, panel_h.max(2))),
            );
            y += panel_h.max(if row.bar.is_some() { 2 } else { 0 }) + caption_h;
        }
        let height = y
            + self.footer.len() as u32 * LINE
            + if self.footer.is_empty() { 0 } else { GAP }
            + MARGIN;
        SheetLayout {
            width,
            height,
            panels,
            captions,
            bars,
        }
    }

    /// Draws the sheet; panel pixels are copied unchanged.
    pub fn render(&self) -> Result<(Rgb8Image, SheetLayout)> {
        let layout = self.layout();
        let font = text::font()?;
        let mut canvas = Rgb8Image::filled(layout.width, layout.height, BACKGROUND);
        let everywhere = Rect::full(layout.width, layout.height);
        if let Some(t) = &self.title {
            text::draw(
                &mut canvas,
                &font,
                TITLE_PX,
                (MARGIN as f32, MARGIN as f32),
                INK,
                everywhere,
                t,
            );
        }
        for (r, row) in self.rows.iter().enumerate() {
            for (c, cell) in row.cells.iter().enumerate() {
                let (Some(p), Some(rect), Some(cap)) =
                    (cell, layout.panels[r][c], layout.captions[r][c])
                else {
                    continue;
                };
                canvas.blit(&p.image, rect.x, rect.y);
                for (i, line) in p.caption.iter().enumerate() {
                    let top = cap.y + i as u32 * LINE;
                    text::draw(
                        &mut canvas,
                        &font,
                        CAPTION_PX,
                        (cap.x as f32, top as f32),
                        INK,
                        cap,
                        line,
                    );
                }
            }
            if let (Some(scale), Some(rect)) = (row.bar, layout.bars[r]) {
                canvas.blit(&scale.bar(rect.width, rect.height), rect.x, rect.y);
                let lx = (rect.x + rect.width + 6) as f32;
                let labels = Rect::new(
                    rect.x + rect.width,
                    rect.y.saturating_sub(LINE),
                    BAR_LABELS,
                    rect.height + 2 * LINE,
                );
                text::draw(
                    &mut canvas,
                    &font,
                    CAPTION_PX,
                    (lx, rect.y as f32 - 3.0),
                    INK,
                    labels,
                    &format_value(scale.max()),
                );
                let bottom = (rect.y + rect.height) as f32 - LINE as f32 + 3.0;
                text::draw(
                    &mut canvas,
                    &font,
                    CAPTION_PX,
                    (lx, bottom),
                    INK,
                    labels,
                    &format_value(scale.min()),
                );
                let kind_area = Rect::new(
                    rect.x,
                    rect.y + rect.height + CAPTION_PAD,
                    BAR_WIDTH + BAR_LABELS,
                    2 * LINE,
                );
                for (i, word) in scale.kind().label().split(' ').enumerate() {
                    let top = (kind_area.y + i as u32 * LINE) as f32;
                    text::draw(
                        &mut canvas,
                        &font,
                        CAPTION_PX,
                        (rect.x as f32, top),
                        INK,
                        kind_area,
                        word,
                    );
                }
            }
        }
        let mut y = layout.height - MARGIN - self.footer.len() as u32 * LINE;
        for line in &self.footer {
            text::draw(
                &mut canvas,
                &font,
                FOOTER_PX,
                (MARGIN as f32, y as f32),
                INK,
                everywhere,
                line,
            );
            y += LINE;
        }
        Ok((canvas, layout))
    }
}

/// A tick label: 3 significant digits, scientific notation outside [0.01, 1000).
pub fn format_value(v: f32) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (0.01..1000.0).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

/// One method in a comparison: its name, its image (linear RGB) and how long it took.
#[derive(Clone, Copy, Debug)]
pub struct Entry<'a> {
    /// Method name, first caption line.
    pub method: &'a str,
    /// The rendered image, linear RGB.
    pub image: &'a Image,
    /// Time taken in seconds, if known (second caption line).
    pub seconds: Option<f64>,
}

/// Choices for [`comparison`].
#[derive(SmartDefault, Clone, Debug, PartialEq)]
pub struct ComparisonOptions {
    /// The tone map of every render panel; `None` means [`ToneMap::auto_default`] on the
    /// reference, with `curve`.
    pub tone_map: Option<ToneMap>,
    /// The curve used with the automatic exposure.
    #[default(Curve::Clip)]
    pub curve: Curve,
    /// The error shown in the difference row.
    #[default(ErrorKind::Relative)]
    pub error: ErrorKind,
    /// Its colour map.
    #[default(Palette::Viridis)]
    pub palette: Palette,
    /// The colour scale runs from 0 to this percentile of the largest error map (see
    /// [`Scale::shared`]); `None` for a fixed scale in `scale_max`.
    #[default(Some(0.99))]
    pub scale_percentile: Option<f32>,
    /// Top of a fixed colour scale, used when `scale_percentile` is `None`.
    #[default(1.0)]
    pub scale_max: f32,
    /// Sheet title.
    pub title: Option<String>,
}

/// A drawn comparison sheet and the numbers behind it.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The sheet pixels (write with [`crate::write::write_png`] and `describe` as description).
    pub image: Rgb8Image,
    /// Where the panels went: row 0 the renders (reference first), row 1 the differences (the
    /// reference's cell empty).
    pub layout: SheetLayout,
    /// The one tone map of every render panel.
    pub tone_map: ToneMap,
    /// The one colour scale of every difference panel.
    pub scale: Scale,
    /// Metrics of each of `others` against the reference, in order.
    pub metrics: Vec<Metrics>,
    /// What the sheet shows and how it was tone mapped, for the PNG's description.
    pub describe: String,
}

/// Builds the standard comparison: row 0 the reference then every other method, tone mapped
/// with one exposure; row 1 their false-colour differences against the reference on one scale,
/// with the colour bar. Captions: method, time, relative RMSE and SSIM.
pub fn comparison(
    reference: &Entry<'_>,
    others: &[Entry<'_>],
    options: &ComparisonOptions,
) -> Result<Comparison> {
    let tone_map = match options.tone_map {
        Some(t) => t,
        None => ToneMap::auto_default(reference.image)?.with_curve(options.curve),
    };
    let mut maps = Vec::with_capacity(others.len());
    let mut metrics = Vec::with_capacity(others.len());
    for e in others {
        maps.push(ErrorMap::new(e.image, reference.image, options.error)?);
        metrics.push(compare(e.image, reference.image, &tone_map)?);
    }
    let scale = match options.scale_percentile {
        Some(p) if !maps.is_empty() => {
            Scale::shared(&maps.iter().collect::<Vec<_>>(), p, options.palette)?
        }
        Some(_) => Scale::new(0.0, 1.0, options.palette, options.error)?,
        None => Scale::new(0.0, options.scale_max, options.palette, options.error)?,
    };
    let time = |s: Option<f64>| s.map_or_else(|| "time n/a".to_owned(), |s| format!("{s:.2} s"));
    let mut renders = vec![Some(Panel {
        image: tone_map.apply(reference.image),
        caption: vec![
            reference.method.to_owned(),
            time(reference.seconds),
            "reference".into(),
        ],
    })];
    let mut diffs = vec![None];
    for ((e, m), map) in others.iter().zip(&metrics).zip(&maps) {
        renders.push(Some(Panel {
            image: tone_map.apply(e.image),
            caption: vec![
                e.method.to_owned(),
                time(e.seconds),
                format!("rel RMSE {:.2} %", 100.0 * m.rel_rmse),
                format!("SSIM {:.4}", m.ssim),
            ],
        }));
        diffs.push(Some(Panel {
            image: scale.apply(map),
            caption: vec![e.method.to_owned()],
        }));
    }
    let footer = vec![
        format!("Renders {}.", tone_map.describe()),
        format!(
            "Differences: {} against {}, {:?} colour map from {} to {}.",
            options.error.label(),
            reference.method,
            options.palette,
            format_value(scale.min()),
            format_value(scale.max())
        ),
    ];
    let describe = footer.join(" ");
    let sheet = Sheet {
        title: options.title.clone(),
        rows: vec![
            Row {
                cells: renders,
                bar: None,
            },
            Row {
                cells: diffs,
                bar: Some(scale),
            },
        ],
        footer,
    };
    let (image, layout) = sheet.render()?;
    Ok(Comparison {
        image,
        layout,
        tone_map,
        scale,
        metrics,
        describe,
    })
}
