//! The sky in both radiosity solvers and its sampling against closed forms: a plane under a
//! uniform sky of radiance L receives E = pi L; under a daylight sky it receives the sun's
//! L_sun Omega cos(theta) (the model's own sun radiance) plus the dome's integral of L cos; a
//! sun below the horizon gives no sun light and no NaN; one and two threads solve alike; a
//! room lit through one window gets the same irradiance at a floor point with and without a
//! portal on the window (Lambert's polygon formula), with far smaller variance with it.

use std::ops::ControlFlow;

use glam::{DVec3, Vec3};
use twopass_radiosity::{Method, Options, Solver, Stop};
use twopass_scene::{Ray, Scene, Sky};

use crate::lamps::{RHO, plane_under};

const METHODS: [Method; 2] = [Method::Progressive, Method::Hierarchical];

fn options(method: Method) -> Options {
    Options {
        method,
        element_size: Some(0.25),
        stop: Stop {
            unshot_fraction: 1e-6,
            ..Stop::default()
        },
        ..Options::default()
    }
}

/// Per method, B / rho at every vertex of the plane (object 0) of `scene`: its irradiance,
/// W/m^2 (the plane sees nothing else, so that is all it receives).
fn plane_irradiance(scene: &Scene) -> Vec<Vec<DVec3>> {
    METHODS
        .iter()
        .map(|&method| {
            let mut solver = Solver::new(scene, options(method)).unwrap();
            solver.run(|_| ControlFlow::Continue(()));
            let solution = solver.solution();
            let b = solution.vertex_radiosity();
            solution
                .mesh()
                .vertices
                .iter()
                .enumerate()
                .filter(|(_, v)| v.object == 0)
                .map(|(i, _)| b[i].as_dvec3() / RHO)
                .collect()
        })
        .collect()
}

/// The dome's irradiance on a surface facing `up` (W/m^2 per channel), by the midpoint rule
/// over a 512 x 1024 grid of the upper hemisphere (its error is far under 1e-4 of the value
/// for the smooth dome).
pub(crate) fn dome_irradiance(sky: &Sky, up: Vec3) -> DVec3 {
    let frame = twopass_brdf::frame::Frame::from_normal(up);
    let (nt, np) = (512, 1024);
    let mut sum = DVec3::ZERO;
    for i in 0..nt {
        let theta = (f64::from(i) + 0.5) / f64::from(nt) * std::f64::consts::FRAC_PI_2;
        for j in 0..np {
            let phi = (f64::from(j) + 0.5) / f64::from(np) * std::f64::consts::TAU;
            let local = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            let l = sky
                .dome_radiance(frame.to_world(local.as_vec3()))
                .as_dvec3();
            sum += l * (theta.cos() * theta.sin());
        }
    }
    sum * (std::f64::consts::FRAC_PI_2 / f64::from(nt)) * (std::f64::consts::TAU / f64::from(np))
}

/// Mean and standard error of the mean, per channel.
fn mean_and_error(values: &[DVec3]) -> (DVec3, DVec3) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<DVec3>() / n;
    let var = values
        .iter()
        .map(|v| (*v - mean) * (*v - mean))
        .sum::<DVec3>()
        / (n - 1.0);
    (mean, (var / n).map(f64::sqrt))
}

#[test]
fn a_plane_under_a_uniform_sky_receives_pi_l() {
    let s = plane_under("[sky]\nkind = \"uniform\"\nradiance = [1, 2, 3]\n", false);
    let expected = DVec3::new(1.0, 2.0, 3.0) * std::f64::consts::PI;
    for (method, vertices) in METHODS.iter().zip(plane_irradiance(&s)) {
        // The hierarchical solver keeps the plane's two triangles (the light is even).
        assert!(vertices.len() >= 4, "{method:?}: {}", vertices.len());
        for e in vertices {
            // Every cosine-distributed sample of a uniform sky gives pi L exactly: f32
            // rounding only.
            assert!(
                ((e - expected).abs() / expected).max_element() < 1e-5,
                "{method:?}: {e} vs {expected}"
            );
        }
    }
}

/// A daylight sky with the sun at `elevation` degrees, turbidity 3.
fn daylight(elevation: f32) -> String {
    format!(
        "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_elevation = {elevation}\nsun_azimuth = 30\nscale = 0.001\n"
    )
}

#[test]
fn a_plane_under_daylight_receives_the_suns_closed_form_and_the_domes_integral() {
    for elevation in [35.0f32, 5.0, -5.0] {
        let s = plane_under(&daylight(elevation), false);
        let sky = s.sky.as_ref().unwrap();
        // The sun: L_sun times its solid angle times cos(theta) = sin(elevation), its
        // radiance the model's own; none below the horizon.
        let sun = sky.sun.map_or(DVec3::ZERO, |sun| {
            let half = (0.53f64 / 2.0).to_radians();
            let omega = std::f64::consts::TAU * (1.0 - half.cos());
            sun.radiance.as_dvec3() * omega * f64::from(elevation).to_radians().sin()
        });
        assert_eq!(sun == DVec3::ZERO, elevation < 0.0);
        let expected = sun + dome_irradiance(sky, Vec3::Y);
        for (method, vertices) in METHODS.iter().zip(plane_irradiance(&s)) {
            assert!(vertices.iter().all(|v| v.is_finite()));
            // Each vertex is an independent stratified estimate: the mean over the vertices
            // is within five standard errors (plus the quadrature's 1e-4).
            assert!(vertices.len() >= 4, "{method:?}: {}", vertices.len());
            let (mean, error) = mean_and_error(&vertices);
            let gap = (mean - expected).abs();
            eprintln!(
                "{method:?} elevation {elevation}: {mean} vs {expected} (standard error {error}, {} vertices)",
                vertices.len()
            );
            assert!(
                gap.cmple(error * 5.0 + expected * 1e-4).all(),
                "{method:?} elevation {elevation}: {mean} vs {expected} (standard error {error})"
            );
        }
    }
}

#[test]
fn the_sky_solves_the_same_on_one_and_two_threads() {
    let s = plane_under(&daylight(40.0), true);
    for method in METHODS {
        let solve = || {
            let mut solver = Solver::new(&s, options(method)).unwrap();
            solver.run(|_| ControlFlow::Continue(()));
            solver.solution().vertex_radiosity().to_vec()
        };
        let one = crate::on_threads(1, solve);
        let two = crate::on_threads(2, solve);
        assert!(one == two, "{method:?}");
    }
}

/// A closed 4 x 3 x 4 room whose -z wall has a 1 x 1 window (x in [-0.5, 0.5], y in [1, 2]),
/// under a uniform sky of radiance 1, with a portal on the window or without.
fn window_room(portal: bool) -> Scene {
    let quad = |name: &str, o: [f32; 3], u: [f32; 3], v: [f32; 3]| {
        format!(
            "[[object]]\nname = \"{name}\"\nmaterial = \"grey\"\n\
             shape = {{ type = \"quad\", origin = {o:?}, edge_u = {u:?}, edge_v = {v:?} }}\n"
        )
    };
    let walls = [
        quad("floor", [-2.0, 0.0, -2.0], [0.0, 0.0, 4.0], [4.0, 0.0, 0.0]),
        quad(
            "ceiling",
            [-2.0, 3.0, -2.0],
            [4.0, 0.0, 0.0],
            [0.0, 0.0, 4.0],
        ),
        quad("back", [-2.0, 0.0, 2.0], [0.0, 3.0, 0.0], [4.0, 0.0, 0.0]),
        quad("left", [-2.0, 0.0, -2.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]),
        quad("right", [2.0, 0.0, -2.0], [0.0, 0.0, 4.0], [0.0, 3.0, 0.0]),
        quad(
            "front-left",
            [-2.0, 0.0, -2.0],
            [1.5, 0.0, 0.0],
            [0.0, 3.0, 0.0],
        ),
        quad(
            "front-right",
            [0.5, 0.0, -2.0],
            [1.5, 0.0, 0.0],
            [0.0, 3.0, 0.0],
        ),
        quad("sill", [-0.5, 0.0, -2.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        quad(
            "lintel",
            [-0.5, 2.0, -2.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ),
    ]
    .concat();
    let portal = if portal {
        "[[portal]]\norigin = [-0.5, 1, -2]\nedge_u = [1, 0, 0]\nedge_v = [0, 1, 0]\n"
    } else {
        ""
    };
    twopass_scene::load_toml(
        &format!(
            "version = 1\n\
             [camera]\nposition = [0, 1.5, 1.5]\nlook_at = [0, 1, -2]\nfov_y = 60\nresolution = [32, 24]\n\
             [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
             {walls}[sky]\nkind = \"uniform\"\nradiance = 1\n{portal}"
        ),
        std::path::Path::new("room.toml"),
    )
    .unwrap()
    .0
}

/// The projected solid angle (sr) of the polygon `corners` seen from `x` by a surface of
/// normal `n`: Lambert's formula, the sum over the edges of the angle each subtends times the
/// cosine between `n` and the normal of the plane through `x` and the edge, over 2.
fn projected_solid_angle(x: DVec3, n: DVec3, corners: &[DVec3]) -> f64 {
    let k = corners.len();
    let sum: f64 = (0..k)
        .map(|i| {
            let a = (corners[i] - x).normalize();
            let b = (corners[(i + 1) % k] - x).normalize();
            a.dot(b).clamp(-1.0, 1.0).acos() * a.cross(b).normalize().dot(n)
        })
        .sum();
    (sum / 2.0).abs()
}

/// `n` estimates of the sky's irradiance (red channel) at the floor's centre, one sample of
/// the dome each, keyed 0, 1, ...
fn floor_estimates(scene: &Scene, n: u64) -> Vec<DVec3> {
    let hit = scene
        .intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y))
        .expect("the floor");
    assert!(hit.point.position.y.abs() < 1e-6);
    let mut rays = 0;
    (0..n)
        .map(|key| {
            scene
                .sky_irradiance(&hit.point, Vec3::Y, key, 1, &mut rays)
                .as_dvec3()
        })
        .collect()
}

#[test]
fn portals_give_the_same_light_through_a_window_with_far_less_variance() {
    let window = [
        DVec3::new(-0.5, 1.0, -2.0),
        DVec3::new(0.5, 1.0, -2.0),
        DVec3::new(0.5, 2.0, -2.0),
        DVec3::new(-0.5, 2.0, -2.0),
    ];
    // Radiance 1 through the window only.
    let exact = projected_solid_angle(DVec3::ZERO, DVec3::Y, &window);
    let n = 40_000;
    let mut variances = Vec::new();
    for portal in [false, true] {
        let estimates = floor_estimates(&window_room(portal), n);
        let (mean, error) = mean_and_error(&estimates);
        let variance = error.x * error.x * n as f64;
        eprintln!(
            "portal {portal}: {} +- {} (exact {exact}), variance of one sample {variance}",
            mean.x, error.x
        );
        assert!(
            (mean.x - exact).abs() < 5.0 * error.x,
            "portal {portal}: {} +- {} vs {exact}",
            mean.x,
            error.x
        );
        variances.push(variance);
    }
    let ratio = variances[0] / variances[1];
    eprintln!("variance ratio without / with the portal: {ratio}");
    assert!(ratio > 10.0, "variance ratio {ratio}");
}

/// [`crate::lamps::BEAM_WALL`] (a grey wall facing a perfect mirror tilted 45 degrees, the
/// mirror turning light that falls straight down toward the wall) without its lamp, under `sky`.
fn beam_wall_under(sky: &str) -> Scene {
    let text = crate::lamps::BEAM_WALL;
    let without_lamp = &text[..text.find("[[light]]").unwrap()];
    twopass_scene::load_toml(
        &format!("{without_lamp}{sky}"),
        std::path::Path::new("mirror.toml"),
    )
    .unwrap()
    .0
}

/// Solves `scene` (with the specular transfer, or with mirrors as absorbers) and returns, per
/// vertex of the wall (object 0), its position and radiosity (W/m^2, red channel), and the
/// power the wall reflects (W, red).
fn wall_light(scene: &Scene, method: Method, specular: bool) -> (Vec<(Vec3, f64)>, f64) {
    let mut options = crate::lamps::options(method, 0.1, 1e-6);
    if !specular {
        options.specular = None;
    }
    let mut solver = Solver::new(scene, options).unwrap();
    solver.run(|_| ControlFlow::Continue(()));
    let solution = solver.solution();
    let b = solution.vertex_radiosity();
    let mesh = solution.mesh();
    let on_wall = |n: &u32| mesh.vertices[mesh.nodes[*n as usize].vertices[0] as usize].object == 0;
    let reflected = mesh
        .leaves()
        .filter(on_wall)
        .map(|n| {
            let node = &mesh.nodes[n as usize];
            let sum: f64 = node
                .vertices
                .iter()
                .map(|&v| f64::from(b[v as usize].x))
                .sum();
            sum / 3.0 * f64::from(node.area)
        })
        .sum();
    let vertices = mesh
        .vertices
        .iter()
        .enumerate()
        .filter(|(_, v)| v.object == 0)
        .map(|(i, v)| (v.position, f64::from(b[i].x)))
        .collect();
    (vertices, reflected)
}

/// Under a uniform sky of radiance L the wall sees the sky in every direction of its
/// hemisphere, directly or through the mirror (which turns the wall's view of it straight up,
/// to the open sky): E = pi L at every point, B = rho pi L. Shadow rays stop at the mirror, so
/// the light through it is the specular transfer's: rho L times the wall's projected solid
/// angle of the mirror integrated over the wall (Lambert's polygon formula, midpoint rule),
/// about 2.3 % of the wall's light, 4 % at its centre.
#[test]
fn the_sky_through_a_mirror_lights_a_wall_as_the_open_sky_would() {
    let s = beam_wall_under("[sky]\nkind = \"uniform\"\nradiance = 1\n");
    let want = RHO * std::f64::consts::PI;
    // The mirror's corners, and the wall (x in [-2, 2], y in [-1, 1] at z = 2, facing -z).
    let o = DVec3::new(-0.5, -0.25, 0.25);
    let (u, v) = (DVec3::X, DVec3::new(0.0, 0.5, -0.5));
    let mirror = [o, o + u, o + u + v, o + v];
    let (nx, ny) = (400, 200);
    let cell = 4.0 / f64::from(nx) * 2.0 / f64::from(ny);
    let mut through = 0.0;
    for i in 0..nx {
        for j in 0..ny {
            let x = DVec3::new(
                -2.0 + 4.0 * (f64::from(i) + 0.5) / f64::from(nx),
                -1.0 + 2.0 * (f64::from(j) + 0.5) / f64::from(ny),
                2.0,
            );
            through += projected_solid_angle(x, -DVec3::Z, &mirror) * cell;
        }
    }
    let through = RHO * through;
    for method in METHODS {
        let (vertices, reflected) = wall_light(&s, method, true);
        let (_, absorbed) = wall_light(&s, method, false);
        // What the wall's own light sends back through the mirror is far below the tolerance:
        // after the mirror a ray goes (x, -z, -y), up and over the wall.
        let gained = reflected - absorbed;
        eprintln!(
            "{method:?}: the wall reflects {reflected} W, {gained} W through the mirror \
             (want {through})"
        );
        assert!(
            (gained / through - 1.0).abs() < 0.02,
            "{method:?}: {gained} W through the mirror vs {through}"
        );
        if method == Method::Hierarchical {
            // Its leaves are split where links or lamps need it, not where the sky's light
            // varies or deposits land: only the light through the mirror is checked.
            continue;
        }
        let power = want * 8.0;
        assert!(
            (reflected / power - 1.0).abs() < 0.005,
            "{method:?}: {reflected} W vs {power}"
        );
        let centre: Vec<f64> = vertices
            .iter()
            .filter(|(p, _)| p.x.abs() < 0.5 && p.y.abs() < 0.5)
            .map(|&(_, b)| b)
            .collect();
        let mean = centre.iter().sum::<f64>() / centre.len() as f64;
        eprintln!(
            "{method:?}: {} centre vertices, mean B {mean} (want {want})",
            centre.len()
        );
        assert!(centre.len() >= 10, "{}", centre.len());
        assert!(
            (mean / want - 1.0).abs() < 0.01,
            "{method:?}: {mean} vs {want}"
        );
    }
}

/// The sun straight overhead, turned by the mirror onto the wall: the mirror's image on the
/// wall (|x| < 0.5, |y| < 0.25) receives the sun's whole irradiance L_sun Omega_sun (a
/// mirror keeps a parallel beam's cross-section) on top of the dome's light, which varies
/// smoothly across the beam's edge: the mean inside minus the mean in a band just outside is
/// rho E_sun, within the dome's change over the band (about 1 % of the sun's).
#[test]
fn the_sun_through_a_mirror_lights_the_mirrors_image_on_a_wall() {
    let s = beam_wall_under(
        "[sky]\nkind = \"daylight\"\nturbidity = 3\nsun_direction = [0, 1, 0]\nscale = 0.001\n",
    );
    let sun = s.sky.as_ref().unwrap().sun.unwrap();
    let e_sun = f64::from(sun.radiance.x * sun.solid_angle());
    let (vertices, _) = wall_light(&s, Method::Progressive, true);
    let (mut inside, mut band) = (Vec::new(), Vec::new());
    for &(p, b) in &vertices {
        match crate::lamps::in_mirrored_beam(p, 0.15) {
            Some(true) => inside.push(b),
            Some(false) if p.x.abs() < 0.95 && p.y.abs() < 0.7 => band.push(b),
            _ => {}
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let step = mean(&inside) - mean(&band);
    eprintln!(
        "{} inside, {} in the band: step {step} (want {})",
        inside.len(),
        band.len(),
        RHO * e_sun
    );
    assert!(inside.len() >= 10 && band.len() >= 10);
    assert!(
        (step / (RHO * e_sun) - 1.0).abs() < 0.03,
        "{step} vs {}",
        RHO * e_sun
    );
}
