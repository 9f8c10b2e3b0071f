//! Base colour textures a scene cannot use: each an input error (exit 1) naming the MTL
//! library and line, the material, the texture file and the problem; never a panic. And a
//! textured floor rendered from its irradiance lightmap shows the texture, as from its radiance
//! lightmap.

use std::path::Path;

use crate::common::twopass;

/// Writes `quad.obj` and `quad.mtl` (its `map_Kd` naming `texture` on line 3) into `dir`;
/// returns the OBJ.
fn quad_with(dir: &Path, texture: &str) -> std::path::PathBuf {
    std::fs::write(
        dir.join("quad.mtl"),
        format!("newmtl checker\nKd 0.5 0.5 0.5\nmap_Kd {texture}\n"),
    )
    .unwrap();
    let obj = dir.join("quad.obj");
    std::fs::write(
        &obj,
        "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl checker\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    obj
}

/// A PNG whose header declares `width` x `height` RGB pixels followed by one tiny image data
/// chunk (a zlib stream of one zero byte): what a decompression bomb shows before it is
/// decoded.
fn png_header(width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, width, height);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().unwrap();
    w.write_chunk(
        png::chunk::IDAT,
        &[0x78, 0x9c, 0x63, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01],
    )
    .unwrap();
    drop(w);
    out
}

/// `twopass info` on the quad with `texture` fails with exit 1 and exactly `problem` after
/// the location.
fn refused(dir: &Path, texture: &str, problem: &str) {
    let obj = quad_with(dir, texture);
    let out = twopass(&["info".as_ref(), obj.as_os_str()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let expected = format!(
        "{}:3: material `checker`: texture {}: {problem}",
        dir.join("quad.mtl").display(),
        dir.join(texture).display()
    );
    assert!(
        stderr.contains(&expected),
        "expected `{expected}` in:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_missing_texture_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    refused(
        dir.path(),
        "missing.png",
        "cannot read: No such file or directory (os error 2)",
    );
}

#[test]
fn a_corrupt_png_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    // The signature and the start of the header chunk, cut short.
    let mut bytes = png_header(4, 4);
    bytes.truncate(20);
    std::fs::write(dir.path().join("corrupt.png"), &bytes).unwrap();
    refused(
        dir.path(),
        "corrupt.png",
        "not a readable Png image: unexpected end of file",
    );
    std::fs::write(dir.path().join("text.png"), "not an image").unwrap();
    refused(
        dir.path(),
        "text.png",
        "not a PNG or JPEG image (its first bytes are neither signature)",
    );
}

#[test]
fn a_decompression_bomb_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bomb.png"), png_header(100_000, 100_000)).unwrap();
    refused(
        dir.path(),
        "bomb.png",
        "its header declares 100000 x 100000 pixels, more than the 67108864 pixels (32768 on a side) read at most; not decoded",
    );
}

/// A 1 m floor (an OBJ whose `map_Kd` is an 8 x 8 red and green checker) under a square light,
/// seen from above, written into `dir`; returns the scene file.
fn checker_floor(dir: &Path) -> std::path::PathBuf {
    twopass_tests::write_checker_floor(dir, 8, [230, 30, 30], [30, 230, 30], 0.9);
    let scene = dir.join("floor.toml");
    std::fs::write(
        &scene,
        "version = 1\n[camera]\nposition = [0.5, 1.2, 0.5]\nlook_at = [0.5, 0, 0.5]\n\
         up = [0, 0, 1]\nfov_y = 40\nresolution = [64, 64]\n\
         [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"floor\"\nshape = { type = \"obj\", file = \"floor.obj\" }\n\
         [[object]]\nname = \"light\"\nmaterial = \"white\"\nemission = 10\n\
         shape = { type = \"quad\", origin = [0.3, 2, 0.3], edge_u = [0.4, 0, 0], edge_v = [0, 0, 0.4] }\n",
    )
    .unwrap();
    scene
}

#[test]
fn a_render_from_an_irradiance_lightmap_multiplies_by_the_texture() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = checker_floor(d);
    // The same floor from an irradiance lightmap (the texture applied per hit, as an engine
    // does) and from a radiance lightmap (the texture baked into the texels): both show the
    // checker, and agree pixel by pixel where a square's texels hold one colour.
    let render = |quantity: &str| {
        let out = d.join(quantity);
        let o = twopass(&[
            "bake".as_ref(),
            scene.as_os_str(),
            "--lightmap".as_ref(),
            "--texel-size".as_ref(),
            "0.01".as_ref(),
            "--lightmap-quantity".as_ref(),
            quantity.as_ref(),
            "--quiet".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let exr = d.join(format!("{quantity}.exr"));
        let o = twopass(&[
            "render".as_ref(),
            scene.as_os_str(),
            "--method".as_ref(),
            "radiosity".as_ref(),
            "--bake".as_ref(),
            out.join("floor.lightmap.glb").as_os_str(),
            "--quiet".as_ref(),
            "-o".as_ref(),
            exr.as_os_str(),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        twopass_composite::write::read_exr(&exr).unwrap()
    };
    let (irradiance, radiance) = (render("irradiance"), render("radiance"));
    let (mut reds, mut greens, mut agree, mut compared) = (0, 0, 0, 0);
    for (a, b) in irradiance.pixels().iter().zip(radiance.pixels()) {
        if b.x > 3.0 * b.y {
            reds += 1;
        } else if b.y > 3.0 * b.x {
            greens += 1;
        } else {
            continue; // a texel across a square's edge
        }
        compared += 1;
        if (a.x - b.x).abs() <= 0.05 * b.x.max(b.y) && (a.y - b.y).abs() <= 0.05 * b.x.max(b.y) {
            agree += 1;
        }
    }
    assert!(
        reds > 100 && greens > 100,
        "the checker shows: {reds} red, {greens} green pixels"
    );
    assert!(
        agree * 10 >= compared * 9,
        "{agree} of {compared} pixels agree within 5 %"
    );
}

/// A textured room (the checker floor, two white walls, a white block) lit by a point lamp and
/// the sun of a daylight sky (open above and in front): the render from its gathered lightmap
/// within 4 % relative RMSE of the path tracer's image of the same scene, the target for real
/// scenes, with the reference's own noise shown to be far below it.
#[test]
fn a_textured_room_under_a_point_lamp_and_the_sun_bakes_within_4_percent_of_the_path_tracer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    twopass_tests::write_checker_floor(d, 8, [230, 40, 30], [40, 200, 60], 0.9);
    let scene = d.join("room.toml");
    std::fs::write(
        &scene,
        "version = 1\n[camera]\nposition = [0.95, 0.85, 1.7]\nlook_at = [0.4, 0.2, 0.3]\n\
         fov_y = 50\nresolution = [48, 48]\n\
         [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.7\n\
         [[object]]\nname = \"floor\"\nshape = { type = \"obj\", file = \"floor.obj\" }\n\
         [[object]]\nname = \"back\"\nmaterial = \"white\"\n\
         shape = { type = \"quad\", origin = [0, 0, 0], edge_u = [1, 0, 0], edge_v = [0, 0.8, 0] }\n\
         [[object]]\nname = \"left\"\nmaterial = \"white\"\n\
         shape = { type = \"quad\", origin = [0, 0, 0], edge_u = [0, 0.8, 0], edge_v = [0, 0, 1] }\n\
         [[object]]\nname = \"block\"\nmaterial = \"white\"\n\
         shape = { type = \"box\", min = [0.35, 0, 0.35], max = [0.55, 0.25, 0.55] }\n\
         [[light]]\nkind = \"point\"\nname = \"bulb\"\nposition = [0.75, 0.5, 0.25]\nintensity = 1\n\
         [sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = 50\nsun_azimuth = 45\n\
         scale = 0.05\n",
    )
    .unwrap();
    let run = |args: &[&std::ffi::OsStr]| {
        let o = twopass(args);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let out = d.join("bake");
    run(&[
        "bake".as_ref(),
        scene.as_os_str(),
        "--lightmap".as_ref(),
        "--texel-size".as_ref(),
        "0.01".as_ref(),
        "--quiet".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    let render = |name: &str, extra: &[&str]| {
        let exr = d.join(format!("{name}.exr"));
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "render".as_ref(),
            scene.as_os_str(),
            "--quiet".as_ref(),
            "-o".as_ref(),
            exr.as_os_str(),
        ];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        run(&args);
        twopass_composite::write::read_exr(&exr).unwrap()
    };
    let lightmap = out.join("room.lightmap.glb");
    // As many samples per pixel as the reference's halves have, near enough: at 16 the pixels
    // across the room's edges against the sky carry the coverage's noise (4.7 % in all).
    let baked = render(
        "baked",
        &[
            "--method",
            "radiosity",
            "--spp",
            "256",
            "--bake",
            lightmap.to_str().unwrap(),
        ],
    );
    let halves = [1, 2].map(|seed| {
        render(
            &format!("reference-{seed}"),
            &[
                "--method",
                "reference",
                "--spp",
                "1024",
                "--seed",
                &seed.to_string(),
            ],
        )
    });
    let reference = twopass_composite::Image::from_fn(48, 48, |x, y| {
        (halves[0].get(x, y) + halves[1].get(x, y)) * 0.5
    });
    let tone = twopass_composite::ToneMap::default();
    let metric = |a, b| twopass_composite::metric::compare(a, b, &tone).unwrap();
    // Light reaches the room from the lamp, the sun and the dome: bright enough that the
    // relative error's constant (0.01 against r^2) does not hide errors.
    let mean = reference
        .pixels()
        .iter()
        .map(|p| p.element_sum())
        .sum::<f32>()
        / (3 * reference.pixels().len()) as f32;
    assert!(mean > 0.5, "the room's mean radiance {mean}");
    // The reference's own noise: one half against the other is sqrt(2) times a half's noise,
    // twice the two-half mean's.
    let noise = 0.5 * metric(&halves[0], &halves[1]).rel_rmse;
    let error = metric(&baked, &reference).rel_rmse;
    eprintln!(
        "textured room: lightmap render {:.2} % from the reference, its noise {:.2} %",
        100.0 * error,
        100.0 * noise
    );
    assert!(noise < 0.01, "the reference's noise {noise}");
    assert!(
        error < 0.04,
        "the lightmap render is {error} from the path tracer"
    );
}
