//! Lamps in both radiosity solvers against closed forms: the solution at the element vertices
//! under a point lamp is rho I cos(theta) / r^2, under a spot it follows glTF's falloff, under
//! a directional lamp it is rho E cos(theta) outside a black blocker's shadow and 0 inside; a
//! point lamp of power P in a closed box delivers P, all absorbed at convergence.

use std::ops::ControlFlow;
use std::path::Path;

use glam::{DVec3, Vec3};
use twopass_radiosity::{Method, Options, Solver, Stop};
use twopass_scene::{Scene, load_toml};

/// The plane's reflectance in [`plane_under`].
pub(crate) const RHO: f64 = 0.5;

/// glTF's spot falloff, written from the `KHR_lights_punctual` specification: with the
/// cosines of the cone's half angles, `t = clamp((cd - cos_outer) / max(0.001, cos_inner -
/// cos_outer), 0, 1)` and the intensity scaled by `t^2`.
pub(crate) fn gltf_falloff(cd: f64, inner_deg: f64, outer_deg: f64) -> f64 {
    let (ci, co) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
    let scale = 1.0 / (ci - co).max(0.001);
    let t = (cd * scale - co * scale).clamp(0.0, 1.0);
    t * t
}

/// Whether point `p` of the plane lies in the blocker's shadow under a directional lamp
/// travelling along (1, -2, 0): the blocker's square moved by +0.25 in x (x in [0, 0.5],
/// |z| < 0.25); `None` within `margin` of the shadow's edges.
pub(crate) fn in_blocker_shadow(p: Vec3, margin: f64) -> Option<bool> {
    let p = p.as_dvec3();
    let (dx, dz) = ((p.x - 0.25).abs() - 0.25, p.z.abs() - 0.25);
    if dx.abs() < margin || dz.abs() < margin {
        return None;
    }
    Some(dx < 0.0 && dz < 0.0)
}

const METHODS: [Method; 2] = [Method::Progressive, Method::Hierarchical];

fn scene(text: &str) -> Scene {
    load_toml(text, Path::new("lamps.toml")).unwrap().0
}

/// A 4 x 4 grey plane at y = 0 (reflectance [`RHO`]) seen from above by a 32 x 32 camera,
/// lit by the `[[light]]` table `light`; with `blocker`, a black square 0.5 wide at y = 0.5
/// over the origin, facing down.
pub(crate) fn plane_under(light: &str, blocker: bool) -> Scene {
    let blocker = if blocker {
        "[[object]]\nname = \"blocker\"\nmaterial = \"black\"\n\
         shape = { type = \"quad\", origin = [-0.25, 0.5, -0.25], edge_u = [0.5, 0, 0], edge_v = [0, 0, 0.5] }\n"
    } else {
        ""
    };
    scene(&format!(
        "version = 1\n\
         [camera]\nposition = [0, 3, 2.5]\nlook_at = [0, 0, 0]\nfov_y = 50\nresolution = [32, 32]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = {RHO}\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[object]]\nname = \"plane\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }}\n\
         {blocker}{light}"
    ))
}

pub(crate) fn options(method: Method, element: f32, unshot: f64) -> Options {
    Options {
        method,
        element_size: Some(element),
        stop: Stop {
            unshot_fraction: unshot,
            ..Stop::default()
        },
        ..Options::default()
    }
}

/// Solves `scene` with each method and checks every vertex of the plane (object 0) against
/// `expected` (radiosity B, W/m^2, at a position; `None` to skip it): nothing else lights the
/// plane (it sees only the black blocker), so each vertex's value is its exact lamp
/// irradiance times rho, within 1e-4 of the larger of it and `peak` (f32 rounding, and the
/// receiving point a hair, 1e-5 of the way to its triangle's centre, inside the vertex, where
/// a spot's blend changes E steeply). Returns the vertices checked per method.
fn vertices_match(
    scene: &Scene,
    peak: f64,
    mut expected: impl FnMut(Vec3) -> Option<f64>,
) -> Vec<usize> {
    METHODS
        .iter()
        .map(|&method| {
            let mut solver = Solver::new(scene, options(method, 0.25, 1e-6)).unwrap();
            solver.run(|_| ControlFlow::Continue(()));
            let solution = solver.solution();
            let b = solution.vertex_radiosity();
            let mut n = 0;
            for (v, vert) in solution.mesh().vertices.iter().enumerate() {
                if vert.object != 0 {
                    continue;
                }
                let Some(e) = expected(vert.position) else {
                    continue;
                };
                let got = f64::from(b[v].x);
                if e > 0.0 {
                    assert!(
                        (got - e).abs() < 1e-4 * e.max(peak),
                        "{method:?}: vertex {v} at {}: {got} vs {e}",
                        vert.position
                    );
                } else {
                    assert!(
                        got.abs() < 1e-9,
                        "{method:?}: vertex {v}: {got} in the dark"
                    );
                }
                n += 1;
            }
            n
        })
        .collect()
}

#[test]
fn the_solution_under_a_point_lamp_is_rho_i_cos_over_r_squared() {
    let (i, h) = (3.0, 1.0);
    let s = plane_under(
        &format!("[[light]]\nkind = \"point\"\nposition = [0, {h}, 0]\nintensity = {i}\n"),
        false,
    );
    let n = vertices_match(&s, RHO * i / (h * h), |p| {
        let p = p.as_dvec3();
        let r2 = p.x * p.x + h * h + p.z * p.z;
        Some(RHO * i * h / (r2 * r2.sqrt()))
    });
    assert!(n.iter().all(|&n| n > 200), "{n:?} vertices");
}

#[test]
fn the_solution_under_a_spot_follows_the_gltf_falloff() {
    let (i, h, inner, outer) = (5.0, 1.0, 20.0f64, 40.0f64);
    let s = plane_under(
        &format!(
            "[[light]]\nkind = \"spot\"\nposition = [0, {h}, 0]\nlook_at = [0, 0, 0]\n\
             intensity = {i}\ninner_angle = {inner}\nouter_angle = {outer}\n"
        ),
        false,
    );
    let mut fading = 0;
    let n = vertices_match(&s, RHO * i / (h * h), |p| {
        let p = p.as_dvec3();
        let r = (p.x * p.x + h * h + p.z * p.z).sqrt();
        let f = gltf_falloff(h / r, inner, outer);
        fading += usize::from(f > 0.0 && f < 1.0);
        Some(RHO * i * f * (h / r) / (r * r))
    });
    assert!(
        fading > 20 && n.iter().all(|&n| n > 200),
        "{n:?}, {fading} in the blend"
    );
}

#[test]
fn the_solution_under_a_directional_lamp_is_rho_e_cos_outside_a_sharp_shadow() {
    let e = 2.0;
    let s = plane_under(
        &format!("[[light]]\nkind = \"directional\"\ndirection = [1, -2, 0]\nirradiance = {e}\n"),
        true,
    );
    // Vertices on the shadow's edges (the element mesh has some there) are skipped.
    let cos = 2.0 / 5f64.sqrt();
    let mut dark = 0;
    let n = vertices_match(&s, RHO * e * cos, |p| {
        let inside = in_blocker_shadow(p, 1e-3)?;
        dark += usize::from(inside);
        Some(if inside { 0.0 } else { RHO * e * cos })
    });
    // The hierarchical solver refines only where the lamp's light varies: about the shadow.
    assert!(dark > 0 && n[0] > 200 && n[1] > 50, "{n:?}, {dark} dark");
}

#[test]
fn a_point_lamp_of_power_p_in_a_closed_box_has_p_absorbed() {
    // 4 pi I = P, the lamp off the centre so that no symmetry helps.
    let power = 10.0;
    let faces: String = crate::radiosity::CUBE_FACES
        .iter()
        .enumerate()
        .map(|(k, (o, u, v))| {
            format!(
                "[[object]]\nname = \"face{k}\"\nmaterial = \"w\"\n\
                 shape = {{ type = \"quad\", origin = {o:?}, edge_u = {u:?}, edge_v = {v:?} }}\n"
            )
        })
        .collect();
    let s = scene(&format!(
        "version = 1\n[camera]\nposition = [0.5, 0.5, 0.1]\nlook_at = [0.5, 0.5, 1]\nfov_y = 60\n\
         [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = {RHO}\n{faces}\
         [[light]]\nkind = \"point\"\nposition = [0.4, 0.55, 0.6]\npower = {power}\n"
    ));
    assert!(s.emitters.is_empty());
    let expected = DVec3::splat(power);
    // Absorbed over emitted after a solve to an unshot fraction of 1e-6 (per method, the
    // hierarchical solver at its default link tolerance and a tenth of it).
    let absorbed = |method: Method, link_tolerance: Option<f64>| {
        let mut o = options(method, 1.0 / 16.0, 1e-6);
        if let Some(t) = link_tolerance {
            o.hierarchical.link_tolerance = t;
        }
        let mut solver = Solver::new(&s, o).unwrap();
        solver.run(|_| ControlFlow::Continue(()));
        let p = solver.progress();
        eprintln!("{method:?} {link_tolerance:?}: {:?}", p.energy);
        assert!((p.energy.emitted - expected).abs().max_element() < 1e-9 * power);
        assert!(p.worst_imbalance < 1e-6, "{}", p.worst_imbalance);
        p.energy.absorbed.x / power
    };
    // At convergence everything the lamp sent is absorbed, up to the mesh's discretization:
    // the elements' linear interpolation of the lamp's irradiance and the vertex form factors
    // (a closed cube's sum to 1 within 0.5 %), which the solvers report as escaped. The
    // closed room lit by an area emitter holds the hierarchical solver to the same 0.5 %
    // (`hierarchical::a_closed_room_loses_no_light`); its link discretization, here about
    // 1 % at the default tolerance, shrinks with the tolerance, so it is held to 0.5 % at a
    // tenth of it (and must improve on the default).
    let progressive = absorbed(Method::Progressive, None);
    assert!(
        (progressive - 1.0).abs() < 5e-3,
        "progressive: {progressive}"
    );
    let coarse = absorbed(Method::Hierarchical, None);
    let fine = absorbed(Method::Hierarchical, Some(2e-6));
    assert!((fine - 1.0).abs() < 5e-3, "hierarchical: {fine}");
    assert!(
        (fine - 1.0).abs() < (coarse - 1.0).abs(),
        "hierarchical {coarse} -> {fine} with a finer link tolerance"
    );
}

#[test]
fn lamp_lit_solutions_are_the_same_on_one_and_two_threads() {
    let s = plane_under(
        "[[light]]\nkind = \"spot\"\nposition = [0.2, 1, 0]\nlook_at = [0, 0, 0]\nintensity = 5\nouter_angle = 50\n\
         [[light]]\nkind = \"directional\"\ndirection = [1, -2, 0.5]\nirradiance = 1\n",
        true,
    );
    for method in METHODS {
        let solve = || {
            let mut solver = Solver::new(&s, options(method, 0.25, 1e-4)).unwrap();
            solver.run(|_| ControlFlow::Continue(()));
            solver.solution().vertex_radiosity()
        };
        let one = crate::on_threads(1, solve);
        let two = crate::on_threads(2, solve);
        assert!(one == two, "{method:?}");
    }
}

/// A directional lamp (irradiance [`BEAM_E`], straight down) over a mirror tilted 45 degrees
/// (1 x 0.707, centred at the origin, facing (0, 1, 1)) that turns the beam toward +z onto a
/// grey wall at z = 2 facing it: the wall gets no direct light (it is parallel to the beam)
/// and, through the mirror, the beam's whole irradiance E (a mirror keeps a parallel beam's
/// cross-section) over the mirror's image, |x| < 0.5 and |y| < 0.25, and nothing elsewhere
/// but the wall's own light that the mirror turns back to it.
pub(crate) const BEAM_WALL: &str = "version = 1\n\
    [camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 2]\nfov_y = 50\nresolution = [16, 16]\n\
    [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
    [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = 1\n\
    [[object]]\nname = \"wall\"\nmaterial = \"grey\"\n\
    shape = { type = \"quad\", origin = [-2, -1, 2], edge_u = [0, 2, 0], edge_v = [4, 0, 0] }\n\
    [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
    shape = { type = \"quad\", origin = [-0.5, -0.25, 0.25], edge_u = [1, 0, 0], edge_v = [0, 0.5, -0.5] }\n\
    [[light]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 2\n";

/// The irradiance of [`BEAM_WALL`]'s lamp, W/m^2.
pub(crate) const BEAM_E: f64 = 2.0;

/// Where a point of [`BEAM_WALL`]'s wall lies: `Some(true)` in the mirrored beam, `Some(false)`
/// out of it, `None` within `margin` of its edges.
pub(crate) fn in_mirrored_beam(p: Vec3, margin: f64) -> Option<bool> {
    let p = p.as_dvec3();
    let (dx, dy) = (p.x.abs() - 0.5, p.y.abs() - 0.25);
    if dx.abs() < margin || dy.abs() < margin {
        return None;
    }
    Some(dx < 0.0 && dy < 0.0)
}

/// Both solvers carry the beam's power to the wall; progressive refinement shows it on the
/// vertices inside the mirror's image and nowhere else.
#[test]
fn a_directional_lamp_through_a_mirror_lights_the_wall_with_its_beam() {
    let s = scene(BEAM_WALL);
    for method in METHODS {
        let mut solver = Solver::new(&s, options(method, 0.1, 1e-6)).unwrap();
        solver.run(|_| ControlFlow::Continue(()));
        let solution = solver.solution();
        let b = solution.vertex_radiosity();
        // The power the wall reflects: rho times the beam's, E times the mirror's image's
        // 0.5 m^2 (what the wall's own light sends back through the mirror is far below the
        // tolerance), whatever the elements the deposits are spread over.
        let mesh = solution.mesh();
        let (reflected, _) = crate::element_integral(
            mesh,
            |node| mesh.vertices[node.vertices[0] as usize].object == 0,
            |v| f64::from(b[v as usize].x),
        );
        let want = RHO * BEAM_E * 0.5;
        assert!(
            (reflected / want - 1.0).abs() < 0.01,
            "{method:?}: {reflected} W vs {want}"
        );
        if method == Method::Hierarchical {
            // Its leaves are split where links or lamps need it, not where deposits land, so
            // the beam's edges spread over its leaves: only the power is checked.
            continue;
        }
        let (mut lit, mut dark) = (Vec::new(), 0);
        for (v, vert) in solution.mesh().vertices.iter().enumerate() {
            if vert.object != 0 {
                continue;
            }
            // The deposits are splatted over the elements around a vertex (0.1 here).
            match in_mirrored_beam(vert.position, 0.15) {
                Some(true) => lit.push(f64::from(b[v].x)),
                // Out of the beam only the wall's own light comes back through the mirror
                // (D S D, left out of the closed form), seen through a small mirror at
                // grazing angles: far below a thousandth of the beam's.
                Some(false) => {
                    let x = f64::from(b[v].x);
                    assert!(
                        x.abs() < 1e-3 * RHO * BEAM_E,
                        "{method:?}: {x} out of the beam"
                    );
                    dark += 1;
                }
                None => {}
            }
        }
        let mean = lit.iter().sum::<f64>() / lit.len() as f64;
        let want = RHO * BEAM_E;
        eprintln!(
            "{method:?}: {} lit vertices, mean {mean} (want {want}), {dark} dark",
            lit.len()
        );
        assert!(
            lit.len() >= 10 && dark > 100,
            "{method:?}: {} lit, {dark} dark",
            lit.len()
        );
        // About 1e6 rays land on the beam's 0.5 m^2: the mean of the lit vertices has well
        // under 1 % of noise.
        assert!(
            (mean / want - 1.0).abs() < 0.01,
            "{method:?}: {mean} vs {want}"
        );
        for x in &lit {
            assert!(
                (x / want - 1.0).abs() < 0.1,
                "{method:?}: a lit vertex at {x}"
            );
        }
    }
}
