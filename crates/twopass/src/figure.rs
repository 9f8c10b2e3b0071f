//! What every plot of the CLI shares: the compiled-in font, the legend's style, and drawing
//! into an RGB buffer that is written as a PNG atomically.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
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
