//! What every plot of the CLI shares: the compiled-in font, the legend's style, and drawing
//! into an RGB buffer that is written as a PNG atomically.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;

use crate::error::CliError;
use crate::output::write_png_rgb8;

/// The font family every plot uses (Ubuntu Light, compiled in).
pub const FONT: &str = "sans-serif";

/// Registers the compiled-in font once.
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; registering it cannot fail for valid TrueType bytes, and if it
        // did, text drawing reports the error through the plot's Result.
        let _ = plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// A drawing error as the CLI's error for the file being drawn.
pub fn draw_error(path: &Path) -> impl Fn(String) -> CliError + '_ {
    move |message| CliError::Encode {
        path: PathBuf::from(path),
        message,
    }
}

/// The legend box of every plot: translucent white, light grey border, `size`-point labels.
pub fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, size))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(|e| e.to_string())
}

/// A chart on `root` whose caption is `title` in the style of every figure's title (22-point).
pub fn titled<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, DB> {
    let mut chart = ChartBuilder::on(root);
    chart.caption(title, (FONT, 22));
    chart
}

/// How a plot's axes are drawn: their descriptions, the size of those descriptions (points)
/// and the grey of the light grid lines (each figure keeps its own published values). Tick
/// labels are 14-point for every plot.
pub struct Axes<'a> {
    /// Description of the x axis.
    pub x: &'a str,
    /// Description of the y axis.
    pub y: &'a str,
    /// Size of the descriptions, points.
    pub desc_size: u32,
    /// Grey level (0 to 255) of the light grid lines.
    pub grid: u8,
}

impl Axes<'_> {
    /// Draws the axes, ticks, labels and grid of `chart` in this style.
    pub fn draw<'a, DB, X, Y>(
        &self,
        chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    ) -> Result<(), String>
    where
        DB: DrawingBackend + 'a,
        X: Ranged + ValueFormatter<X::ValueType>,
        Y: Ranged + ValueFormatter<Y::ValueType>,
    {
        let grid = RGBColor(self.grid, self.grid, self.grid);
        chart
            .configure_mesh()
            .x_desc(self.x)
            .y_desc(self.y)
            .label_style((FONT, 14))
            .axis_desc_style((FONT, self.desc_size))
            .light_line_style(grid)
            .draw()
            .map_err(|e| e.to_string())
    }
}

/// Draws a `width` x `height` figure on white with `draw` and writes it to `path` as PNG.
pub fn png(
    path: &Path,
    width: u32,
    height: u32,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<(), CliError> {
    register_font();
    let mut buf = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| draw_error(path)(e.to_string()))?;
        draw(&root).map_err(draw_error(path))?;
        root.present()
            .map_err(|e| draw_error(path)(e.to_string()))?;
    }
    write_png_rgb8(path, width, height, &buf)
}
