//! `twopass render --bake x.lightmap.glb`: a lightmap bake read back (the `.glb`'s
//! `TEXCOORD_1` and the HDR lightmap EXR beside it) renders what the radiosity solution it was
//! baked from renders, and a lightmap of another scene, a missing EXR or hybrid-direct are
//! refused with the file named.

mod common;

use std::path::Path;

use common::{assert_ok, bake_cornell_lightmap, repo, twopass};
use twopass_composite::metric::compare;
use twopass_composite::tonemap::ToneMap;
use twopass_composite::write::read_exr;

fn render(scene: &str, bake: &Path, method: &str, out: &Path) -> std::process::Output {
    twopass(&[
        "render",
        repo(scene).to_str().unwrap(),
        "--method",
        method,
        "--bake",
        bake.to_str().unwrap(),
        "--width",
        "128",
        "--height",
        "128",
        "--spp",
        "16",
        "--output",
        out.to_str().unwrap(),
        "--quiet",
    ])
}

#[test]
fn a_lightmap_glb_renders_as_the_solution_it_was_baked_from() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    bake_cornell_lightmap(dir);
    let from_bake = dir.join("from-bake.exr");
    let from_glb = dir.join("from-glb.exr");
    let scene = "scenes/cornell-box.toml";
    assert_ok(&render(
        scene,
        &dir.join("cornell-box.bake"),
        "radiosity",
        &from_bake,
    ));
    assert_ok(&render(
        scene,
        &dir.join("cornell-box.lightmap.glb"),
        "radiosity",
        &from_glb,
    ));
    let reference = read_exr(&from_bake).unwrap();
    let image = read_exr(&from_glb).unwrap();
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
    let glb = dir.join("cornell-box.lightmap.glb");
    let out_file = dir.join("x.exr");
    let other = render("scenes/cornell-spheres.toml", &glb, "radiosity", &out_file);
    let err = String::from_utf8_lossy(&other.stderr);
    assert_eq!(other.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cornell-box.lightmap.glb") && err.contains("another scene"),
        "{err}"
    );
    let direct = render("scenes/cornell-box.toml", &glb, "hybrid-direct", &out_file);
    let err = String::from_utf8_lossy(&direct.stderr);
    assert_eq!(direct.status.code(), Some(1), "{err}");
    assert!(err.contains("hybrid-direct"), "{err}");
    // The EXR removed: the manifest check names it, and without the manifest the reader does.
    std::fs::remove_file(dir.join("cornell-box.lightmap.exr")).unwrap();
    std::fs::remove_file(dir.join("cornell-box.manifest.json")).unwrap();
    let missing = render("scenes/cornell-box.toml", &glb, "radiosity", &out_file);
    let err = String::from_utf8_lossy(&missing.stderr);
    assert_eq!(missing.status.code(), Some(1), "{err}");
    assert!(err.contains("cornell-box.lightmap.exr"), "{err}");
    assert!(!out_file.exists());
}
