//! What a render EXR says about how it was made: header attributes beside the pixels.

/// How an image was rendered, written into an EXR's header by
/// [`write_exr_render`](crate::write::write_exr_render) as text attributes
/// `twopass:method`, `twopass:spp`, `twopass:seed`, `twopass:seconds` and `twopass:version`,
/// plus OpenEXR's standard `software` attribute (`twopass <version>`).
#[derive(Debug, Clone, PartialEq)]
pub struct RenderMetadata {
    /// The rendering method's name (`whitted`, `radiosity`, `hybrid`, `hybrid-direct`,
    /// `reference`).
    pub method: String,
    /// Samples per pixel.
    pub samples_per_pixel: u32,
    /// The seed of the per-pixel sample streams.
    pub seed: u64,
    /// Wall-clock time of the render, seconds.
    pub seconds: f64,
    /// The twopass version that rendered it (default: this crate's, which is the workspace's).
    pub version: String,
}

/// The version every twopass crate shares (the workspace version).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

impl RenderMetadata {
    /// Metadata of a render by this build (`version` = [`VERSION`]).
    pub fn new(method: impl Into<String>, samples_per_pixel: u32, seed: u64, seconds: f64) -> Self {
        Self {
            method: method.into(),
            samples_per_pixel,
            seed,
            seconds,
            version: VERSION.to_owned(),
        }
    }

    /// The header attributes, as `(name, text value)` pairs in a fixed order.
    pub fn attributes(&self) -> [(&'static str, String); 5] {
        [
            ("twopass:method", self.method.clone()),
            ("twopass:spp", self.samples_per_pixel.to_string()),
            ("twopass:seed", self.seed.to_string()),
            ("twopass:seconds", format!("{}", self.seconds)),
            ("twopass:version", self.version.clone()),
        ]
    }
}
