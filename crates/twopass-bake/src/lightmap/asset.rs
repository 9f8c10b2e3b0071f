//! The user's own glTF written back with the lightmap: the document as it was loaded (every
//! node, name, material, texture, extension and extra, edited as JSON, so nothing this crate
//! does not model is lost), its buffers and images gathered into one `.glb`, the atlas on each
//! baked primitive's `TEXCOORD_1`, and the lightmap PNG embedded and referenced.
//!
//! **Coordinates.** When the scene's own `TEXCOORD_1` is the atlas ([`AtlasSource::Scene`]:
//! every primitive has one, in [0, 1], without overlap) the geometry is written back byte for
//! byte. Otherwise each baked primitive gets new vertex streams: every attribute it has
//! (`POSITION`, `NORMAL`, `TEXCOORD_0`, `COLOR_0`, `TANGENT`, joints, weights, morph targets)
//! copied element by element into the order of a vertex list split where the generated charts
//! split it (a vertex per glTF vertex and chart), and a new `TEXCOORD_1` (replacing the one it
//! had; a primitive without `TEXCOORD_0` gets the atlas there too, as glTF numbers the sets
//! without gaps). Triangles the scene dropped (zero area, exact repeats) are left out. A mesh that
//! several nodes use gets one copy per node after the first (the copies share nothing but
//! their names), since each use has its own place in the atlas.
//!
//! **The camera.** The scene's camera is the user's own camera node when it came from one
//! (`GltfSource::camera_node`); otherwise (the default framing) it is added as a perspective
//! camera on a new root node named [`CAMERA_NAME`](super::CAMERA_NAME) ([`GltfCamera`]). The
//! user's camera nodes are never edited; `asset.extras.twopass.camera_node` names the node.
//!
//! **The lightmap's reference** (no glTF extension exists for lightmaps, and an unknown one
//! would be a validator warning): the texture engines take (the RGBM PNG, or the sRGB PNG with
//! `--lightmap-encoding srgb`) is an image with a texture (bilinear, clamped), and every
//! material a baked primitive uses gets `extras.lightMap` (module `reference`: texture,
//! `texCoord` 1, quantity, encoding, multiplier or exposure, three.js's intensity; three.js's
//! GLTFLoader puts a material's extras in `material.userData`, Blender's importer in the
//! material's custom properties). `asset.extras.twopass` records the same with the decode
//! formula, units and EXR fingerprint.

use std::collections::HashMap;

use glam::Vec2;
use serde_json::{Value, json};
use twopass_scene::{GltfSource, Scene};

use super::camera::{CameraRecord, GltfCamera};
use super::layout::Layout;
use super::reference::Encoded;
use super::settings::{AtlasSource, Resolved};
use crate::error::BakeError;

/// The component byte size of a glTF `componentType`.
fn component_size(ty: u64) -> Option<usize> {
    match ty {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

/// The component count of a glTF accessor `type`.
fn component_count(ty: &str) -> Option<usize> {
    Some(match ty {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    })
}

/// The document being written: its JSON and its one binary buffer.
struct Writer {
    root: Value,
    bin: Vec<u8>,
}

fn err(message: String) -> BakeError {
    BakeError::Encode {
        path: "lightmapped glb".into(),
        message,
    }
}

impl Writer {
    fn array(&mut self, key: &str) -> &mut Vec<Value> {
        let root = self.root.as_object_mut().expect("the root is an object");
        let entry = root.entry(key).or_insert_with(|| Value::Array(Vec::new()));
        if !entry.is_array() {
            *entry = Value::Array(Vec::new());
        }
        entry.as_array_mut().expect("made an array")
    }

    fn push(&mut self, key: &str, value: Value) -> usize {
        let a = self.array(key);
        a.push(value);
        a.len() - 1
    }

    /// Appends `data` at a 4-byte boundary as a buffer view of buffer 0.
    fn view(&mut self, data: &[u8], extra: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": data.len(),
        });
        if let (Some(v), Some(e)) = (view.as_object_mut(), extra.as_object()) {
            v.extend(e.clone());
        }
        self.bin.extend_from_slice(data);
        self.push("bufferViews", view)
    }

    /// The bytes of every element of accessor `index` (no sparse accessors), element by element.
    fn elements(&self, index: usize) -> Result<(Value, Vec<Vec<u8>>), BakeError> {
        let a = self.root["accessors"][index].clone();
        let bad = |what: &str| err(format!("accessor {index}: {what}"));
        if a.get("sparse").is_some() {
            return Err(bad("sparse accessors are not rewritten"));
        }
        let count = a["count"].as_u64().ok_or_else(|| bad("no count"))? as usize;
        let size = component_size(a["componentType"].as_u64().unwrap_or(0))
            .zip(component_count(a["type"].as_str().unwrap_or("")))
            .map(|(s, n)| s * n)
            .ok_or_else(|| bad("unknown type"))?;
        let Some(view) = a["bufferView"].as_u64() else {
            return Ok((a, vec![vec![0; size]; count]));
        };
        let v = &self.root["bufferViews"][view as usize];
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let stride = v["byteStride"].as_u64().map_or(size, |s| s as usize);
        let out = (0..count)
            .map(|i| {
                let at = start + i * stride;
                self.bin
                    .get(at..at + size)
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| bad("reaches past its buffer"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((a, out))
    }

    /// A new vertex accessor like `original` holding `elements` (each padded to 4 bytes, as
    /// glTF wants vertex attributes aligned), with float bounds recomputed where it had any.
    fn vertex_accessor(&mut self, original: &Value, elements: &[&[u8]]) -> usize {
        let size = elements.first().map_or(0, |e| e.len());
        let stride = size.next_multiple_of(4);
        let mut data = Vec::with_capacity(elements.len() * stride);
        for e in elements {
            data.extend_from_slice(e);
            data.resize(data.len() + stride - size, 0);
        }
        let mut extra = json!({ "target": 34962 });
        if stride != size {
            extra["byteStride"] = json!(stride);
        }
        let view = self.view(&data, extra);
        let mut a = json!({
            "bufferView": view,
            "componentType": original["componentType"],
            "count": elements.len(),
            "type": original["type"],
        });
        for key in ["normalized", "name", "extras"] {
            if let Some(v) = original.get(key) {
                a[key] = v.clone();
            }
        }
        if original.get("min").is_some() && original["componentType"] == 5126 {
            let n = size / 4;
            let mut min = vec![f32::INFINITY; n];
            let mut max = vec![f32::NEG_INFINITY; n];
            for e in elements {
                for c in 0..n {
                    let v = f32::from_le_bytes(e[4 * c..4 * c + 4].try_into().expect("4 bytes"));
                    min[c] = min[c].min(v);
                    max[c] = max[c].max(v);
                }
            }
            a["min"] = json!(min);
            a["max"] = json!(max);
        }
        self.push("accessors", a)
    }

    fn float_accessor(&mut self, values: &[Vec2]) -> usize {
        let data: Vec<u8> = values
            .iter()
            .flat_map(|v| v.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let view = self.view(&data, json!({ "target": 34962 }));
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5126, "count": values.len(), "type": "VEC2" }),
        )
    }

    fn index_accessor(&mut self, indices: &[u32]) -> usize {
        let data: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&data, json!({ "target": 34963 }));
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5125, "count": indices.len(), "type": "SCALAR" }),
        )
    }
}

/// The user's glTF (`src`, loaded as `scene`) with the lightmap `png` on `layout`, as `.glb`
/// bytes; see the module docs.
pub(super) fn encode_asset_glb(
    src: &GltfSource,
    scene: &Scene,
    layout: &Layout,
    s: &Resolved,
    encoded: &Encoded<'_>,
) -> Result<Vec<u8>, BakeError> {
    let root: Value = serde_json::from_slice(&src.json)
        .map_err(|e| err(format!("the loaded document no longer parses: {e}")))?;
    let mut w = Writer {
        root,
        bin: Vec::new(),
    };
    // Every buffer into one, each view moved by where its buffer starts.
    let mut starts = Vec::with_capacity(src.buffers.len());
    for b in &src.buffers {
        while !w.bin.len().is_multiple_of(8) {
            w.bin.push(0);
        }
        starts.push(w.bin.len());
        w.bin.extend_from_slice(b);
    }
    for v in w.array("bufferViews") {
        let buffer = v["buffer"].as_u64().unwrap_or(0) as usize;
        let offset = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        v["buffer"] = json!(0);
        v["byteOffset"] = json!(starts.get(buffer).copied().unwrap_or(0) + offset);
    }
    // Images given by URI into the binary chunk, so the asset is one file.
    for (i, image) in src.images.iter().enumerate() {
        if let Some((bytes, mime)) = image {
            let view = w.view(bytes, json!({}));
            let im = &mut w.root["images"][i];
            if let Some(o) = im.as_object_mut() {
                o.remove("uri");
                o.insert("bufferView".into(), json!(view));
                o.insert("mimeType".into(), json!(mime));
            }
        }
    }
    if src.origins.len() != scene.objects.len() {
        return Err(err(format!(
            "{} objects but {} glTF origins",
            scene.objects.len(),
            src.origins.len()
        )));
    }
    if layout.source != AtlasSource::Scene {
        rewrite_primitives(&mut w, src, scene, layout)?;
    }
    // The lightmap: image, sampler, texture.
    let view = w.view(encoded.engine_png(), json!({}));
    let image = w.push(
        "images",
        json!({ "name": "twopass lightmap", "bufferView": view, "mimeType": "image/png" }),
    );
    let sampler = w.push(
        "samplers",
        json!({ "magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071 }),
    );
    let texture = w.push(
        "textures",
        json!({ "name": "twopass lightmap", "sampler": sampler, "source": image }),
    );
    let reference = encoded.material_entry(texture, s);
    let mut used: Vec<usize> = Vec::new();
    for o in &src.origins {
        let p = &w.root["meshes"][o.mesh]["primitives"][o.primitive];
        if let Some(m) = p["material"].as_u64() {
            used.push(m as usize);
        }
    }
    used.sort_unstable();
    used.dedup();
    for m in used {
        let material = &mut w.root["materials"][m];
        let extras = material
            .as_object_mut()
            .map(|o| o.entry("extras").or_insert_with(|| json!({})));
        if let Some(Value::Object(e)) = extras {
            e.insert("lightMap".into(), reference.clone());
        }
    }
    let camera_node = match src.camera_node {
        Some(node) => node,
        None => add_camera(&mut w, scene),
    };
    let mut record = json!({
        "lightmap": s.quantity.png_formula(),
        "quantity": s.quantity.name(),
        "texcoord": 1,
        "exposure": encoded.mapping.exposure,
        "hdr_scale": 1.0 / encoded.mapping.exposure,
        "unit": "W/(m^2 sr)",
        "texel_size_m": f64::from(s.texel_size) * scene.unit.metres(),
        "padding_texels": s.padding,
        "atlas": layout.source.describe(),
        "exr_fingerprint": format!("{:016x}", encoded.exr_fingerprint),
        "camera_node": camera_node,
        "camera": serde_json::to_value(CameraRecord::of(scene)).map_err(|e| err(e.to_string()))?,
    });
    if let (Some(r), Value::Object(more)) = (record.as_object_mut(), encoded.record(texture, s)) {
        r.extend(more);
    }
    let asset = &mut w.root["asset"];
    if let Some(o) = asset.as_object_mut() {
        let extras = o.entry("extras").or_insert_with(|| json!({}));
        if let Value::Object(e) = extras {
            e.insert("twopass".into(), record);
        }
    }
    let bin_len = w.bin.len();
    w.root["buffers"] = json!([{ "byteLength": bin_len }]);
    finish(w)
}

/// Adds the scene's camera ([`GltfCamera`]) on a new root node of the document's scene and
/// returns the node's index.
fn add_camera(w: &mut Writer, scene: &Scene) -> usize {
    let camera = GltfCamera::of(scene);
    let index = w.push("cameras", camera.camera_json());
    let node = w.push("nodes", camera.node_json(index));
    let shown = w.root["scene"].as_u64().unwrap_or(0) as usize;
    if let Some(s) = w.root["scenes"][shown].as_object_mut() {
        let nodes = s.entry("nodes").or_insert_with(|| json!([]));
        if let Some(list) = nodes.as_array_mut() {
            list.push(json!(node));
        }
    }
    node
}

/// Gives each baked primitive the generated atlas on a vertex list split by chart (module
/// docs): the first node that shows a mesh edits it, every other one gets a copy.
fn rewrite_primitives(
    w: &mut Writer,
    src: &GltfSource,
    scene: &Scene,
    layout: &Layout,
) -> Result<(), BakeError> {
    let meshes = w.root["meshes"].clone();
    let size = Vec2::new(layout.width as f32, layout.height as f32);
    // The objects of each node, in order.
    let mut by_node: Vec<(usize, usize, Vec<usize>)> = Vec::new();
    for (i, o) in src.origins.iter().enumerate() {
        match by_node.last_mut() {
            Some((node, _, objects)) if *node == o.node => objects.push(i),
            _ => by_node.push((o.node, o.mesh, vec![i])),
        }
    }
    let mut edited = vec![false; meshes.as_array().map_or(0, Vec::len)];
    for (node, mesh, objects) in by_node {
        let mut new_mesh = meshes[mesh].clone();
        for &i in &objects {
            let object = &scene.objects[i];
            let origin = src.origins[i];
            let primitive = &meshes[mesh]["primitives"][origin.primitive];
            let first = object.vertices.start;
            let mut split: HashMap<(u32, u32), u32> = HashMap::new();
            let (mut order, mut uv, mut indices) = (Vec::new(), Vec::new(), Vec::new());
            for t in object.triangles.clone() {
                let tri = scene.mesh.triangle(t);
                let mut corner = [0u32; 3];
                for k in 0..3 {
                    let v = tri[k] - first;
                    let key = (v, layout.groups[t as usize][k]);
                    corner[k] = *split.entry(key).or_insert_with(|| {
                        order.push(v as usize);
                        uv.push(layout.corners[t as usize][k] / size);
                        order.len() as u32 - 1
                    });
                }
                if origin.flips {
                    corner.swap(1, 2);
                }
                indices.extend_from_slice(&corner);
            }
            let mut p = primitive.clone();
            let mut attributes = serde_json::Map::new();
            if let Some(a) = primitive["attributes"].as_object() {
                for (semantic, accessor) in a {
                    if semantic == "TEXCOORD_1" {
                        continue;
                    }
                    let index = accessor.as_u64().unwrap_or(0) as usize;
                    attributes.insert(semantic.clone(), json!(gathered(w, index, &order)?));
                }
            }
            let atlas = w.float_accessor(&uv);
            attributes.insert("TEXCOORD_1".into(), json!(atlas));
            // glTF numbers texture coordinate sets from 0 without gaps: a primitive that had
            // none shows the atlas on set 0 too.
            attributes
                .entry("TEXCOORD_0")
                .or_insert_with(|| json!(atlas));
            p["attributes"] = Value::Object(attributes);
            if let Some(targets) = primitive["targets"].as_array() {
                let mut new_targets = Vec::with_capacity(targets.len());
                for target in targets {
                    let mut t = serde_json::Map::new();
                    for (semantic, accessor) in target.as_object().into_iter().flatten() {
                        let index = accessor.as_u64().unwrap_or(0) as usize;
                        t.insert(semantic.clone(), json!(gathered(w, index, &order)?));
                    }
                    new_targets.push(Value::Object(t));
                }
                p["targets"] = json!(new_targets);
            }
            p["indices"] = json!(w.index_accessor(&indices));
            new_mesh["primitives"][origin.primitive] = p;
        }
        if std::mem::replace(&mut edited[mesh], true) {
            let copy = w.push("meshes", new_mesh);
            w.root["nodes"][node]["mesh"] = json!(copy);
        } else {
            w.root["meshes"][mesh] = new_mesh;
        }
    }
    Ok(())
}

/// A new accessor holding the elements of accessor `index` in `order`.
fn gathered(w: &mut Writer, index: usize, order: &[usize]) -> Result<usize, BakeError> {
    let (original, elements) = w.elements(index)?;
    let picked = order
        .iter()
        .map(|&v| {
            elements
                .get(v)
                .map(Vec::as_slice)
                .ok_or_else(|| err(format!("accessor {index} has no element {v}")))
        })
        .collect::<Result<Vec<&[u8]>, _>>()?;
    Ok(w.vertex_accessor(&original, &picked))
}

/// The `.glb` bytes of the document.
fn finish(w: Writer) -> Result<Vec<u8>, BakeError> {
    let json_bytes = serde_json::to_vec(&w.root).map_err(|e| err(e.to_string()))?;
    crate::gltf::glb_bytes(json_bytes, w.bin)
}
