//! Atomic EXR and PNG writes, and reading EXRs back.
//!
//! Every write encodes the whole file in memory first, then writes it to a temporary file in
//! the destination's folder, syncs it and renames it over the destination. A failed write
//! (bad pixels, encoder error, full disk) leaves the destination as it was and no temporary file
//! behind. Non-finite pixels are refused before anything touches the disk, with an error naming
//! the file, the layer and the pixel.
//!
//! EXR files are linear, 32-bit float, ZIP-compressed scanlines, one part. A layer set is
//! written the way OpenEXR names layers in one part: the final image as plain `R`, `G`, `B`
//! (what a viewer or a tool that reads "the" image shows first), and every layer beside it as
//! channels `<layer>.R`, `<layer>.G`, `<layer>.B` (as Blender's multilayer files, tev and
//! OpenEXR's tools read them); a single image is written as plain `R`, `G`, `B`, and a
//! render's final image alone as plain `R`, `G`, `B`, `A` ([`encode_exr_rgba`]). A render's
//! [`RenderMetadata`] goes into the header as text attributes. PNGs are 8-bit sRGB with an `sRGB` chunk and, when
//! given, a `Description` text chunk that says how they were tone mapped.

use std::io::{Cursor, Write};
use std::path::Path;

use exr::prelude as ex;
use exr::prelude::{ReadChannels, ReadLayers, WritableImage};
use glam::Vec3;

use crate::error::{CompositeError, Result, WriteError};
use crate::image::{Image, Rgb8Image};
use crate::layer::{FINAL, Layers};
use crate::metadata::RenderMetadata;
use crate::tonemap::ToneMap;

/// Writes `bytes` to `path` atomically: a temporary file in the same folder (which must exist),
/// synced, then renamed over `path`, with the mode a new file would get (0666 less the umask).
/// On failure the temporary file is removed and `path` is untouched.
///
/// This is the one atomic write of the workspace (ARCHITECTURE.md, "Where each idea lives"):
/// images, bake files, reports and presets all go through it.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::result::Result<(), WriteError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| WriteError { path: p, source }
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".twopass-").suffix(".tmp");
    // Temporary files are private (0600) by default; an output gets the usual mode.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir).map_err(io(dir))?;
    tmp.write_all(bytes).map_err(io(path))?;
    tmp.as_file().sync_all().map_err(io(path))?;
    // On error the returned temporary file is dropped, which deletes it.
    tmp.persist(path).map_err(|e| io(path)(e.error))?;
    Ok(())
}

fn refuse_non_finite(path: &Path, layer: &str, image: &Image) -> Result<()> {
    match image.first_non_finite() {
        None => Ok(()),
        Some((x, y, v)) => Err(CompositeError::NonFinite {
            path: Some(path.to_path_buf()),
            layer: Some(layer.to_owned()),
            x,
            y,
            value: v.to_array(),
        }),
    }
}

/// Encodes one EXR part holding every `(prefix, image)`: channels `prefix.R/G/B`, or `R/G/B`
/// for an empty prefix, with `metadata` (name, value) as text header attributes and the `software`
/// attribute always. All images have one size (checked by the callers).
fn encode_exr(
    path: &Path,
    parts: &[(&str, &Image)],
    metadata: &[(&str, String)],
    alpha: bool,
) -> Result<Vec<u8>> {
    let Some((_, first)) = parts.first() else {
        return Err(CompositeError::Empty {
            what: format!("layer set for {}", path.display()),
        });
    };
    let (w, h) = first.size();
    if w == 0 || h == 0 {
        return Err(CompositeError::Empty {
            what: format!("image for {}", path.display()),
        });
    }
    // Named layers first: a non-finite pixel is reported in the pass it comes from rather
    // than in the final image summed from it.
    let (plain, named): (Vec<_>, Vec<_>) = parts.iter().partition(|(n, _)| n.is_empty());
    for (name, image) in named.into_iter().chain(plain) {
        refuse_non_finite(path, if name.is_empty() { "image" } else { name }, image)?;
    }
    let mut channels: ex::SmallVec<[ex::AnyChannel<ex::FlatSamples>; 4]> = ex::SmallVec::new();
    for (prefix, image) in parts {
        for (c, letter) in ["R", "G", "B"].iter().enumerate() {
            let name = if prefix.is_empty() {
                (*letter).to_owned()
            } else {
                format!("{prefix}.{letter}")
            };
            let samples: Vec<f32> = image.pixels().iter().map(|p| p[c]).collect();
            let text = ex::Text::new_or_none(&name).ok_or_else(|| CompositeError::LayerName {
                name: (*prefix).to_owned(),
                reason: "not representable as an EXR channel name",
            })?;
            channels.push(ex::AnyChannel::new(text, ex::FlatSamples::F32(samples)));
        }
    }
    if alpha {
        let opaque = vec![1.0f32; w as usize * h as usize];
        let name = ex::Text::new_or_none("A").expect("a valid channel name");
        channels.push(ex::AnyChannel::new(name, ex::FlatSamples::F32(opaque)));
    }
    let text = |value: &str, what: &str| {
        ex::Text::new_or_none(value).ok_or_else(|| CompositeError::LayerName {
            name: what.to_owned(),
            reason: "not representable as EXR header text",
        })
    };
    let mut attributes = ex::LayerAttributes {
        software_name: Some(text(
            &format!("twopass {}", crate::metadata::VERSION),
            "software",
        )?),
        ..ex::LayerAttributes::default()
    };
    for (name, value) in metadata {
        attributes.other.insert(
            text(name, name)?,
            exr::meta::attribute::AttributeValue::Text(text(value, name)?),
        );
    }
    let layer = ex::Layer::new(
        ex::Vec2(w as usize, h as usize),
        attributes,
        ex::Encoding::SMALL_LOSSLESS,
        ex::AnyChannels::sort(channels),
    );
    let mut buf = Cursor::new(Vec::new());
    // Blocks compress on all cores (exr's own short-lived pool): ZIP is most of the time a
    // render's EXR takes to write.
    ex::Image::from_layer(layer)
        .write()
        .to_buffered(&mut buf)
        .map_err(|source| CompositeError::Exr {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(buf.into_inner())
}

/// Encodes one linear image as EXR bytes with channels `R`, `G`, `B` (32-bit float); `path`
/// only names the file in errors.
pub fn encode_exr_image(path: &Path, image: &Image) -> Result<Vec<u8>> {
    encode_exr(path, &[("", image)], &[], false)
}

/// [`encode_exr_image`] with `attributes` (name, value) as text attributes in the header,
/// which [`read_exr_header`] reads back.
pub fn encode_exr_image_with(
    path: &Path,
    image: &Image,
    attributes: &[(&str, String)],
) -> Result<Vec<u8>> {
    encode_exr(path, &[("", image)], attributes, false)
}

/// What an EXR's header says, read without decoding a pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExrHeader {
    /// Each part's size (width, height), pixels: what decoding it would allocate.
    pub sizes: Vec<(u64, u64)>,
    /// The first part's text attributes, by name.
    pub text: std::collections::BTreeMap<String, String>,
}

/// Reads an EXR's header only: the parts' sizes and the first part's text attributes, so a
/// caller can refuse a file (a size it does not expect: a decompression bomb of a few
/// megabytes can declare gigapixels) before any pixel is decoded.
pub fn read_exr_header(path: &Path) -> Result<ExrHeader> {
    check_regular(path)?;
    let meta =
        exr::meta::MetaData::read_from_file(path, false).map_err(|source| CompositeError::Exr {
            path: path.to_path_buf(),
            source,
        })?;
    let sizes = meta
        .headers
        .iter()
        .map(|h| (h.layer_size.0 as u64, h.layer_size.1 as u64))
        .collect();
    let text = meta
        .headers
        .first()
        .map(|h| {
            h.own_attributes
                .other
                .iter()
                .filter_map(|(k, v)| match v {
                    exr::meta::attribute::AttributeValue::Text(t) => {
                        Some((k.to_string(), t.to_string()))
                    }
                    _ => None,
                })
                .collect()
        })
        .unwrap_or_default();
    Ok(ExrHeader { sizes, text })
}

/// Writes one linear image as an EXR with channels `R`, `G`, `B` (32-bit float), atomically.
pub fn write_exr(path: &Path, image: &Image) -> Result<()> {
    let bytes = encode_exr_image(path, image)?;
    Ok(write_atomic(path, &bytes)?)
}

/// The name of the layer a set's final image is in: [`IMAGE`] (the renderers' merged image)
/// or [`FINAL`], whichever the set has (in that order), or `None`.
pub fn final_layer(layers: &Layers) -> Option<&'static str> {
    [IMAGE, FINAL].into_iter().find(|n| layers.get(n).is_some())
}

/// A layer set's final image: the layer [`final_layer`] names or, when there is none, the sum
/// of every layer (the passes split the light without overlap).
fn final_image(layers: &Layers) -> Result<std::borrow::Cow<'_, Image>> {
    Ok(match final_layer(layers) {
        Some(name) => std::borrow::Cow::Borrowed(layers.require(name)?),
        None => std::borrow::Cow::Owned(layers.sum_all()),
    })
}

/// The layer name under which the twopass renderers put their merged image.
pub const IMAGE: &str = "image";

/// Encodes a layer set as EXR bytes: the final image as plain `R`, `G`, `B` (the layer
/// [`final_layer`] names or, when there is none, the sum of every layer, since the passes
/// split the light without overlap), every layer as `<layer>.R/G/B`, and `metadata` as header
/// attributes.
pub fn encode_exr_layers(
    path: &Path,
    layers: &Layers,
    metadata: Option<&RenderMetadata>,
) -> Result<Vec<u8>> {
    let top = final_image(layers)?;
    let mut parts: Vec<(&str, &Image)> = vec![("", &top)];
    parts.extend(layers.iter());
    let attributes = metadata.map_or_else(Vec::new, |m| m.attributes().to_vec());
    encode_exr(path, &parts, &attributes, false)
}

/// Encodes a layer set's final image alone as a plain RGBA EXR: channels `R`, `G`, `B` (the
/// layer [`final_layer`] names, or the sum of every layer) and `A` = 1 (every pixel is
/// covered: a ray leaving the scene still counts as the scene's background), 32-bit float,
/// with `metadata` as header attributes. What any EXR reader opens as "the" image.
pub fn encode_exr_rgba(
    path: &Path,
    layers: &Layers,
    metadata: Option<&RenderMetadata>,
) -> Result<Vec<u8>> {
    let top = final_image(layers)?;
    let attributes = metadata.map_or_else(Vec::new, |m| m.attributes().to_vec());
    encode_exr(path, &[("", &top)], &attributes, true)
}

/// Writes a render's final image as a plain RGBA EXR with its metadata, atomically; see
/// [`encode_exr_rgba`] ([`write_exr_render`] keeps every layer).
pub fn write_exr_render_rgba(
    path: &Path,
    layers: &Layers,
    metadata: &RenderMetadata,
) -> Result<()> {
    let bytes = encode_exr_rgba(path, layers, Some(metadata))?;
    Ok(write_atomic(path, &bytes)?)
}

/// Writes every layer into one EXR, atomically: the final image as plain `R`, `G`, `B` and
/// each layer as `<layer>.R/G/B` (32-bit float); see [`encode_exr_layers`].
pub fn write_exr_layers(path: &Path, layers: &Layers) -> Result<()> {
    let bytes = encode_exr_layers(path, layers, None)?;
    Ok(write_atomic(path, &bytes)?)
}

/// [`write_exr_layers`] with the render's metadata in the header.
pub fn write_exr_render(path: &Path, layers: &Layers, metadata: &RenderMetadata) -> Result<()> {
    let bytes = encode_exr_layers(path, layers, Some(metadata))?;
    Ok(write_atomic(path, &bytes)?)
}

/// Reads every part and channel of an EXR as `(full channel name, width, height, samples)`;
/// the full name is `<part name>.<channel>` when the part is named (multi-part files).
/// One channel read: full name, width, height, samples.
type Channel = (String, u32, u32, Vec<f32>);

/// Refuses `path` unless it is a regular file, before anything opens it: opening a FIFO
/// blocks until a writer comes, which may be never, and a device never ends. (`metadata`
/// follows symbolic links, as opening does.)
fn check_regular(path: &Path) -> Result<()> {
    let io = |source| CompositeError::Io {
        path: path.to_path_buf(),
        source,
    };
    if std::fs::metadata(path).map_err(io)?.is_file() {
        return Ok(());
    }
    Err(io(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        "not a regular file (a device, pipe or directory is not read as one)",
    )))
}

fn read_channels(path: &Path) -> Result<Vec<Channel>> {
    check_regular(path)?;
    let image = ex::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .non_parallel()
        .from_file(path)
        .map_err(|source| CompositeError::Exr {
            path: path.to_path_buf(),
            source,
        })?;
    let mut out = Vec::new();
    for layer in &image.layer_data {
        let (w, h) = (layer.size.width() as u32, layer.size.height() as u32);
        let part = layer.attributes.layer_name.as_ref().map(|t| t.to_string());
        for ch in &layer.channel_data.list {
            let name = match &part {
                Some(p) => format!("{p}.{}", ch.name),
                None => ch.name.to_string(),
            };
            out.push((name, w, h, ch.sample_data.values_as_f32().collect()));
        }
    }
    Ok(out)
}

fn assemble(path: &Path, prefix: &str, channels: &[Channel]) -> Result<Image> {
    let mut rgb: [Option<&Channel>; 3] = [None; 3];
    for (c, letter) in ["R", "G", "B"].iter().enumerate() {
        let want = if prefix.is_empty() {
            (*letter).to_owned()
        } else {
            format!("{prefix}.{letter}")
        };
        rgb[c] = channels.iter().find(|(n, ..)| *n == want);
        if rgb[c].is_none() {
            return Err(CompositeError::MissingChannel {
                path: path.to_path_buf(),
                channel: want,
            });
        }
    }
    let [Some(r), Some(g), Some(b)] = rgb else {
        unreachable!("checked above")
    };
    let (w, h) = (r.1, r.2);
    for ch in [g, b] {
        if (ch.1, ch.2) != (w, h) {
            return Err(CompositeError::SizeMismatch {
                what: format!("{}: channel {}", path.display(), ch.0),
                expected: (w, h),
                found: (ch.1, ch.2),
            });
        }
    }
    let pixels = (0..r.3.len())
        .map(|i| Vec3::new(r.3[i], g.3[i], b.3[i]))
        .collect();
    Ok(Image::from_pixels(w, h, pixels)?)
}

/// Reads an EXR's plain `R`, `G`, `B` channels as a linear image.
pub fn read_exr(path: &Path) -> Result<Image> {
    let channels = read_channels(path)?;
    assemble(path, "", &channels)
}

/// Reads every layer of an EXR: each channel group `<layer>.R/G/B` becomes a layer (in
/// alphabetical order, as EXR stores channels). Channels without a layer prefix, and groups
/// without all of R, G and B, are skipped.
pub fn read_exr_layers(path: &Path) -> Result<Layers> {
    let channels = read_channels(path)?;
    let mut names: Vec<&str> = channels
        .iter()
        .filter_map(|(n, ..)| n.rsplit_once('.').map(|(p, _)| p))
        .collect();
    names.sort_unstable();
    names.dedup();
    let mut pairs = Vec::new();
    for name in names {
        let has = |l: &str| channels.iter().any(|(n, ..)| *n == format!("{name}.{l}"));
        if has("R") && has("G") && has("B") {
            pairs.push((name.to_owned(), assemble(path, name, &channels)?));
        }
    }
    // Layer names from other tools may hold '.', which `Layers` refuses; keep what it accepts.
    let mut layers = match pairs.first() {
        Some((_, i)) => Layers::new(i.width(), i.height()),
        None => Layers::new(0, 0),
    };
    for (name, image) in pairs {
        match layers.push(name, image) {
            Ok(()) | Err(CompositeError::LayerName { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(layers)
}

/// Encodes an 8-bit sRGB PNG in memory, with an `sRGB` chunk and an optional `Description`.
pub fn encode_png(path: &Path, image: &Rgb8Image, description: Option<&str>) -> Result<Vec<u8>> {
    if image.width() == 0 || image.height() == 0 {
        return Err(CompositeError::Empty {
            what: format!("image for {}", path.display()),
        });
    }
    let err = |source| CompositeError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, image.width(), image.height());
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        if let Some(d) = description {
            enc.add_text_chunk("Description".into(), d.into())
                .map_err(err)?;
        }
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(image.data()).map_err(err)?;
        writer.finish().map_err(err)?;
    }
    Ok(buf)
}

/// Encodes 8-bit RGBA data that is not a colour image (an RGBM lightmap: linear values and a
/// multiplier) as a PNG in memory: no `sRGB` or `gAMA` chunk, so no reader converts it, and an
/// optional `Description` that says how to decode it. `rgba` holds `width * height` pixels
/// of four bytes, rows top to bottom.
pub fn encode_png_rgba(
    path: &Path,
    (width, height): (u32, u32),
    rgba: &[u8],
    description: Option<&str>,
) -> Result<Vec<u8>> {
    if width == 0 || height == 0 || rgba.len() as u64 != 4 * u64::from(width) * u64::from(height) {
        return Err(CompositeError::Empty {
            what: format!(
                "RGBA data of {} bytes for a {width} x {height} image {}",
                rgba.len(),
                path.display()
            ),
        });
    }
    let err = |source| CompositeError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, width, height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        if let Some(d) = description {
            enc.add_text_chunk("Description".into(), d.into())
                .map_err(err)?;
        }
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(rgba).map_err(err)?;
        writer.finish().map_err(err)?;
    }
    Ok(buf)
}

/// Writes an 8-bit sRGB image (a sheet, a false-colour image) as a PNG, atomically.
/// `description` goes into a `Description` text chunk (say how the pixels were made).
pub fn write_png(path: &Path, image: &Rgb8Image, description: Option<&str>) -> Result<()> {
    let bytes = encode_png(path, image, description)?;
    Ok(write_atomic(path, &bytes)?)
}

/// Tone maps a linear image with `map` and writes it as a PNG whose `Description` says so
/// ([`ToneMap::describe`]), atomically. Non-finite pixels are refused.
pub fn write_png_tonemapped(path: &Path, image: &Image, map: &ToneMap) -> Result<()> {
    refuse_non_finite(path, "image", image)?;
    write_png(path, &map.apply(image), Some(&map.describe()))
}
