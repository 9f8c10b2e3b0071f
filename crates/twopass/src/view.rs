//! `twopass view BAKE_DIR`: a static page that shows a lightmap bake in a real engine
//! (three.js), from the scene's camera, with orbit controls to look around.
//!
//! The folder written (`--output`, default `BAKE_DIR/view/`) holds `index.html`, `view.js`
//! (the page's module; both from `crates/twopass/view/`, built into the binary), a copy of the
//! bake's `<stem>.lightmap.glb`, and the three.js files the page imports, copied from the
//! `three` npm package (`crates/twopass/view/package.json` pins it; `npm ci --prefix
//! crates/twopass/view` installs it; `--three DIR` names another copy). Nothing is fetched
//! from the network when the page runs. Browsers refuse ES modules from `file://`, so the page
//! is opened through any static server (`python3 -m http.server --directory DIR`).
//!
//! **What the page shows.** An irradiance lightmap of a glTF scene (`<stem>.lightmapped.glb`
//! beside the lightmap, `quantity` irradiance) is shown the way an engine shows it: the
//! user's own asset with its materials and base colour textures, each material's
//! `material.lightMap` set to the texture its `extras.lightMap` names (UV channel 1,
//! `lightMapIntensity` = the entry's intensity x the bake's exposure, x the RGBM multiplier
//! with the RGBM texel read as `rgb * a` by a shader chunk), so three.js multiplies the
//! irradiance by the albedo; its emission is scaled by the exposure too. Otherwise (a
//! radiance lightmap, or a scene that is not glTF) the page shows the lightmap `.glb`'s sRGB
//! PNG unlit on UV set 1. Either way a pixel is `sRGB(min(1, exposure * L))` with the bake's
//! exposure: the tone map of `twopass render --exposure log2(exposure)` (the exposure is in
//! the `.glb`'s `asset.extras.twopass`, with the camera). The page's mode is its
//! `twopass-mode` meta tag: `lightmap` or `unlit`.

use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;

use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// The folder of a `twopass bake --lightmap` (holding one `<stem>.lightmap.glb`).
    pub bake_dir: PathBuf,
    /// The `three` npm package to copy three.js from [default: crates/twopass/view/node_modules/three
    /// of the source tree this binary was built from].
    #[arg(long, value_name = "DIR")]
    pub three: Option<PathBuf>,
}

/// The page's HTML; `@GLB@` is replaced by the `.glb`'s file name, `@MODE@` by the page's
/// mode (`lightmap` or `unlit`).
const INDEX_HTML: &str = include_str!("../view/index.html");
/// The page's module.
const VIEW_JS: &str = include_str!("../view/view.js");

/// The files of the `three` package the page imports (and its licence), relative to the
/// package's folder; they keep these paths under `three/` in the output.
const THREE_FILES: [&str; 5] = [
    "build/three.module.js",
    "examples/jsm/loaders/GLTFLoader.js",
    "examples/jsm/utils/BufferGeometryUtils.js",
    "examples/jsm/controls/OrbitControls.js",
    "LICENSE",
];

/// Largest three.js file copied, bytes (three.module.js is about 1.3 MB).
const MAX_THREE_FILE: u64 = 64 << 20;

#[derive(Debug, Serialize)]
struct Summary {
    glb: PathBuf,
    mode: &'static str,
    three_version: String,
    page: PathBuf,
    files: Vec<PathBuf>,
}

/// Writes the page for the lightmap bake in `args.bake_dir`.
pub fn run(args: &ViewArgs, ctx: &Context) -> Result<(), CliError> {
    let lightmap = find_lightmap(&args.bake_dir)?;
    let (glb, bytes, mode) = shown_glb(&lightmap)?;
    let three = args
        .three
        .clone()
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("view/node_modules/three"));
    let three_version = three_version(&three)?;
    let out = ctx
        .output
        .clone()
        .unwrap_or_else(|| args.bake_dir.join("view"));
    crate::output::create_dir(&out)?;
    let name = glb
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut files = Vec::new();
    let mut write = |rel: &str, data: &[u8]| -> Result<PathBuf, CliError> {
        let path = out.join(rel);
        if let Some(dir) = path.parent() {
            crate::output::create_dir(dir)?;
        }
        crate::output::write_atomic(&path, data)?;
        files.push(path.clone());
        Ok(path)
    };
    // Only the package's own files are copied: a symbolic link in it that leads out of it
    // (to a private file, say) is refused, since the page folder is made to be served.
    let root = three.canonicalize().map_err(|e| CliError::io(&three, e))?;
    for rel in THREE_FILES {
        let from = three.join(rel);
        let real = from.canonicalize().map_err(|e| CliError::io(&from, e))?;
        if !real.starts_with(&root) {
            return Err(CliError::Input(format!(
                "{}: a symbolic link out of the three.js package {} (to {}); only the \
                 package's own files are copied",
                from.display(),
                three.display(),
                real.display()
            )));
        }
        let data = twopass_scene::read_bounded(&real, MAX_THREE_FILE)
            .map_err(|e| CliError::io(&from, e))?;
        let copy = write(&format!("three/{rel}"), &data)?;
        keep_permissions(&real, &copy)?;
    }
    let copy = write(&name, &bytes)?;
    keep_permissions(&glb, &copy)?;
    write("view.js", VIEW_JS.as_bytes())?;
    write(
        "index.html",
        INDEX_HTML
            .replace("@GLB@", &html_attr(&name))
            .replace("@MODE@", mode)
            .as_bytes(),
    )?;
    let summary = Summary {
        glb,
        mode,
        three_version,
        page: out.join("index.html"),
        files,
    };
    crate::output::report(&summary, ctx, || {
        outln!(
            "wrote {} (three.js {}, the bake {}, {})",
            summary.page.display(),
            summary.three_version,
            summary.glb.display(),
            match summary.mode {
                LIGHTMAP_MODE => "the asset's own materials with material.lightMap",
                _ => "the lightmap unlit",
            }
        );
        outln!(
            "open it through a local server: python3 -m http.server --directory {}",
            out.display()
        );
        Ok(())
    })
}

/// Gives `copy` the permissions of `source`: a file only its owner may read stays so.
fn keep_permissions(source: &Path, copy: &Path) -> Result<(), CliError> {
    let permissions = std::fs::metadata(source)
        .map_err(|e| CliError::io(source, e))?
        .permissions();
    std::fs::set_permissions(copy, permissions).map_err(|e| CliError::io(copy, e))
}

/// The page's mode for the user's asset with an irradiance lightmap: its own materials with
/// `material.lightMap`.
const LIGHTMAP_MODE: &str = "lightmap";
/// The page's mode for the lightmap `.glb`: the lightmap shown unlit.
const UNLIT_MODE: &str = "unlit";

/// The `.glb` the page shows for the lightmap bake `lightmap` (a `<stem>.lightmap.glb`), its
/// bytes (checked: a camera record the page reads) and the page's mode: the
/// `<stem>.lightmapped.glb` beside it when that holds an irradiance lightmap, else `lightmap`.
fn shown_glb(lightmap: &Path) -> Result<(PathBuf, Vec<u8>, &'static str), CliError> {
    let read = |path: &Path| -> Result<(Vec<u8>, serde_json::Value), CliError> {
        let bytes = twopass_scene::read_bounded(path, twopass_bake::MAX_BAKE_BYTES)
            .map_err(|e| CliError::io(path, e))?;
        let json = check_camera(path, &bytes)?;
        Ok((bytes, json))
    };
    let name = lightmap
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.strip_suffix(".lightmap.glb").unwrap_or(&name);
    let asset = lightmap.with_file_name(format!("{stem}.lightmapped.glb"));
    if asset.is_file() {
        let (bytes, json) = read(&asset)?;
        if json["asset"]["extras"]["twopass"]["quantity"] == "irradiance" {
            return Ok((asset, bytes, LIGHTMAP_MODE));
        }
    }
    let (bytes, _) = read(lightmap)?;
    Ok((lightmap.to_owned(), bytes, UNLIT_MODE))
}

/// The one `<stem>.lightmap.glb` in `dir`.
fn find_lightmap(dir: &Path) -> Result<PathBuf, CliError> {
    let entries = std::fs::read_dir(dir).map_err(|e| CliError::io(dir, e))?;
    let mut found = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| CliError::io(dir, e))?.path();
        if path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().ends_with(".lightmap.glb"))
        {
            found.push(path);
        }
    }
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(CliError::Input(format!(
            "{}: no <stem>.lightmap.glb; bake with `twopass bake SCENE --lightmap --output {}`",
            dir.display(),
            dir.display()
        ))),
        _ => Err(CliError::Input(format!(
            "{}: several lightmap bakes ({}); give each its own folder",
            dir.display(),
            found
                .iter()
                .filter_map(|p| p.file_name())
                .map(|n| n.to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// Checks that the `.glb` is a glTF binary whose `asset.extras.twopass.camera` the page can
/// read (a bake older than the record has none); returns its JSON.
fn check_camera(glb: &Path, bytes: &[u8]) -> Result<serde_json::Value, CliError> {
    let bad = |why: &str| CliError::Input(format!("{}: {why}", glb.display()));
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if bytes.get(..4) != Some(b"glTF") || word(16) != Some(0x4E4F_534A) {
        return Err(bad("not a glTF binary with a JSON chunk"));
    }
    let len = word(12).unwrap_or(0);
    let json = bytes
        .get(20..20 + len)
        .ok_or_else(|| bad("the JSON chunk is truncated"))?;
    let value: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| bad(&format!("the JSON chunk: {e}")))?;
    let camera = &value["asset"]["extras"]["twopass"]["camera"];
    let fov = camera["vertical_fov_degrees"].as_f64();
    let vec3 = |k: &str| {
        camera[k]
            .as_array()
            .is_some_and(|a| a.len() == 3 && a.iter().all(|v| v.as_f64().is_some()))
    };
    if !(vec3("position") && vec3("target") && vec3("up") && fov.is_some_and(|f| f > 0.0)) {
        return Err(bad(
            "no asset.extras.twopass.camera (a bake from an older twopass); bake again",
        ));
    }
    Ok(value)
}

/// The `version` of the `three` package at `dir`, or a clear error saying how to install it.
fn three_version(dir: &Path) -> Result<String, CliError> {
    let manifest = dir.join("package.json");
    let text = crate::output::read_small(&manifest).map_err(|e| {
        CliError::Input(format!(
            "{}: {e}: three.js is not installed there; run `npm ci --prefix crates/twopass/view` \
             in the twopass source tree, or name a `three` package with --three DIR",
            manifest.display()
        ))
    })?;
    let value: serde_json::Value = serde_json::from_slice(&text)
        .map_err(|e| CliError::Input(format!("{}: {e}", manifest.display())))?;
    if value["name"] != "three" {
        return Err(CliError::Input(format!(
            "{}: not the `three` package",
            manifest.display()
        )));
    }
    Ok(value["version"].as_str().unwrap_or("unknown").to_owned())
}

/// `s` escaped for an HTML attribute value in double quotes.
fn html_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
