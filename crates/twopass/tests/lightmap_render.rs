//! `twopass render --bake x.lightmap.glb`: a lightmap bake read back (the `.glb`'s
//! `TEXCOORD_1` and the HDR lightmap EXR beside it) renders what the radiosity solution it was
//! baked from renders, and a lightmap of another scene, a missing EXR or hybrid-direct are
//! refused with the file named.

use std::path::Path;

use crate::common::{BOX, SPHERES, assert_ok, bake_cornell_lightmap, cli, repo};
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
    // The EXR removed: the manifest check names it, and without the manifest the reader does.
    std::fs::remove_file(dir.join("cornell-box.lightmap.exr")).unwrap();
    std::fs::remove_file(dir.join("cornell-box.manifest.json")).unwrap();
    let err = refused(BOX, "radiosity");
    assert!(err.contains("cornell-box.lightmap.exr"), "{err}");
    assert!(!dir.join("x.exr").exists());
}
