//! Plain image types: linear RGB [`Image`], display-referred [`Rgb8Image`], and [`Rect`].
//!
//! Conventions (ARCHITECTURE.md, "Conventions"): colour is linear RGB (Rec. 709 / sRGB
//! primaries), `f32` per channel, no alpha; pixels are stored row-major with pixel (0, 0) at the
//! top left; sizes and coordinates are in pixels.

use glam::Vec3;

use crate::error::{CompositeError, Result};
pub use crate::rect::Rect;

pub use twopass_brdf::colour::{LUMINANCE, luminance};

/// `rect` as a region of a `width` x `height` image: an error unless it lies inside.
pub(crate) fn check_region(rect: Rect, width: u32, height: u32) -> Result<()> {
    if rect.fits_in(width, height) {
        Ok(())
    } else {
        Err(CompositeError::Region {
            rect,
            width,
            height,
        })
    }
}

/// A linear RGB image, `f32` per channel, row-major, pixel (0, 0) at the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl Image {
    /// A black `width` x `height` image. Zero sizes are allowed; metrics and writers refuse them.
    pub fn new(width: u32, height: u32) -> Self {
        Self::filled(width, height, Vec3::ZERO)
    }

    /// A `width` x `height` image of one colour.
    pub fn filled(width: u32, height: u32, colour: Vec3) -> Self {
        Self {
            width,
            height,
            pixels: vec![colour; width as usize * height as usize],
        }
    }

    /// An image whose pixel (x, y) is `f(x, y)`; `f` may return `glam::Vec3` or `[f32; 3]`.
    /// Called in row-major order.
    pub fn from_fn<P: Into<Vec3>>(
        width: u32,
        height: u32,
        mut f: impl FnMut(u32, u32) -> P,
    ) -> Self {
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                pixels.push(f(x, y).into());
            }
        }
        Self {
            width,
            height,
            pixels,
        }
    }

    /// Wraps row-major pixels; the length must be `width * height`.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Result<Self> {
        if pixels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(CompositeError::PixelCount {
                width,
                height,
                len: pixels.len(),
            });
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// (width, height) in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The pixels, row-major.
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// The pixels, row-major, mutable.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    /// The pixel vector, row-major.
    pub fn into_pixels(self) -> Vec<Vec3> {
        self.pixels
    }

    /// Pixel (x, y). Panics when out of range, as slice indexing does.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets pixel (x, y). Panics when out of range, as slice indexing does.
    pub fn set(&mut self, x: u32, y: u32, value: Vec3) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize] = value;
    }

    /// The first non-finite pixel in row-major order, as (x, y, value).
    pub fn first_non_finite(&self) -> Option<(u32, u32, Vec3)> {
        let i = self.pixels.iter().position(|p| !p.is_finite())?;
        let w = self.width as usize;
        Some(((i % w) as u32, (i / w) as u32, self.pixels[i]))
    }

    /// `Ok` when every pixel is finite; otherwise the error names `what` (a layer or role).
    pub fn check_finite(&self, what: &str) -> Result<()> {
        match self.first_non_finite() {
            None => Ok(()),
            Some((x, y, v)) => Err(CompositeError::NonFinite {
                path: None,
                layer: Some(what.to_owned()),
                x,
                y,
                value: v.to_array(),
            }),
        }
    }

    /// A copy of the pixels inside `rect`.
    pub fn crop(&self, rect: Rect) -> Result<Image> {
        check_region(rect, self.width, self.height)?;
        Ok(Image::from_fn(rect.width, rect.height, |x, y| {
            self.get(rect.x + x, rect.y + y)
        }))
    }

    /// Applies `f` to every pixel.
    pub fn map(&self, mut f: impl FnMut(Vec3) -> Vec3) -> Image {
        Image {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(|&p| f(p)).collect(),
        }
    }

    /// Per-pixel luminance (see [`luminance`]), row-major.
    pub fn luminance(&self) -> Vec<f32> {
        self.pixels.iter().map(|&p| luminance(p)).collect()
    }

    pub(crate) fn check_same_size(&self, other: &Image, what: &str) -> Result<()> {
        if self.size() == other.size() {
            Ok(())
        } else {
            Err(CompositeError::SizeMismatch {
                what: what.to_owned(),
                expected: self.size(),
                found: other.size(),
            })
        }
    }
}

/// A display-referred 8-bit RGB image (sRGB-encoded), row-major, 3 bytes per pixel, pixel
/// (0, 0) at the top left. This is what PNGs and sheets hold.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rgb8Image {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

impl Rgb8Image {
    /// A `width` x `height` image of one colour.
    pub fn filled(width: u32, height: u32, colour: [u8; 3]) -> Self {
        let n = width as usize * height as usize;
        let mut data = Vec::with_capacity(3 * n);
        for _ in 0..n {
            data.extend_from_slice(&colour);
        }
        Self {
            width,
            height,
            data,
        }
    }

    /// An image whose pixel (x, y) is `f(x, y)`, called in row-major order.
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> [u8; 3]) -> Self {
        let mut data = Vec::with_capacity(3 * width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.extend_from_slice(&f(x, y));
            }
        }
        Self {
            width,
            height,
            data,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// (width, height) in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The bytes, row-major, R G B per pixel.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// Pixel (x, y). Panics when out of range.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Sets pixel (x, y). Panics when out of range.
    pub fn set(&mut self, x: u32, y: u32, value: [u8; 3]) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        self.data[i..i + 3].copy_from_slice(&value);
    }

    /// Copies `src` with its top-left corner at (`x`, `y`), clipped to this image.
    pub fn blit(&mut self, src: &Rgb8Image, x: u32, y: u32) {
        for sy in 0..src.height {
            let ty = y as u64 + sy as u64;
            if ty >= self.height as u64 {
                break;
            }
            let w = src.width.min(self.width.saturating_sub(x)) as usize;
            if w == 0 {
                break;
            }
            let s = 3 * sy as usize * src.width as usize;
            let t = 3 * (ty as usize * self.width as usize + x as usize);
            self.data[t..t + 3 * w].copy_from_slice(&src.data[s..s + 3 * w]);
        }
    }

    /// Fills `rect` (clipped to the image) with one colour.
    pub fn fill_rect(&mut self, rect: Rect, colour: [u8; 3]) {
        let x1 = (rect.x as u64 + rect.width as u64).min(self.width as u64) as u32;
        let y1 = (rect.y as u64 + rect.height as u64).min(self.height as u64) as u32;
        for y in rect.y..y1 {
            for x in rect.x..x1 {
                self.set(x, y, colour);
            }
        }
    }

    /// A copy of the pixels inside `rect`.
    pub fn crop(&self, rect: Rect) -> Result<Rgb8Image> {
        check_region(rect, self.width, self.height)?;
        Ok(Rgb8Image::from_fn(rect.width, rect.height, |x, y| {
            self.get(rect.x + x, rect.y + y)
        }))
    }
}
