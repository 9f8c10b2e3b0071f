//! Text drawn with the embedded Ubuntu Light font (from `epaint_default_fonts`) through
//! `ab_glyph`: coverage-antialiased glyphs blended over an 8-bit image, clipped to a rectangle.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

use crate::error::{CompositeError, Result};
use crate::image::{Rect, Rgb8Image};

/// The embedded font.
pub(crate) fn font() -> Result<FontRef<'static>> {
    FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT).map_err(CompositeError::Font)
}

/// Width in pixels of `text` at `px` pixels per em (advances and kerning).
pub(crate) fn width(font: &FontRef<'_>, px: f32, text: &str) -> f32 {
    let f = font.as_scaled(PxScale::from(px));
    let mut w = 0.0;
    let mut prev = None;
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            w += f.kern(p, id);
        }
        w += f.h_advance(id);
        prev = Some(id);
    }
    w
}

/// Draws one line of `text` with its top-left corner at `(left, top)`, at `px` pixels per em, in `colour`, touching only pixels inside `clip`.
pub(crate) fn draw(
    canvas: &mut Rgb8Image,
    font: &FontRef<'_>,
    px: f32,
    (left, top): (f32, f32),
    colour: [u8; 3],
    clip: Rect,
    text: &str,
) {
    let f = font.as_scaled(PxScale::from(px));
    let baseline = top + f.ascent();
    let mut x = left;
    let mut prev = None;
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            x += f.kern(p, id);
        }
        let glyph = id.with_scale_and_position(PxScale::from(px), point(x, baseline));
        x += f.h_advance(id);
        prev = Some(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue; // spaces have no outline
        };
        let b = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let px_ = b.min.x as i64 + i64::from(gx);
            let py_ = b.min.y as i64 + i64::from(gy);
            if px_ < 0 || py_ < 0 {
                return;
            }
            let (px_, py_) = (px_ as u32, py_ as u32);
            if !clip.contains(px_, py_) || px_ >= canvas.width() || py_ >= canvas.height() {
                return;
            }
            let a = coverage.clamp(0.0, 1.0);
            let d = canvas.get(px_, py_);
            let mut o = [0u8; 3];
            for i in 0..3 {
                o[i] = (f32::from(d[i]) * (1.0 - a) + f32::from(colour[i]) * a).round() as u8;
            }
            canvas.set(px_, py_, o);
        });
    }
}
