//! `twopass view`: the page shows the lightmap bake in a real engine. Headless Chromium
//! (Debian's `chromium`) opens the page through a local HTTP server, the page says it has
//! drawn (its title), and its screenshot matches twopass's own radiosity render of the same
//! view, tone-mapped the same way (the bake's exposure, clip, sRGB), to a mean error of 3 %.
//!
//! With `CI` set, a missing `chromium` or a missing three.js (`npm ci --prefix
//! crates/twopass/view`) fails the test (`.ci/run` installs both); elsewhere it prints a note.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use crate::common::{assert_ok, bake_cornell_lightmap, cli, repo, twopass};

/// Skips (with a note) or, in CI, fails when a tool the test needs is missing.
fn missing(what: &str) -> bool {
    if std::env::var_os("CI").is_some() {
        panic!("{what}: .ci/run installs it");
    }
    eprintln!("note: the page of `twopass view` not checked in a browser: {what}");
    true
}

/// Longest wait of the page's `./hold` request for its `./ready`, real time.
const HOLD_LIMIT: Duration = Duration::from_secs(120);

/// Serves the files under `root` over HTTP/1.0 on a free local port, one thread per
/// connection, for as long as the test runs; returns the page's URL (with `?hold`).
///
/// `/hold` answers only once a `/ready` request arrives after it (or after [`HOLD_LIMIT`]):
/// the page opened with `?hold` requests `./hold` as it starts and `./ready` once it has drawn,
/// and headless Chromium's virtual time stands still while a request is pending, so the DOM
/// dump and the screenshot come after the page's first frame however slow the machine is.
fn serve(root: PathBuf) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}/?hold", listener.local_addr().unwrap());
    let readies = Arc::new((Mutex::new(0u64), Condvar::new()));
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let root = root.clone();
            let readies = Arc::clone(&readies);
            std::thread::spawn(move || {
                let mut reader = BufReader::new(&stream);
                let mut line = String::new();
                if reader.read_line(&mut line).is_err() {
                    return;
                }
                // Skip the headers.
                let mut header = String::new();
                while reader.read_line(&mut header).is_ok_and(|n| n > 2) {
                    header.clear();
                }
                let path = line.split_whitespace().nth(1).unwrap_or("/");
                let path = path.split('?').next().unwrap_or("/");
                let rel = if path == "/" {
                    "index.html"
                } else {
                    &path[1..]
                };
                let file = root.join(rel);
                let mut stream = &stream;
                let (count, changed) = &*readies;
                if rel == "hold" || rel == "ready" {
                    let mut n = count.lock().unwrap();
                    if rel == "ready" {
                        *n += 1;
                        changed.notify_all();
                    } else {
                        let seen = *n;
                        let _ = changed.wait_timeout_while(n, HOLD_LIMIT, |n| *n == seen);
                    }
                    let _ = stream.write_all(b"HTTP/1.0 204 No Content\r\n\r\n");
                    return;
                }
                let body = if rel.contains("..") {
                    None
                } else {
                    std::fs::read(&file).ok()
                };
                let Some(body) = body else {
                    let _ =
                        stream.write_all(b"HTTP/1.0 404 Not Found\r\nContent-Length: 0\r\n\r\n");
                    return;
                };
                let kind = match file.extension().and_then(|e| e.to_str()) {
                    Some("html") => "text/html; charset=utf-8",
                    Some("js") => "text/javascript",
                    Some("glb") => "model/gltf-binary",
                    _ => "application/octet-stream",
                };
                let head = format!(
                    "HTTP/1.0 200 OK\r\nContent-Type: {kind}\r\nContent-Length: {}\r\n\r\n",
                    body.len()
                );
                let _ = stream.write_all(head.as_bytes());
                let _ = stream.write_all(&body);
            });
        }
    });
    url
}

/// Headless Chromium on `url` with a `width` x `height` window, plus `extra` arguments
/// (`--dump-dom` or `--screenshot=FILE`); WebGL through SwiftShader (no GPU).
fn chromium(url: &str, (width, height): (u32, u32), profile: &Path, extra: &str) -> String {
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--force-device-scale-factor=1",
            "--hide-scrollbars",
            // Virtual time for the page after its load; it stands still while the page's
            // `./hold` request is pending (see `serve`), so the first frame comes first.
            "--virtual-time-budget=20000",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--window-size={width},{height}"),
            extra,
            url,
        ])
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium {extra}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The 8-bit sRGB RGB values of a PNG (RGB or RGBA; alpha dropped), and its size.
fn read_png_rgb(path: &Path) -> (Vec<u8>, u32, u32) {
    let mut decoder =
        png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(
        channels == 3 || channels == 4,
        "{path:?}: {:?}",
        info.color_type
    );
    let rgb = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    (rgb, info.width, info.height)
}

/// The `.glb`'s `asset.extras.twopass` (the exposure and the camera).
fn glb_extras(glb: &Path) -> serde_json::Value {
    let gltf = gltf::Gltf::open(glb).unwrap();
    let raw = gltf.document.as_json().asset.extras.as_ref().unwrap();
    serde_json::from_str::<serde_json::Value>(raw.get()).unwrap()["twopass"].clone()
}

/// Whether the browser test can run: `chromium` and three.js are there (else a note, or a
/// failure in CI).
fn browser_ready() -> bool {
    if Command::new("chromium").arg("--version").output().is_err()
        && missing("`chromium` is not on PATH")
    {
        return false;
    }
    repo("crates/twopass/view/node_modules/three/package.json").exists()
        || !missing("three.js is not installed (npm ci --prefix crates/twopass/view)")
}

/// Opens the page in `page` (showing `shown`, a `.glb` in it) in headless Chromium, checks it
/// drew, and compares its screenshot with twopass's own radiosity render of `scene` from the
/// solution in `bake_file`, tone-mapped the same way, to a mean error under 3 %.
fn assert_page_matches_render(
    dir: &Path,
    page: &Path,
    shown: &str,
    scene: &Path,
    bake_file: &Path,
) {
    let extras = glb_extras(&page.join(shown));
    let exposure = extras["exposure"].as_f64().unwrap();
    let camera = &extras["camera"];
    let size = (
        camera["width"].as_u64().unwrap() as u32,
        camera["height"].as_u64().unwrap() as u32,
    );
    let url = serve(page.to_owned());
    let dom = chromium(&url, size, &dir.join("profile-dom"), "--dump-dom");
    assert!(
        dom.contains("<title>twopass view: ready</title>"),
        "the page did not draw: {}",
        dom.lines()
            .find(|l| l.contains("<title>"))
            .unwrap_or("no title")
    );
    let shot = dir.join("shot.png");
    chromium(
        &url,
        size,
        &dir.join("profile-shot"),
        &format!("--screenshot={}", shot.display()),
    );
    // twopass's own radiosity render of the scene's view at the scene's size, tone-mapped as
    // the page is: exposure (the bake's), clip, sRGB transfer, 8 bits.
    let render = dir.join("render.png");
    let render_box = cli("render")
        .arg(scene)
        .words("--method radiosity --bake")
        .arg(bake_file)
        .words("--spp 4 --exposure")
        .arg(format!("{:.9}", exposure.log2()))
        .output(&render)
        .words("--quiet");
    assert_ok(&render_box.run());
    let (a, aw, ah) = read_png_rgb(&shot);
    let (b, bw, bh) = read_png_rgb(&render);
    assert_eq!((aw, ah), (bw, bh), "screenshot and render sizes");
    // Mean error: the mean absolute difference of the 8-bit sRGB values over every pixel and
    // channel, divided by the mean of the render's values. In sRGB because that is what the
    // page displays and the screenshot holds (decoding to linear would weigh the bright light
    // and walls and hide errors in the dark corners); relative to the mean so the figure does
    // not depend on how bright the exposure makes the image.
    let diff: u64 = a
        .iter()
        .zip(&b)
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    let total: u64 = b.iter().map(|&y| u64::from(y)).sum();
    let error = diff as f64 / total as f64;
    eprintln!(
        "page ({shown}) vs render: mean |sRGB difference| / mean sRGB = {:.4} ({} x {})",
        error, aw, ah
    );
    assert!(error < 0.03, "mean error {error:.4}");
}

#[test]
fn the_page_in_headless_chromium_matches_the_radiosity_render() {
    if !browser_ready() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let bake = dir.join("bake");
    bake_cornell_lightmap(&bake);
    let page = dir.join("page");
    assert_ok(&cli("view").arg(&bake).output(&page).words("--quiet").run());
    assert_page_matches_render(
        dir,
        &page,
        "cornell-box.lightmap.glb",
        &repo("scenes/cornell-box.toml"),
        &bake.join("cornell-box.bake"),
    );
}

/// Bakes the Cornell box written as glTF (`cornell.glb` in `dir`) with a lightmap of
/// `quantity` into `dir/bake`; returns the glTF's path.
fn bake_cornell_gltf(dir: &Path, quantity: &str) -> PathBuf {
    let glb = dir.join("cornell.glb");
    crate::gltf_input::cornell_glb(&glb, None);
    let lightmap = "--format bake --lightmap --texel-size 0.005 --gather off --quiet";
    let bake = cli("bake")
        .arg(&glb)
        .words(lightmap)
        .words("--lightmap-quantity")
        .arg(quantity)
        .output(dir.join("bake"));
    assert_ok(&bake.run());
    glb
}

#[test]
fn the_irradiance_page_in_headless_chromium_matches_the_radiosity_render() {
    // The page multiplies the irradiance lightmap by the asset's own base colours
    // (material.lightMap): the image of twopass's radiosity render of the same solve.
    if !browser_ready() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let glb = bake_cornell_gltf(dir, "irradiance");
    let page = dir.join("page");
    assert_ok(
        &cli("view")
            .arg(dir.join("bake"))
            .output(&page)
            .words("--quiet")
            .run(),
    );
    assert_page_matches_render(
        dir,
        &page,
        "cornell.lightmapped.glb",
        &glb,
        &dir.join("bake/cornell.bake"),
    );
}

/// Issue 41: an irradiance bake of a glTF is shown on the asset's own materials through
/// `material.lightMap` on UV channel 1, a radiance bake unlit; checked without a browser in
/// the page's files and, with `node`, in the asset's material wiring the page relies on
/// (`tests/node/lightmap_wiring.mjs`).
#[cfg(unix)]
#[test]
fn an_irradiance_bake_of_a_gltf_is_shown_through_material_lightmap() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let three = dir.join("three");
    fake_three(&three);
    bake_cornell_gltf(dir, "irradiance");
    let page = dir.join("page");
    let out = cli("view")
        .arg(dir.join("bake"))
        .arg("--three")
        .arg(&three)
        .output(&page)
        .words("--json")
        .run();
    let summary = crate::common::ok_json(&out);
    assert_eq!(summary["mode"], "lightmap", "{summary}");
    assert!(page.join("cornell.lightmapped.glb").is_file());
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(
        html.contains(r#"<meta name="twopass-glb" content="cornell.lightmapped.glb">"#)
            && html.contains(r#"<meta name="twopass-mode" content="lightmap">"#),
        "{html}"
    );
    let js = std::fs::read_to_string(page.join("view.js")).unwrap();
    for needle in [
        "material.userData?.lightMap",
        "material.lightMap = texture",
        "texture.channel = entry.texCoord",
        "material.lightMapIntensity = entry.intensity * exposure",
        "lightMapTexel.rgb * lightMapTexel.a * lightMapIntensity",
    ] {
        assert!(js.contains(needle), "view.js lacks {needle}");
    }
    // The wiring in the asset: every primitive on UV 1 with its material's lightMap entry.
    let script = repo("tests/node/lightmap_wiring.mjs");
    match Command::new("node")
        .arg(&script)
        .arg(page.join("cornell.lightmapped.glb"))
        .output()
    {
        Ok(out) => {
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(r["problems"], serde_json::json!([]), "{r}");
            let (scene, _) = twopass_scene::load(repo(crate::common::BOX)).unwrap();
            assert_eq!(
                r["primitives"].as_u64().unwrap() as usize,
                scene.objects.len()
            );
            assert_eq!(
                r["materials"].as_u64().unwrap() as usize,
                scene.objects.len()
            );
        }
        Err(_) if std::env::var_os("CI").is_some() => panic!("`node` is not on PATH"),
        Err(_) => eprintln!("note: the asset's wiring not checked: `node` is not on PATH"),
    }
    // A radiance bake of the same asset is shown unlit, from the lightmap .glb.
    let radiance = dir.join("radiance");
    std::fs::create_dir_all(&radiance).unwrap();
    bake_cornell_gltf(&radiance, "radiance");
    let page = radiance.join("page");
    let out = cli("view")
        .arg(radiance.join("bake"))
        .arg("--three")
        .arg(&three)
        .output(&page)
        .words("--json")
        .run();
    assert_eq!(crate::common::ok_json(&out)["mode"], "unlit");
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(html.contains(r#"content="cornell.lightmap.glb""#), "{html}");
    assert!(!page.join("cornell.lightmapped.glb").exists());
}

#[test]
fn view_refuses_a_folder_without_a_lightmap_or_with_a_broken_one() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let out = twopass(&["view", dir.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&*dir.to_string_lossy()) && err.contains("lightmap.glb"),
        "{err}"
    );
    // A .glb that is not a glTF binary is named.
    std::fs::write(dir.join("x.lightmap.glb"), b"not a glb").unwrap();
    let out = twopass(&["view", dir.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("x.lightmap.glb") && err.contains("glTF"),
        "{err}"
    );
    let out = twopass(&["view"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.join("view").exists());
}

/// A stand-in for the `three` package at `dir`: its manifest and the files the page copies,
/// each holding its own path, readable by its owner only.
#[cfg(unix)]
fn fake_three(dir: &Path) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        dir.join("package.json"),
        r#"{"name": "three", "version": "0.0.0"}"#,
    )
    .unwrap();
    for rel in [
        "build/three.module.js",
        "examples/jsm/loaders/GLTFLoader.js",
        "examples/jsm/utils/BufferGeometryUtils.js",
        "examples/jsm/controls/OrbitControls.js",
        "LICENSE",
    ] {
        let path = dir.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, rel).unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
    }
}

/// Issue 43, finding 15: `view --three T` copies only the package's own files with their
/// permissions (a file only its owner may read stays so), and refuses a symbolic link in `T`
/// that leads out of it, naming the link, without copying what it leads to.
#[cfg(unix)]
#[test]
fn view_refuses_links_out_of_the_three_package_and_keeps_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let bake = dir.join("bake");
    bake_cornell_lightmap(&bake);
    let three = dir.join("three");
    fake_three(&three);
    let page = dir.join("page");
    let run = |out: &Path| {
        twopass(&[
            "view",
            bake.to_str().unwrap(),
            "--three",
            three.to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
        ])
    };
    assert_ok(&run(&page));
    let copy = page.join("three/build/three.module.js");
    assert_eq!(
        std::fs::read_to_string(&copy).unwrap(),
        "build/three.module.js"
    );
    let mode = std::fs::metadata(&copy).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600, "{mode:o}");
    // LICENSE a link to a private file outside the package.
    let private = dir.join("private.txt");
    std::fs::write(&private, "secret").unwrap();
    std::fs::remove_file(three.join("LICENSE")).unwrap();
    std::os::unix::fs::symlink(&private, three.join("LICENSE")).unwrap();
    let page = dir.join("page2");
    let out = run(&page);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("LICENSE") && err.contains("a symbolic link out of the three.js package"),
        "{err}"
    );
    assert!(!page.join("three/LICENSE").exists());
}
