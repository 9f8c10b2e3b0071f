//! Rectangles of pixels: plain data that images, sheets and errors share. Coordinates and sizes
//! are in pixels.

/// An axis-aligned rectangle of pixels: columns `x .. x + width`, rows `y .. y + height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Rect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Rect {
    /// The rectangle at (`x`, `y`) of `width` x `height` pixels.
    pub const fn new(x: u32, y: u32, width: u32, height: u32) -> Self {
        Self {
            x,
            y,
            width,
            height,
        }
    }

    /// The whole of a `width` x `height` image.
    pub const fn full(width: u32, height: u32) -> Self {
        Self::new(0, 0, width, height)
    }

    /// Number of pixels.
    pub fn area(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// Whether the rectangle lies inside a `width` x `height` image.
    pub fn fits_in(&self, width: u32, height: u32) -> bool {
        u64::from(self.x) + u64::from(self.width) <= u64::from(width)
            && u64::from(self.y) + u64::from(self.height) <= u64::from(height)
    }

    /// Whether pixel (`px`, `py`) is inside.
    pub fn contains(&self, px: u32, py: u32) -> bool {
        px >= self.x && py >= self.y && px - self.x < self.width && py - self.y < self.height
    }

    /// Whether two rectangles share a pixel.
    pub fn overlaps(&self, other: &Rect) -> bool {
        let (a0, a1) = (u64::from(self.x), u64::from(self.x) + u64::from(self.width));
        let (b0, b1) = (
            u64::from(other.x),
            u64::from(other.x) + u64::from(other.width),
        );
        let (c0, c1) = (
            u64::from(self.y),
            u64::from(self.y) + u64::from(self.height),
        );
        let (d0, d1) = (
            u64::from(other.y),
            u64::from(other.y) + u64::from(other.height),
        );
        a0 < b1 && b0 < a1 && c0 < d1 && d0 < c1
    }
}
