//! twopass's path tracer against a third-party renderer: Mitsuba 3 (PyPI's `mitsuba`, its
//! `scalar_rgb` path tracer, driven by `tests/mitsuba/render.py` through the scene converter
//! `crates/twopass/bench/mitsuba_scene.py`) renders the same scene lit by each of the lights a
//! user brings besides area emitters: a point lamp, a spot, a directional lamp, a uniform
//! sky, and the daylight sky with its sun (tabulated from twopass's model, since Mitsuba's
//! daylight is another model: this compares how each engine renders the sky it is given). The two images must agree per region of 8 x 8 pixels, within a tolerance that the
//! images' own noise (each engine's two halves, with different seeds) is shown to be far below.
//!
//! Mitsuba is not a dependency of twopass: without it these tests print a note and pass, except
//! when `CI` is set (`.ci/run` installs it), where they fail.

use std::path::Path;

use crate::common::{assert_ok, cli, repo};

/// Image side, pixels.
const SIZE: u32 = 64;
/// Samples per pixel of each half of each engine's image.
const SPP: u32 = 2048;
/// Region side, pixels.
const BLOCK: usize = 8;

/// The room every case is lit in: a floor, a back wall and a red left wall (open above, in
/// front and on the right, so the sky reaches in), a grey block on the floor casting shadows.
const ROOM: &str = r#"version = 1
[camera]
position = [0, 2.2, 5]
look_at = [0, 0.6, 0]
fov_y = 50
resolution = [64, 64]
[[material]]
name = "grey"
type = "lambert"
diffuse = 0.5
[[material]]
name = "red"
type = "lambert"
diffuse = [0.6, 0.2, 0.15]
[[object]]
name = "floor"
material = "grey"
shape = { type = "quad", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }
[[object]]
name = "back"
material = "grey"
shape = { type = "quad", origin = [-2, 0, -2], edge_u = [4, 0, 0], edge_v = [0, 2.5, 0] }
[[object]]
name = "left"
material = "red"
shape = { type = "quad", origin = [-2, 0, -2], edge_u = [0, 2.5, 0], edge_v = [0, 0, 4] }
[[object]]
name = "block"
material = "grey"
shape = { type = "box", min = [-0.2, 0, -0.8], max = [0.7, 0.9, 0.1] }
"#;

/// Whether Mitsuba 3 can be imported; `false` (after a note) when it cannot and `CI` is not
/// set.
fn mitsuba_found() -> bool {
    let found = std::process::Command::new("python3")
        .args(["-c", "import mitsuba, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        if std::env::var_os("CI").is_some() {
            panic!("Mitsuba 3 is not importable by python3: .ci/run installs it with pip");
        }
        eprintln!("note: not compared with Mitsuba 3: `python3 -c 'import mitsuba'` fails");
    }
    found
}

/// The mean RGB of each `BLOCK` x `BLOCK` region of the EXR at `path`, row by row.
fn blocks(path: &Path) -> Vec<[f64; 3]> {
    let image = twopass_composite::write::read_exr(path).unwrap();
    assert_eq!((image.width(), image.height()), (SIZE, SIZE), "{path:?}");
    let n = SIZE as usize / BLOCK;
    let mut sums = vec![[0.0; 3]; n * n];
    for y in 0..SIZE {
        for x in 0..SIZE {
            let p = image.get(x, y);
            let b = &mut sums[(y as usize / BLOCK) * n + x as usize / BLOCK];
            for (s, v) in b.iter_mut().zip([p.x, p.y, p.z]) {
                assert!(v.is_finite(), "{path:?}: pixel ({x}, {y}) is {v}");
                *s += f64::from(v) / (BLOCK * BLOCK) as f64;
            }
        }
    }
    sums
}

/// Renders `scene` with twopass's path tracer and with Mitsuba, two halves of `SPP` each (seeds
/// 1 and 2), into `dir`; returns the halves' regions, twopass's then Mitsuba's.
fn render_both(dir: &Path, scene: &Path) -> [[Vec<[f64; 3]>; 2]; 2] {
    let half = |engine: &str, seed: u32| {
        let out = dir.join(format!("{engine}-{seed}.exr"));
        if engine == "twopass" {
            let o = cli("render")
                .arg(scene)
                .words(&format!(
                    "--method reference --spp {SPP} --width {SIZE} --height {SIZE} --seed {seed} --quiet"
                ))
                .output(&out)
                .run();
            assert_ok(&o);
        } else {
            let o = std::process::Command::new("python3")
                .arg(repo("tests/mitsuba/render.py"))
                .arg(scene)
                .args([SIZE, SIZE, SPP, seed].map(|v| v.to_string()))
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                o.status.success(),
                "Mitsuba: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        blocks(&out)
    };
    ["twopass", "mitsuba"].map(|engine| [half(engine, 1), half(engine, 2)])
}

/// Largest relative difference allowed between the engines' regions (both halves averaged),
/// over max(region, 10 % of the image's mean): the engines model these lights the same way
/// (their units are converted exactly), so only noise and the spot's cone edge (a ramp 0.14
/// degrees wide that the two engines shape differently) separate them.
const TOLERANCE: f64 = 0.03;

/// Compares the engines on `ROOM` lit by `lights` (TOML appended to the room).
fn agree(name: &str, lights: &str) {
    agree_with(name, lights, |_| {});
}

/// [`agree`], `prepare` first given the scene file (to write what the converter reads beside
/// it).
fn agree_with(name: &str, lights: &str, prepare: impl FnOnce(&Path)) {
    if !mitsuba_found() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join(format!("{name}.toml"));
    std::fs::write(&scene, format!("{ROOM}{lights}")).unwrap();
    prepare(&scene);
    let [[t1, t2], [m1, m2]] = render_both(dir.path(), &scene);
    let mean = |b: &[[f64; 3]]| b.iter().flatten().sum::<f64>() / (3 * b.len()) as f64;
    let image_mean = 0.25 * (mean(&t1) + mean(&t2) + mean(&m1) + mean(&m2));
    assert!(image_mean > 0.0, "{name}: the room is dark");
    let floor = 0.1 * image_mean;
    let (mut worst, mut worst_noise, mut at) = (0.0_f64, 0.0_f64, 0);
    let mut sums = [0.0_f64; 2];
    for i in 0..t1.len() {
        for c in 0..3 {
            let t = 0.5 * (t1[i][c] + t2[i][c]);
            let m = 0.5 * (m1[i][c] + m2[i][c]);
            let scale = t.max(m).max(floor);
            // Each engine's noise in its two-half mean: half the halves' difference.
            let noise = (0.5 * (t1[i][c] - t2[i][c]).abs()).max(0.5 * (m1[i][c] - m2[i][c]).abs());
            worst_noise = worst_noise.max(noise / scale);
            let d = (t - m).abs() / scale;
            if d > worst {
                (worst, at) = (d, i);
            }
            sums[0] += t;
            sums[1] += m;
        }
    }
    let n = SIZE as usize / BLOCK;
    eprintln!(
        "{name}: worst region ({}, {}) differs by {:.2} %, the worst half-to-half noise is \
         {:.2} %, image means twopass {:.5} Mitsuba {:.5}",
        at % n,
        at / n,
        100.0 * worst,
        100.0 * worst_noise,
        sums[0] / (3 * t1.len()) as f64,
        sums[1] / (3 * t1.len()) as f64,
    );
    // The tolerance means something only if the noise is well below it.
    assert!(
        worst_noise < TOLERANCE / 3.0,
        "{name}: noise {worst_noise} too large for the tolerance"
    );
    assert!(
        worst < TOLERANCE,
        "{name}: region ({}, {}) differs from Mitsuba by {:.2} %",
        at % n,
        at / n,
        100.0 * worst
    );
    let whole = (sums[0] - sums[1]).abs() / sums[1];
    assert!(
        whole < 0.01,
        "{name}: the image means differ by {:.2} %",
        100.0 * whole
    );
}

#[test]
fn a_point_lamp_renders_as_in_mitsuba() {
    agree(
        "point",
        "[[light]]\nkind = \"point\"\nposition = [0.8, 2.0, 0.9]\nintensity = 4\n",
    );
}

#[test]
fn a_spot_renders_as_in_mitsuba() {
    // A hard-edged cone (inner = outer): the falloff between the angles is glTF's, which
    // Mitsuba does not have (the converter refuses a soft spot).
    agree(
        "spot",
        "[[light]]\nkind = \"spot\"\nposition = [0.3, 3.0, 1.6]\nlook_at = [0, 0, -0.4]\n\
         power = 150\ninner_angle = 45\nouter_angle = 45\n",
    );
}

#[test]
fn a_directional_lamp_renders_as_in_mitsuba() {
    agree(
        "directional",
        "[[light]]\nkind = \"directional\"\ndirection = [-0.4, -1, -0.6]\nirradiance = 1.5\n\
         colour = [1, 0.9, 0.8]\n",
    );
}

#[test]
fn a_uniform_sky_renders_as_in_mitsuba() {
    agree(
        "sky",
        "[sky]\nkind = \"uniform\"\nradiance = [0.3, 0.4, 0.5]\n",
    );
}

/// Writes beside `scene` the tabulation of its daylight sky that the converter turns into
/// Mitsuba's emitters (`crates/twopass/bench/mitsuba_scene.py`): the dome's radiance from
/// twopass's model on a 1024 x 512 map in Mitsuba's `envmap` layout, and the sun's disc.
fn tabulate_daylight(scene: &Path) {
    let (s, _) = twopass_scene::load(scene).unwrap();
    let sky = s.sky.as_ref().expect("a sky");
    let (w, h) = (1024u32, 512u32);
    let mut dome = twopass_image::Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let (t, p) = (std::f32::consts::PI * v, std::f32::consts::TAU * u);
            let d = glam::Vec3::new(t.sin() * p.sin(), t.cos(), -t.sin() * p.cos());
            dome.set(x, y, sky.dome_radiance(d));
        }
    }
    twopass_composite::write::write_exr(&scene.with_extension("sky.exr"), &dome).unwrap();
    let sun = sky.sun.as_ref().map(|sun| {
        serde_json::json!({
            "direction": sun.direction.to_array(),
            "one_minus_cos": sun.one_minus_cos,
            "radiance": sun.radiance.to_array(),
        })
    });
    std::fs::write(
        scene.with_extension("sun.json"),
        serde_json::to_vec(&sun).unwrap(),
    )
    .unwrap();
}

#[test]
fn a_daylight_sky_and_its_sun_render_as_in_mitsuba() {
    // Preetham's dome and a sun of 0.53 degrees, 40 degrees up, in from the open front right:
    // the sun's hard shadow of the block on the floor, the dome everywhere else.
    agree_with(
        "daylight",
        "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = 40\nsun_azimuth = 35\n\
         scale = 0.01\n",
        tabulate_daylight,
    );
}
