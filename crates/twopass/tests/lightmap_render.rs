//! `twopass render --bake x.lightmap.glb`: a lightmap bake read back (the `.glb`'s
//! `TEXCOORD_1` and the HDR lightmap EXR beside it) renders what the radiosity solution it was
//! baked from renders, and a lightmap of another scene, a missing EXR or hybrid-direct are
//! refused with the file named.

use std::path::Path;

use crate::common::{self, BOX, SPHERES, assert_ok, bake_cornell_lightmap, cli, repo};
use twopass_composite::metric::compare;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::read_exr;

/// Renders `scene` (a path in the repository) with `method` and the bake file `bake` of `dir`
/// into the file `out` of `dir`, 128 x 128 at 16 samples per pixel.
fn render(dir: &Path, scene: &str, bake: &str, method: &str, out: &str) -> std::process::Output {
    cli("render")
        .arg(repo(scene))
        .words("--method")
        .arg(method)
        .words("--bake")
        .arg(dir.join(bake))
        .words("--width 128 --height 128 --spp 16 --quiet")
        .output(dir.join(out))
        .run()
}

#[test]
fn a_lightmap_glb_renders_as_the_solution_it_was_baked_from() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    bake_cornell_lightmap(dir);
    for (bake, out) in [
        ("cornell-box.bake", "from-bake.exr"),
        ("cornell-box.lightmap.glb", "from-glb.exr"),
    ] {
        assert_ok(&render(dir, BOX, bake, "radiosity", out));
    }
    let reference = read_exr(&dir.join("from-bake.exr")).unwrap();
    let image = read_exr(&dir.join("from-glb.exr")).unwrap();
    let m = compare(&image, &reference, &ToneMap::default()).unwrap();
    // The lightmap holds the solution's radiance at 5 mm texel centres; bilinear sampling
    // between them differs from the element mesh's own interpolation only by that texel-scale
    // resampling, so the images agree to the 2 % relative RMSE.
    eprintln!("lightmap .glb vs .bake: relative RMSE {:.4}", m.rel_rmse);
    assert!(m.rel_rmse < 0.02, "relative RMSE {:.4}", m.rel_rmse);
    // Not a trivially equal pair: both images see the lit box.
    assert!(reference.pixels().iter().any(|p| p.min_element() > 0.0));
}

#[test]
fn a_lightmap_of_another_scene_or_without_its_exr_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    bake_cornell_lightmap(dir);
    let glb = "cornell-box.lightmap.glb";
    // The standard error of a render that must be refused (exit code 1).
    let refused = |scene: &str, method: &str| {
        let out = render(dir, scene, glb, method, "x.exr");
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(1), "{err}");
        err
    };
    let err = refused(SPHERES, "radiosity");
    assert!(
        err.contains("cornell-box.lightmap.glb") && err.contains("another scene"),
        "{err}"
    );
    let err = refused(BOX, "hybrid-direct");
    assert!(err.contains("hybrid-direct"), "{err}");
    // The EXR removed: the manifest check names it, and behind a manifest that does not
    // list it the reader does.
    std::fs::remove_file(dir.join("cornell-box.lightmap.exr")).unwrap();
    let err = refused(BOX, "radiosity");
    assert!(
        err.contains("cornell-box.lightmap.exr") && err.contains("missing"),
        "{err}"
    );
    common::reseal(dir, "cornell-box", |name| !name.ends_with(".exr"));
    let err = refused(BOX, "radiosity");
    assert!(err.contains("cornell-box.lightmap.exr"), "{err}");
    assert!(!dir.join("x.exr").exists());
}

/// `bytes` (an EXR) with its header's data window grown to `size` x `size` pixels, nothing
/// else changed: a file of a few kilobytes that declares a huge image.
fn with_data_window(bytes: &[u8], size: i32) -> Vec<u8> {
    let key = b"dataWindow\0box2i\0\x10\0\0\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("an EXR header has a data window")
        + key.len();
    let word = |k: usize| i32::from_le_bytes(bytes[at + 4 * k..at + 4 * k + 4].try_into().unwrap());
    let (x0, y0) = (word(0), word(1));
    let mut out = bytes.to_vec();
    out[at + 8..at + 12].copy_from_slice(&(x0 + size - 1).to_le_bytes());
    out[at + 12..at + 16].copy_from_slice(&(y0 + size - 1).to_le_bytes());
    out
}

/// Issue 43, findings 4 and 5: the lightmap EXR's header is checked against its `.glb` before
/// a pixel is decoded (a header that declares 20,000 x 20,000 texels is refused by its size),
/// and an EXR of the right size from another bake (another fingerprint), or one whose texels
/// were changed, is refused naming both files.
#[test]
fn a_lightmap_exr_is_checked_against_its_glb_before_decoding() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    bake_cornell_lightmap(dir);
    // Behind a manifest that does not list the EXR, whose checksum would refuse any changed
    // file first.
    common::reseal(dir, "cornell-box", |name| !name.ends_with(".exr"));
    let exr = dir.join("cornell-box.lightmap.exr");
    let good = std::fs::read(&exr).unwrap();
    let refused = |why: &str| {
        let out = render(dir, BOX, "cornell-box.lightmap.glb", "radiosity", "x.exr");
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(1), "{err}");
        for w in ["cornell-box.lightmap.exr", "cornell-box.lightmap.glb", why] {
            assert!(err.contains(w), "lacks `{w}`: {err}");
        }
        assert!(!dir.join("x.exr").exists());
    };
    // A header of 20,000 x 20,000 texels over the few kilobytes of the real pixels: decoding
    // it would fail (or, with the pixels there, take gigabytes); its size is refused first.
    std::fs::write(&exr, with_data_window(&good, 20_000)).unwrap();
    refused("20000 x 20000 texels, the lightmap in");
    // Another bake's EXR of the same size: other texels, their own fingerprint.
    let image = read_exr_path(&good, dir);
    let mut other = image.clone();
    other.pixels_mut()[0] += glam::Vec3::splat(1.0);
    let print = format!("{:016x}", twopass_bake::lightmap_fingerprint(&other));
    let bytes = twopass_composite::write::encode_exr_image_with(
        &exr,
        &other,
        &[(twopass_bake::LIGHTMAP_FINGERPRINT, print.clone())],
    )
    .unwrap();
    std::fs::write(&exr, bytes).unwrap();
    refused(&format!("lightmap fingerprint {print}, but"));
    // Changed texels under the right fingerprint.
    let right = format!("{:016x}", twopass_bake::lightmap_fingerprint(&image));
    let bytes = twopass_composite::write::encode_exr_image_with(
        &exr,
        &other,
        &[(twopass_bake::LIGHTMAP_FINGERPRINT, right)],
    )
    .unwrap();
    std::fs::write(&exr, bytes).unwrap();
    refused("the texels do not match the fingerprint");
    // The good file back: it renders.
    std::fs::write(&exr, &good).unwrap();
    assert_ok(&render(
        dir,
        BOX,
        "cornell-box.lightmap.glb",
        "radiosity",
        "x.exr",
    ));
}

/// The image of the EXR `bytes`, read through a scratch file in `dir`.
fn read_exr_path(bytes: &[u8], dir: &Path) -> twopass_composite::Image {
    let path = dir.join("scratch.exr");
    std::fs::write(&path, bytes).unwrap();
    let image = read_exr(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    image
}
