//! The glTF file read: the document parsed and validated by the `gltf` crate, its buffers
//! resolved (a `.glb`'s binary chunk, base64 data URIs, files beside it) and checked against
//! their declared lengths, and the images given by URI read for the asset a bake writes back.

use std::path::{Path, PathBuf};

use crate::error::{SceneError, Warning};
use crate::input::{self, InputKind, ReadPolicy};

/// A glTF file read whole: the validated document, its JSON and every buffer's bytes.
pub(super) struct GltfFile {
    pub(super) document: gltf::Document,
    pub(super) json: Vec<u8>,
    pub(super) buffers: Vec<Vec<u8>>,
    pub(super) images: Vec<Option<(Vec<u8>, String)>>,
}

/// Reads and validates `path` and everything it refers to.
pub(super) fn read(
    path: &Path,
    policy: &ReadPolicy,
    warnings: &mut Vec<Warning>,
) -> Result<GltfFile, SceneError> {
    let bytes = input::read_bytes(path, InputKind::Gltf, policy)?;
    let err = |at: &str, problem: String| SceneError::Gltf {
        path: path.to_owned(),
        at: at.to_owned(),
        problem,
    };
    if bytes.starts_with(b"glTF") {
        // The gltf crate subtracts the header from the declared length unchecked.
        let declared = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_none_or(|n| n < 12) {
            return Err(err(
                "the document",
                format!(
                    "not a valid glTF binary: its header declares {} bytes, fewer than the 12-byte header itself",
                    declared.unwrap_or(0)
                ),
            ));
        }
    }
    let json = if bytes.starts_with(b"glTF") {
        gltf::Glb::from_slice(&bytes)
            .map_err(|e| err("the document", describe(&e)))?
            .json
            .into_owned()
    } else {
        bytes.clone()
    };
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| err("the document", describe(&e)))?;
    // gltf-json's validation reads each POSITION accessor without checking its index first
    // (it would panic on one past the end): checked here, then the document validated.
    let root = document.into_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = primitive.attributes.get(&position)
                && a.value() >= root.accessors.len()
            {
                return Err(err(
                    &format!("mesh {m}, primitive {p}"),
                    format!(
                        "POSITION accessor {} does not exist (the document has {} accessors)",
                        a.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    // The gltf crate's `Image::source` unwraps a buffer view's mimeType (which glTF requires
    // with one) and the uri of an image without a buffer view; its validation checks neither.
    for (i, image) in root.images.iter().enumerate() {
        if let Some(problem) = image_problem(image) {
            return Err(err(&format!("image {i}"), problem.to_owned()));
        }
    }
    let document =
        gltf::Document::from_json(root).map_err(|e| err("the document", describe(&e)))?;
    drop(bytes);
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::with_capacity(document.buffers().len());
    for buffer in document.buffers() {
        let at = format!("buffer {}{}", buffer.index(), quoted(buffer.name()));
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.clone().ok_or_else(|| {
                err(
                    &at,
                    "refers to the binary chunk, but the file has none".into(),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => match data_uri(uri) {
                Some(decoded) => decoded.map_err(|p| err(&at, p))?.0,
                None => input::read_bytes(&file_uri(dir, uri), InputKind::GltfBuffer, policy)
                    .map_err(|e| err(&at, e.to_string()))?,
            },
        };
        if data.len() < buffer.length() {
            return Err(err(
                &at,
                format!(
                    "holds {} bytes, fewer than its byteLength of {}",
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }
    let mut images = Vec::with_capacity(document.images().len());
    for image in document.images() {
        let at = format!("image {}{}", image.index(), quoted(image.name()));
        images.push(match image.source() {
            gltf::image::Source::View { .. } => None,
            gltf::image::Source::Uri { uri, mime_type } => {
                let read = match data_uri(uri) {
                    Some(decoded) => decoded,
                    None => {
                        let file = file_uri(dir, uri);
                        input::read_bytes(&file, InputKind::GltfImage, policy)
                            .map(|b| (b, mime_of(&file)))
                            .map_err(|e| e.to_string())
                    }
                };
                match read {
                    Ok((data, mime)) => Some((data, mime_type.map_or(mime, str::to_owned))),
                    Err(problem) => {
                        warnings.push(Warning::Gltf {
                            path: path.to_owned(),
                            at,
                            problem: format!(
                                "cannot be read ({problem}); a material with it as its base colour texture cannot load, and an asset written back keeps only its URI"
                            ),
                        });
                        None
                    }
                }
            }
        });
    }
    Ok(GltfFile {
        document,
        json,
        buffers,
        images,
    })
}

/// `` `name` `` with a leading space, or nothing for an unnamed object.
pub(super) fn quoted(name: Option<&str>) -> String {
    name.map_or_else(String::new, |n| {
        format!(" `{}`", crate::input::printable(n))
    })
}

/// The `gltf` crate's error in words: each validation problem with its JSON path.
fn describe(e: &gltf::Error) -> String {
    match e {
        gltf::Error::Validation(problems) => {
            let list: Vec<String> = problems
                .iter()
                .take(8)
                .map(|(at, problem)| format!("{at}: {problem}"))
                .collect();
            let more = problems.len().saturating_sub(list.len());
            let tail = if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            };
            format!("not a valid glTF 2.0 document: {}{tail}", list.join("; "))
        }
        other => format!("not a valid glTF 2.0 file: {other}"),
    }
}

/// A `data:` URI's bytes and MIME type, `None` for any other URI.
fn data_uri(uri: &str) -> Option<Result<(Vec<u8>, String), String>> {
    let rest = uri.strip_prefix("data:")?;
    Some(match rest.split_once(',') {
        Some((head, body)) => match head.strip_suffix(";base64") {
            Some(mime) => base64(body).map(|b| (b, mime.to_owned())),
            None => Err("a data URI that is not base64-encoded".to_owned()),
        },
        None => Err("a data URI without a comma".to_owned()),
    })
}

/// A relative URI as a path beside the glTF file (percent escapes decoded).
fn file_uri(dir: &Path, uri: &str) -> PathBuf {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%'
            && let (Some(h), Some(l)) = (
                bytes.get(i + 1).copied().and_then(hex),
                bytes.get(i + 2).copied().and_then(hex),
            )
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    dir.join(String::from_utf8_lossy(&out).as_ref())
}

/// The MIME type glTF allows for an image file, from its extension.
fn mime_of(file: &Path) -> String {
    let ext = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("jpg" | "jpeg") => "image/jpeg",
        Some("webp") => "image/webp",
        Some("ktx2") => "image/ktx2",
        _ => "image/png",
    }
    .to_owned()
}

/// Standard base64 (RFC 4648, with or without `=` padding) decoded.
pub(super) fn base64(text: &str) -> Result<Vec<u8>, String> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let body = text.trim_end_matches('=');
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in body.bytes().enumerate() {
        let v = value(c).ok_or_else(|| {
            format!(
                "a data URI with the character {:?} at {i}, not base64",
                c as char
            )
        })?;
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if body.len() % 4 == 1 {
        return Err("a data URI whose base64 ends in a lone character".to_owned());
    }
    Ok(out)
}

/// Why the gltf crate would panic reading `image`'s source (`Image::source`), if it would:
/// a buffer view without the mimeType glTF requires with one, or neither a uri nor a buffer
/// view.
pub fn image_problem(image: &gltf::json::Image) -> Option<&'static str> {
    match (&image.buffer_view, &image.uri, &image.mime_type) {
        (Some(_), _, None) => Some("has a bufferView but no mimeType (glTF requires one with it)"),
        (None, None, _) => Some("has neither a uri nor a bufferView"),
        _ => None,
    }
}
