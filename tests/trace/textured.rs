//! A checker floor's bounce colour on a white wall (issue 41): a box of grey walls lit from the
//! ceiling, its floor an 8 x 8 checker of red and green (an OBJ with `map_Kd`, the PNG written
//! here). The back wall's light, per quarter of a view that sees only it, from radiosity alone
//! and from the gathered hybrid, against the path tracer on the same scene; and its hue
//! against the closed form: a checker seen from afar reflects its area-weighted mean albedo,
//! so the wall's colour is that of the same box with a flat floor of the mean albedo (solved
//! without any texture).

use std::ops::ControlFlow;
use std::path::Path;

use twopass_brdf::Rgb;
use twopass_image::Image;
use twopass_scene::Scene;
use twopass_trace::hybrid::{gathered, radiosity_only};
use twopass_trace::{
    Integrator, Reference, ReferenceSettings, RenderProgress, RenderSettings, WhittedSettings,
    render,
};

/// The checker's two colours, 8-bit sRGB.
const RED: [u8; 3] = [230, 30, 30];
const GREEN: [u8; 3] = [30, 230, 30];

/// The floor's `Kd`: the texture's factor.
const KD: f32 = 0.9;

/// sRGB to linear (IEC 61966-2-1), for the closed form.
fn linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The box: walls, ceiling and front of grey 0.7, a 0.3 x 0.3 light below the ceiling, the
/// floor `floor` (a TOML object line), camera inside the front looking at the back wall.
fn box_toml(floor: &str, floor_material: &str) -> String {
    format!(
        r#"version = 1
[camera]
position = [0.5, 0.5, 0.02]
look_at = [0.5, 0.5, 1.0]
up = [0, 1, 0]
fov_y = 50
resolution = [16, 16]

[[material]]
name = "white"
type = "lambert"
diffuse = [0.7, 0.7, 0.7]
{floor_material}
[[object]]
name = "light"
material = "white"
emission = [20, 20, 20]
shape = {{ type = "quad", origin = [0.35, 0.999, 0.35], edge_u = [0.3, 0, 0], edge_v = [0, 0, 0.3] }}

[[object]]
name = "back"
material = "white"
shape = {{ type = "quad", origin = [0, 0, 1], edge_u = [0, 1, 0], edge_v = [1, 0, 0] }}

[[object]]
name = "left"
material = "white"
shape = {{ type = "quad", origin = [0, 0, 0], edge_u = [0, 1, 0], edge_v = [0, 0, 1] }}

[[object]]
name = "right"
material = "white"
shape = {{ type = "quad", origin = [1, 0, 0], edge_u = [0, 0, 1], edge_v = [0, 1, 0] }}

[[object]]
name = "ceiling"
material = "white"
shape = {{ type = "quad", origin = [0, 1, 0], edge_u = [1, 0, 0], edge_v = [0, 0, 1] }}

[[object]]
name = "front"
material = "white"
shape = {{ type = "quad", origin = [0, 0, 0], edge_u = [1, 0, 0], edge_v = [0, 1, 0] }}

{floor}
"#
    )
}

/// The box with the checker floor, written into `dir`.
fn checker_box(dir: &Path) -> Scene {
    twopass_tests::write_checker_floor(dir, 8, RED, GREEN, KD);
    let path = dir.join("box.toml");
    let floor = "[[object]]\nname = \"floor\"\nshape = { type = \"obj\", file = \"floor.obj\" }\n";
    std::fs::write(&path, box_toml(floor, "")).unwrap();
    let (scene, _) = twopass_scene::load(&path).unwrap();
    assert_eq!(scene.textures.len(), 1, "the floor's texture is read");
    scene
}

/// The same box with a flat floor of the checker's mean albedo: no texture anywhere.
fn mean_box() -> Scene {
    let mean = Rgb::new(
        (linear(RED[0]) + linear(GREEN[0])) / 2.0,
        (linear(RED[1]) + linear(GREEN[1])) / 2.0,
        (linear(RED[2]) + linear(GREEN[2])) / 2.0,
    ) * KD;
    let material = format!(
        "[[material]]\nname = \"mean\"\ntype = \"lambert\"\ndiffuse = [{}, {}, {}]\n",
        mean.x, mean.y, mean.z
    );
    let floor = "[[object]]\nname = \"floor\"\nmaterial = \"mean\"\nshape = { type = \"quad\", origin = [0, 0, 0], edge_u = [0, 0, 1], edge_v = [1, 0, 0] }\n";
    twopass_scene::load_toml(&box_toml(floor, &material), Path::new("mean.toml"))
        .unwrap()
        .0
}

fn solve(scene: &Scene, method: twopass_radiosity::Method) -> twopass_radiosity::Solution {
    let options = twopass_radiosity::Options {
        method,
        element_size: Some(0.04),
        stop: twopass_radiosity::Stop {
            unshot_fraction: 1e-4,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut solver = twopass_radiosity::Solver::new(scene, options).unwrap();
    solver.run(|_| ControlFlow::Continue(()));
    solver.solution()
}

fn image(scene: &Scene, integrator: &dyn Integrator, spp: u32) -> Image {
    let settings = RenderSettings {
        samples_per_pixel: spp,
        seed: 41,
        ..RenderSettings::default()
    };
    render(
        scene,
        &scene.camera,
        integrator,
        &settings,
        &RenderProgress::new(),
    )
    .layers
    .composite()
}

/// Per quarter of the 16 x 16 view (top left, top right, bottom left, bottom right): the mean
/// colour and the standard error of that mean from its 64 pixels' spread.
fn quarters(img: &Image) -> [(Rgb, Rgb); 4] {
    std::array::from_fn(|q| {
        let (x0, y0) = ((q as u32 % 2) * 8, (q as u32 / 2) * 8);
        let px: Vec<Rgb> = (y0..y0 + 8)
            .flat_map(|y| (x0..x0 + 8).map(move |x| (x, y)))
            .map(|(x, y)| img.get(x, y))
            .collect();
        let n = px.len() as f32;
        let mean = px.iter().copied().sum::<Rgb>() / n;
        let var = px.iter().map(|p| (*p - mean) * (*p - mean)).sum::<Rgb>() / (n - 1.0);
        (mean, (var / n).sqrt())
    })
}

#[test]
fn a_checker_floor_colours_the_white_wall_as_its_mean_albedo_does() {
    let dir = tempfile::tempdir().unwrap();
    let scene = checker_box(dir.path());
    let reference = image(
        &scene,
        &Reference::new(&scene, ReferenceSettings::default()),
        1024,
    );
    let reference = quarters(&reference);
    let progressive = solve(&scene, twopass_radiosity::Method::Progressive);
    let hierarchical = solve(&scene, twopass_radiosity::Method::Hierarchical);
    let mean_scene = mean_box();
    let flat = |method| {
        let solution = solve(&mean_scene, method);
        quarters(&image(
            &mean_scene,
            &radiosity_only(&mean_scene, &solution),
            4,
        ))
    };
    let flat = [
        flat(twopass_radiosity::Method::Progressive),
        flat(twopass_radiosity::Method::Hierarchical),
    ];
    // Radiosity (either solver) and the gathered hybrid against the path tracer, per quarter
    // and channel. The tolerances hold the solvers' known bias on a 4 cm element mesh (the
    // hierarchical one's link refinement leaves it about 2 % dark here) and the reference's
    // noise (1024 paths per pixel, 64 pixels a quarter: about 0.5 %); a floor read without its
    // texture (white, Kd 0.9) would put the wall's blue 13 % above the reference.
    let renders = [
        (
            "progressive",
            image(&scene, &radiosity_only(&scene, &progressive), 4),
            0.03,
        ),
        (
            "hierarchical",
            image(&scene, &radiosity_only(&scene, &hierarchical), 4),
            0.04,
        ),
        (
            "hybrid",
            image(
                &scene,
                &gathered(&scene, &progressive, WhittedSettings::default()),
                64,
            ),
            0.03,
        ),
    ];
    for (name, img, tolerance) in &renders {
        for (q, ((got, _), (want, _))) in quarters(img).iter().zip(&reference).enumerate() {
            let rel = ((*got - *want).abs() / *want).max_element();
            assert!(
                rel < *tolerance,
                "{name}, quarter {q}: {got} against the reference's {want}: {rel}"
            );
        }
    }
    // The hue: green and blue over red. The checker's red and green have equal means, so the
    // wall's green equals its red; its blue over red is the mean-albedo floor's (radiosity on
    // a scene without textures, by the same solver), from the textured radiosity and from
    // the path tracer.
    let hue = |c: Rgb| Rgb::new(1.0, c.y / c.x, c.z / c.x);
    for (q, (want, _)) in reference.iter().enumerate() {
        let expected = [hue(flat[0][q].0), hue(flat[1][q].0)];
        assert!((expected[0].y - 1.0).abs() < 1e-4, "{expected:?}");
        for (name, got, expected, tolerance) in [
            (
                "progressive",
                quarters(&renders[0].1)[q].0,
                expected[0],
                1e-3,
            ),
            (
                "hierarchical",
                quarters(&renders[1].1)[q].0,
                expected[1],
                1e-3,
            ),
            ("reference", *want, expected[0], 0.015),
        ] {
            let h = hue(got);
            assert!(
                (h - expected).abs().max_element() < tolerance,
                "{name}, quarter {q}: hue {h} against the mean floor's {expected}"
            );
        }
    }
}
