//! What a render produces: named linear RGB layers that sum to the image, each a
//! [`twopass_image::Image`], the compositor's image type too (no conversion between them).
//! Every value is a radiance in W/(m^2 sr) per channel (scene units for areas), the mean over a
//! pixel's camera samples.

use std::ops::{Add, AddAssign, Mul};

use twopass_brdf::Rgb;
use twopass_image::Image;

/// The named layers of a render. Each camera sample's radiance is split among them by what
/// the light did at the first surface the camera ray met; their sum is the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Layer {
    /// Light emitted toward the camera by the surface it sees first (one-sided emitters).
    Emission,
    /// Light reflected diffusely at the first surface: from the radiosity solution (radiosity
    /// alone, hybrid-classic), from shadow rays (Whitted, the direct part of the hybrid and
    /// hybrid-direct, plus the gather rays or the radiosity indirect part there), or every
    /// diffusely reflected path (reference).
    Diffuse,
    /// Light reflected by the glossy lobe (Phong, Blinn-Phong, Cook-Torrance) at the first
    /// surface: from emitters with shadow rays (Whitted, hybrid); the reference path tracer also
    /// puts glossy-reflected indirect light here, having no separate term for it.
    DirectSpecular,
    /// Everything seen through a delta reflection at the first surface (mirror, conductor, the
    /// Fresnel-reflected part of a dielectric), whatever happens further along the path.
    Reflection,
    /// Everything seen through a refraction at the first surface (dielectric transmission).
    Refraction,
    /// The Phong ambient term k_a I_amb of the Whitted tracer (zero for the other methods).
    Ambient,
}

impl Layer {
    /// All layers, in the order of [`LayerImages::images`].
    pub const ALL: [Layer; 6] = [
        Layer::Emission,
        Layer::Diffuse,
        Layer::DirectSpecular,
        Layer::Reflection,
        Layer::Refraction,
        Layer::Ambient,
    ];

    /// The layer's name in output files: `emission`, `diffuse`, `direct_specular`,
    /// `reflection`, `refraction`, `ambient`.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Emission => "emission",
            Layer::Diffuse => "diffuse",
            Layer::DirectSpecular => "direct_specular",
            Layer::Reflection => "reflection",
            Layer::Refraction => "refraction",
            Layer::Ambient => "ambient",
        }
    }

    /// Position in [`Layer::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// The radiance one camera sample carries, split by [`Layer`]; W/(m^2 sr) per channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Radiance {
    /// One value per layer, indexed by [`Layer::index`].
    pub layers: [Rgb; 6],
}

impl Radiance {
    /// No light.
    pub const ZERO: Self = Self {
        layers: [Rgb::ZERO; 6],
    };

    /// `value` in layer `layer` alone.
    pub fn single(layer: Layer, value: Rgb) -> Self {
        let mut r = Self::ZERO;
        r.layers[layer.index()] = value;
        r
    }

    /// Adds `value` to layer `layer`.
    #[inline]
    pub fn add(&mut self, layer: Layer, value: Rgb) {
        self.layers[layer.index()] += value;
    }

    /// The value of layer `layer`.
    pub fn get(&self, layer: Layer) -> Rgb {
        self.layers[layer.index()]
    }

    /// The sum of all layers: the pixel's radiance.
    pub fn total(&self) -> Rgb {
        self.layers.iter().fold(Rgb::ZERO, |a, &b| a + b)
    }

    /// Whether every channel of every layer is finite.
    pub fn is_finite(&self) -> bool {
        self.layers.iter().all(|l| l.is_finite())
    }
}

impl Add for Radiance {
    type Output = Self;
    fn add(mut self, rhs: Self) -> Self {
        self += rhs;
        self
    }
}

impl AddAssign for Radiance {
    fn add_assign(&mut self, rhs: Self) {
        for (a, b) in self.layers.iter_mut().zip(rhs.layers) {
            *a += b;
        }
    }
}

impl Mul<f32> for Radiance {
    type Output = Self;
    fn mul(self, s: f32) -> Self {
        Self {
            layers: self.layers.map(|l| l * s),
        }
    }
}

/// One [`Image`] per [`Layer`], all the same size: radiance in W/(m^2 sr) per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerImages {
    /// Indexed by [`Layer::index`].
    pub images: [Image; 6],
}

impl LayerImages {
    /// Six black images of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            images: std::array::from_fn(|_| Image::new(width, height)),
        }
    }

    /// The image of one layer.
    pub fn layer(&self, layer: Layer) -> &Image {
        &self.images[layer.index()]
    }

    /// Width, pixels.
    pub fn width(&self) -> u32 {
        self.images[0].width()
    }

    /// Height, pixels.
    pub fn height(&self) -> u32 {
        self.images[0].height()
    }

    /// The sum of the layers, in [`Layer::ALL`] order per pixel: the rendered image.
    pub fn composite(&self) -> Image {
        let mut out = Image::new(self.width(), self.height());
        for img in &self.images {
            for (o, p) in out.pixels_mut().iter_mut().zip(img.pixels()) {
                *o += *p;
            }
        }
        out
    }
}
