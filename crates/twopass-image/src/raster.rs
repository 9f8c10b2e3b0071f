//! [`Raster`]: a row-major grid of pixels, and its two kinds, the linear [`Image`] and the
//! display-referred [`Rgb8Image`].

use glam::{DVec3, Vec3};
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance;

use crate::error::ImageError;
use crate::rect::Rect;

/// A `width` x `height` grid of pixels of type `P`, row-major, pixel (0, 0) at the top left.
/// The pixel vector always holds `width * height` pixels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Raster<P> {
    width: u32,
    height: u32,
    pixels: Vec<P>,
}

/// A linear RGB image, `f32` per channel (a renderer's radiance, W/(m^2 sr) per channel).
pub type Image = Raster<Rgb>;

/// A display-referred 8-bit RGB image (sRGB-encoded), 3 bytes per pixel: what PNGs and sheets
/// hold.
pub type Rgb8Image = Raster<[u8; 3]>;

impl<P: Copy> Raster<P> {
    /// A `width` x `height` raster of one pixel value. Zero sizes are allowed; the compositor's
    /// metrics and writers refuse them.
    pub fn filled(width: u32, height: u32, value: P) -> Self {
        Self {
            width,
            height,
            pixels: vec![value; width as usize * height as usize],
        }
    }

    /// A raster whose pixel (x, y) is `f(x, y)` (for an [`Image`], `glam::Vec3` or
    /// `[f32; 3]`). Called in row-major order.
    pub fn from_fn<Q: Into<P>>(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> Q) -> Self {
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
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<P>) -> Result<Self, ImageError> {
        if pixels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(ImageError::PixelCount {
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
    pub fn pixels(&self) -> &[P] {
        &self.pixels
    }

    /// The pixels, row-major, mutable.
    pub fn pixels_mut(&mut self) -> &mut [P] {
        &mut self.pixels
    }

    /// The pixel vector, row-major.
    pub fn into_pixels(self) -> Vec<P> {
        self.pixels
    }

    /// The index of pixel (x, y) in [`Raster::pixels`]. Panics when out of range, as slice
    /// indexing does.
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// Pixel (x, y). Panics when out of range, as slice indexing does.
    pub fn get(&self, x: u32, y: u32) -> P {
        self.pixels[self.index(x, y)]
    }

    /// Sets pixel (x, y). Panics when out of range, as slice indexing does.
    pub fn set(&mut self, x: u32, y: u32, value: P) {
        let i = self.index(x, y);
        self.pixels[i] = value;
    }

    /// Applies `f` to every pixel.
    pub fn map(&self, f: impl FnMut(P) -> P) -> Self {
        Self {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().copied().map(f).collect(),
        }
    }

    /// `Ok` when `rect` lies inside this raster.
    pub fn check_region(&self, rect: Rect) -> Result<(), ImageError> {
        if rect.fits_in(self.width, self.height) {
            Ok(())
        } else {
            Err(ImageError::Region {
                rect,
                width: self.width,
                height: self.height,
            })
        }
    }

    /// A copy of the pixels inside `rect`.
    pub fn crop(&self, rect: Rect) -> Result<Self, ImageError> {
        self.check_region(rect)?;
        Ok(Self::from_fn(rect.width, rect.height, |x, y| {
            self.get(rect.x + x, rect.y + y)
        }))
    }

    /// Copies `src` with its top-left corner at (`x`, `y`), clipped to this raster.
    pub fn blit(&mut self, src: &Self, x: u32, y: u32) {
        for sy in 0..src.height {
            let ty = y as u64 + sy as u64;
            if ty >= self.height as u64 {
                break;
            }
            let w = src.width.min(self.width.saturating_sub(x)) as usize;
            if w == 0 {
                break;
            }
            let s = sy as usize * src.width as usize;
            let t = ty as usize * self.width as usize + x as usize;
            self.pixels[t..t + w].copy_from_slice(&src.pixels[s..s + w]);
        }
    }

    /// Fills `rect` (clipped to the raster) with one value.
    pub fn fill_rect(&mut self, rect: Rect, value: P) {
        let x1 = (rect.x as u64 + rect.width as u64).min(self.width as u64) as u32;
        let y1 = (rect.y as u64 + rect.height as u64).min(self.height as u64) as u32;
        for y in rect.y..y1 {
            for x in rect.x..x1 {
                self.set(x, y, value);
            }
        }
    }
}

impl Raster<Rgb> {
    /// A black `width` x `height` image. Zero sizes are allowed; metrics and writers refuse them.
    pub fn new(width: u32, height: u32) -> Self {
        Self::filled(width, height, Vec3::ZERO)
    }

    /// The first non-finite pixel in row-major order, as (x, y, value).
    pub fn first_non_finite(&self) -> Option<(u32, u32, Rgb)> {
        let i = self.pixels.iter().position(|p| !p.is_finite())?;
        let w = self.width as usize;
        Some(((i % w) as u32, (i / w) as u32, self.pixels[i]))
    }

    /// `Ok` when every pixel is finite; otherwise the error names `what` (a layer or role).
    pub fn check_finite(&self, what: &str) -> Result<(), ImageError> {
        match self.first_non_finite() {
            None => Ok(()),
            Some((x, y, v)) => Err(ImageError::NonFinite {
                what: what.to_owned(),
                x,
                y,
                value: v.to_array(),
            }),
        }
    }

    /// Per-pixel luminance (see [`twopass_brdf::colour::luminance`]), row-major.
    pub fn luminance(&self) -> Vec<f32> {
        self.pixels.iter().map(|&p| luminance(p)).collect()
    }

    /// Mean over all pixels, per channel (computed in f64, in pixel order: deterministic).
    pub fn mean(&self) -> Rgb {
        let s = self
            .pixels
            .iter()
            .fold(DVec3::ZERO, |a, p| a + p.as_dvec3());
        (s / self.pixels.len().max(1) as f64).as_vec3()
    }
}

impl Raster<[u8; 3]> {
    /// The bytes, row-major, R G B per pixel.
    pub fn data(&self) -> &[u8] {
        self.pixels.as_flattened()
    }
}
