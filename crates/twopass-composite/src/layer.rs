//! Named layers of one size, and merging them into a final image.
//!
//! A pass (radiosity, direct specular, mirror paths, ...) renders into its own layer; the final
//! image is their sum, since the passes split the light without overlap (ARCHITECTURE.md, "Hybrid
//! without double counting"). Layer order is kept, and is the order written to EXR.

use crate::error::{CompositeError, Result};
use crate::image::Image;

/// The conventional name of the merged image in a layer set.
pub const FINAL: &str = "final";

/// Named layers, all `width` x `height`, in insertion order, names unique.
#[derive(Clone, Debug, PartialEq)]
pub struct Layers {
    width: u32,
    height: u32,
    layers: Vec<(String, Image)>,
}

impl Layers {
    /// An empty set of `width` x `height` layers.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            layers: Vec::new(),
        }
    }

    /// A set from `(name, image)` pairs; the size is the first image's (0 x 0 when empty).
    pub fn from_vec(layers: Vec<(String, Image)>) -> Result<Self> {
        let (w, h) = layers.first().map_or((0, 0), |(_, i)| i.size());
        let mut set = Self::new(w, h);
        for (name, image) in layers {
            set.push(name, image)?;
        }
        Ok(set)
    }

    /// Adds a layer at the end. The name must be non-empty, unique, free of `.` (it separates
    /// layer from channel in EXR) and of control characters; the image must have the set's size.
    pub fn push(&mut self, name: impl Into<String>, image: Image) -> Result<()> {
        let name = name.into();
        check_name(&name)?;
        if self.get(&name).is_some() {
            return Err(CompositeError::LayerName {
                name,
                reason: "a layer of that name is already in the set",
            });
        }
        if image.size() != (self.width, self.height) {
            return Err(CompositeError::SizeMismatch {
                what: format!("layer '{name}'"),
                expected: (self.width, self.height),
                found: image.size(),
            });
        }
        self.layers.push((name, image));
        Ok(())
    }

    /// [`push`](Self::push), by value, for chaining.
    pub fn with(mut self, name: impl Into<String>, image: Image) -> Result<Self> {
        self.push(name, image)?;
        Ok(self)
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of layers.
    pub fn len(&self) -> usize {
        self.layers.len()
    }

    /// Whether there is no layer.
    pub fn is_empty(&self) -> bool {
        self.layers.is_empty()
    }

    /// The layer called `name`.
    pub fn get(&self, name: &str) -> Option<&Image> {
        self.layers.iter().find(|(n, _)| n == name).map(|(_, i)| i)
    }

    /// The layer called `name`, or [`CompositeError::MissingLayer`].
    pub fn require(&self, name: &str) -> Result<&Image> {
        self.get(name).ok_or_else(|| CompositeError::MissingLayer {
            name: name.to_owned(),
        })
    }

    /// The layer names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.layers.iter().map(|(n, _)| n.as_str())
    }

    /// `(name, image)` pairs, in order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &Image)> {
        self.layers.iter().map(|(n, i)| (n.as_str(), i))
    }

    /// The layers as a vector of pairs.
    pub fn into_vec(self) -> Vec<(String, Image)> {
        self.layers
    }

    /// The pixel-wise sum of the named layers (every one must exist); an empty list gives black.
    pub fn sum(&self, names: &[&str]) -> Result<Image> {
        let mut out = Image::new(self.width, self.height);
        for name in names {
            let layer = self.require(name)?;
            for (o, p) in out.pixels_mut().iter_mut().zip(layer.pixels()) {
                *o += *p;
            }
        }
        Ok(out)
    }

    /// The pixel-wise sum of every layer.
    pub fn sum_all(&self) -> Image {
        let names: Vec<&str> = self.names().collect();
        // Every name exists, so the sum cannot fail.
        self.sum(&names)
            .unwrap_or_else(|_| Image::new(self.width, self.height))
    }

    /// Adds the sum of the `parts` as a new layer called `name` (for example [`FINAL`]), and
    /// returns a reference to it.
    pub fn merge_into(&mut self, name: &str, parts: &[&str]) -> Result<&Image> {
        let merged = self.sum(parts)?;
        self.push(name, merged)?;
        Ok(&self.layers[self.layers.len() - 1].1)
    }
}

fn check_name(name: &str) -> Result<()> {
    let reason = if name.is_empty() {
        "empty"
    } else if name.contains('.') {
        "contains '.', which separates layer and channel in EXR channel names"
    } else if name.chars().any(char::is_control) {
        "contains a control character"
    } else {
        return Ok(());
    };
    Err(CompositeError::LayerName {
        name: name.to_owned(),
        reason,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn merge_is_the_sum_and_sizes_are_checked() {
        let a = Image::filled(2, 1, Vec3::new(1.0, 2.0, 3.0));
        let b = Image::from_fn(2, 1, |x, _| [x as f32, 0.5, 0.25]);
        let mut set = Layers::new(2, 1)
            .with("a", a)
            .unwrap()
            .with("b", b)
            .unwrap();
        let f = set.merge_into(FINAL, &["a", "b"]).unwrap().clone();
        assert_eq!(f.get(0, 0), Vec3::new(1.0, 2.5, 3.25));
        assert_eq!(f.get(1, 0), Vec3::new(2.0, 2.5, 3.25));
        assert_eq!(set.names().collect::<Vec<_>>(), ["a", "b", FINAL]);
        assert!(matches!(
            set.push("c", Image::new(1, 1)),
            Err(CompositeError::SizeMismatch { .. })
        ));
        assert!(matches!(
            set.push("a", Image::new(2, 1)),
            Err(CompositeError::LayerName { .. })
        ));
        assert!(matches!(
            set.push("a.b", Image::new(2, 1)),
            Err(CompositeError::LayerName { .. })
        ));
        assert!(matches!(
            set.sum(&["nope"]),
            Err(CompositeError::MissingLayer { .. })
        ));
    }
}
