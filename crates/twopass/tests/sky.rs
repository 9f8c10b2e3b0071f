//! The sky through the command line: bad `[sky]` and `[[portal]]` tables exit 1 with the
//! file, line, table and key; `info` says whether the sky is in use and plans a scene lit by
//! the sky alone, which renders and is not refused as unlit.

use crate::common::{assert_ok, ok_json, twopass};
use crate::lamps::{floor_with, info_fails, renders_lit, write};

#[test]
fn bad_sky_tables_exit_1_naming_the_line_table_and_key() {
    let dir = tempfile::tempdir().unwrap();
    // The [sky] table starts at line 15.
    #[rustfmt::skip]
    let cases = [
        ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nturbidity = 1\n",
         ":15: sky: `turbidity` must be in [2, 10], where the daylight model is fitted (got 1)"),
        ("[sky]\nkind = \"daylight\"\nsun_elevation = 30\nsun_diameter = 90\n",
         ":15: sky: `sun_diameter` must be in (0, 45] degrees (got 90)"),
        ("[sky]\nkind = \"daylight\"\nsun_direction = [0, 1, 0]\nsun_elevation = 30\n",
         ":15: sky: give exactly one of `sun_elevation` (degrees, with `sun_azimuth`) and `sun_direction`"),
        ("[sky]\nkind = \"uniform\"\nradiance = [1, 1, -3]\n",
         ":15: sky: `radiance` channel 2 must be finite and non-negative (got -3 W/(m^2 sr))"),
        ("[sky]\nkind = \"uniform\"\nradiance = 1\n[[portal]]\norigin = [0, 1, 0]\nedge_u = [0, 0, 0]\nedge_v = [1, 0, 0]\n",
         ":18: portal 1: `edge_u` and `edge_v` are parallel or zero: the portal has no area"),
        ("[[portal]]\norigin = [0, 1, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\n",
         ":15: portal 1: `[[portal]]` needs a `[sky]` table (a portal only lets the sky in)"),
    ];
    for (bad, expected) in cases {
        info_fails(dir.path(), bad, expected);
    }
}

#[test]
fn info_says_when_the_sky_is_in_use_and_a_sky_alone_lights_a_render() {
    let dir = tempfile::tempdir().unwrap();
    let without = write(
        dir.path(),
        &floor_with("[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 1\n"),
    );
    let v = ok_json(&twopass(&["info", without.to_str().unwrap(), "--json"]));
    assert_eq!(v["plan"]["sky"]["required"], false);
    assert_eq!(
        v["plan"]["sky"]["reason"],
        "no [sky] table: rays that leave the scene see black"
    );
    let path = write(
        dir.path(),
        &floor_with(
            "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = 40\nscale = 0.001\n\
             [[portal]]\norigin = [-1, 1, -1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, 2]\n",
        ),
    );
    let out = twopass(&["info", path.to_str().unwrap()]);
    assert_ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    for line in [
        "diffuse pass      required: 1 diffusely reflecting object(s) lit by 0 emitter(s), 0 lamp(s) and the sky",
        "sky               required: daylight (Preetham), turbidity 3, sun elevation 40.0 deg, sun 0.53 deg wide,",
        "scale 0.001, 1 portal",
    ] {
        assert!(text.contains(line), "{line}\n{text}");
    }
    let v = ok_json(&twopass(&["info", path.to_str().unwrap(), "--json"]));
    assert_eq!(v["plan"]["sky"]["required"], true);
    renders_lit(dir.path(), &path, &["radiosity", "hybrid", "reference"]);
}

/// A grey wall (reflectance 0.5, 4 x 2 at z = 2, facing -z) and a perfect mirror tilted 45
/// degrees (1 x 0.707 about the origin, facing (0, 1, 1)) under a daylight sky with the sun
/// straight overhead: the mirror turns the sun's beam onto the wall, its image |x| < 0.5,
/// |y| < 0.25. The camera at z = 1 looks at the wall (90 degrees: it sees x and y in [-1, 1]).
const SUN_MIRROR: &str = "version = 1\n\
    [camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 2]\nfov_y = 90\nresolution = [64, 64]\n\
    [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = 1\n\
    [[object]]\nname = \"wall\"\nmaterial = \"grey\"\n\
    shape = { type = \"quad\", origin = [-2, -1, 2], edge_u = [0, 2, 0], edge_v = [4, 0, 0] }\n\
    [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
    shape = { type = \"quad\", origin = [-0.5, -0.25, 0.25], edge_u = [1, 0, 0], edge_v = [0, 0.5, -0.5] }\n\
    [sky]\nkind = \"daylight\"\nturbidity = 3\nsun_direction = [0, 1, 0]\nscale = 0.001\n";

/// The mean radiance (red) of the pixels of a [`SUN_MIRROR`] image inside the sun's mirrored
/// beam and in a band around it (0.15 clear of its edges).
fn beam_and_band(image: &twopass_composite::Image) -> (f64, f64) {
    let (mut inside, mut band) = (Vec::new(), Vec::new());
    for py in 0..64 {
        for px in 0..64 {
            // Image right is -x; at distance 1 with 90 degrees the image spans [-1, 1].
            let x = -((f64::from(px) + 0.5) / 32.0 - 1.0);
            let y = 1.0 - (f64::from(py) + 0.5) / 32.0;
            let (dx, dy) = (x.abs() - 0.5, y.abs() - 0.25);
            let r = f64::from(image.get(px, py).x);
            if dx < -0.15 && dy < -0.15 {
                inside.push(r);
            } else if (dx > 0.15 || dy > 0.15) && x.abs() < 0.95 && y.abs() < 0.7 {
                band.push(r);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(inside.len() > 50 && band.len() > 500);
    (mean(&inside), mean(&band))
}

/// The sun's beam through a mirror on every path a user takes: the gathered lightmap (its
/// photons start at the sky), the gathered hybrid and the path tracer (their light tracers
/// start at the sky), the classic hybrid and radiosity alone (the solution's specular
/// transfer). The wall inside the beam is brighter than around it by rho E_sun / pi, E_sun the
/// sun's irradiance across its beam (L_sun Omega_sun, the model's), within the dome's
/// change across the band (under 1 % of the step in the solution's test) and the noise.
#[test]
fn the_suns_beam_off_a_mirror_shows_on_every_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("sun-mirror.toml");
    std::fs::write(&scene, SUN_MIRROR).unwrap();
    let loaded = twopass_scene::load_toml(SUN_MIRROR, &scene).unwrap().0;
    let sun = loaded.sky.as_ref().unwrap().sun.unwrap();
    let e_sun = f64::from(sun.radiance.x * sun.solid_angle());
    let want = 0.5 * e_sun / std::f64::consts::PI;
    let bake = d.join("bake");
    assert_ok(&twopass(&[
        "bake",
        scene.to_str().unwrap(),
        "--lightmap",
        "--texel-size",
        "0.02",
        "--quiet",
        "-o",
        bake.to_str().unwrap(),
    ]));
    let lightmap = bake.join("sun-mirror.lightmap.glb");
    let cases: [(&str, Vec<&str>); 5] = [
        (
            "lightmap",
            vec![
                "--method",
                "radiosity",
                "--spp",
                "16",
                "--bake",
                lightmap.to_str().unwrap(),
            ],
        ),
        ("hybrid", vec!["--method", "hybrid", "--spp", "64"]),
        (
            "hybrid-classic",
            vec!["--method", "hybrid-classic", "--spp", "16"],
        ),
        ("radiosity", vec!["--method", "radiosity", "--spp", "16"]),
        ("reference", vec!["--method", "reference", "--spp", "256"]),
    ];
    for (name, args) in cases {
        let exr = d.join(format!("{name}.exr"));
        let mut all = vec![
            "render",
            scene.to_str().unwrap(),
            "--quiet",
            "-o",
            exr.to_str().unwrap(),
        ];
        all.extend(args);
        assert_ok(&twopass(&all));
        let image = twopass_composite::write::read_exr(&exr).unwrap();
        let (inside, band) = beam_and_band(&image);
        let step = inside - band;
        eprintln!("{name}: inside {inside}, band {band}, step {step} (want {want})");
        assert!(
            (step / want - 1.0).abs() < 0.03,
            "{name}: the beam's step {step} vs {want}"
        );
    }
}
