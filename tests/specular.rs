//! The specular transfer of the radiosity pass (light through mirrors and glass, L S+ D and
//! D S+ D) against closed forms: the irradiance through a mirror equals the mirrored emitter's
//! times the reflectance, a furnace with a perfect mirror for one wall stays uniform, the
//! all-diffuse Cornell box is untouched bit for bit, and the power balances on the spheres.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;
use twopass_radiosity::form_factor::point_to_polygon;
use twopass_radiosity::specular::decide;
use twopass_radiosity::{Options, ProgressiveSolver, SpecularOptions, Stop};
use twopass_scene::{Scene, load, load_toml};

use crate::radiosity::{CUBE_FACES, cornell_options, run};
use crate::{on_threads, scene_path};

/// The radiosity tests' Cornell settings (150 mm patches, 60 mm elements, one adaptive
/// round) to the unshot fraction `unshot`, with the specular transfer `specular`.
fn coarse(specular: Option<SpecularOptions>, unshot: f64) -> Options {
    Options {
        specular,
        ..cornell_options(unshot)
    }
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|b| b.to_array().map(f64::to_bits)).collect()
}

#[test]
fn all_diffuse_box_is_untouched_bit_for_bit() {
    let (s, _) = load(scene_path("cornell-box.toml")).unwrap();
    let (needed, why) = decide(&s);
    assert!(!needed, "{why}");
    assert!(why.contains("no mirror, conductor or dielectric"), "{why}");
    let options = |specular| coarse(specular, 1e-3);
    let solve = |specular| {
        let mut solver = ProgressiveSolver::new(&s, options(specular)).unwrap();
        run(&mut solver);
        assert_eq!(solver.specular_transfer(), None);
        let p = solver.progress();
        (bits(&solver.vertex_radiosity()), p.rays, p.shots, p.energy)
    };
    let with = solve(Some(SpecularOptions::default()));
    let without = solve(None);
    assert_eq!(with.0, without.0, "vertex radiosity differs");
    assert_eq!(
        (with.1, with.2),
        (without.1, without.2),
        "rays or shots differ"
    );
    assert_eq!(with.3, without.3);
}

/// An open scene: a mirror of per-channel reflectance `r` in the plane y = 0 (x in [-1.2, 0],
/// z in [-0.4, 0.4], facing up), a small emitter (L_e = 1, reflecting nothing) and a diffuse
/// receiver (rho = 0.5) side by side in the plane y = 1, both facing down. The receiver sees
/// the emitter only through the mirror (they are coplanar), never itself (its own image lies
/// beyond the mirror's edge), and what it reflects can only escape or fall on the black
/// emitter: its radiosity is rho times the irradiance through the mirror, nothing else.
fn mirror_scene(r: [f64; 3]) -> Scene {
    let camera = "position = [0, 3, 0.01]\nlook_at = [0, 0, 0]\nfov_y = 60";
    load_toml(
        &mirror_text(camera, r, false, "black"),
        Path::new("mirror.toml"),
    )
    .unwrap()
    .0
}

/// The mirror scenes' TOML: a mirror of per-channel reflectance `r` in the plane y = 0 (x in
/// [-1.2, 0], z in [-0.4, 0.4]) facing up (or down, `turned`), a 0.2 x 0.2 emitter (L_e = 1)
/// of material `light` (`black` or `grey`) and a grey receiver (rho = 0.5, 0.4 x 0.4) side by
/// side in the plane y = 1, both facing down; `camera` is the body of the `[camera]` table.
pub fn mirror_text(camera: &str, r: [f64; 3], turned: bool, light: &str) -> String {
    let (u, v) = if turned {
        ("[1.2, 0, 0]", "[0, 0, 0.8]")
    } else {
        ("[0, 0, 0.8]", "[1.2, 0, 0]")
    };
    format!(
        "version = 1\n[camera]\n{camera}\n\
         [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = {r:?}\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
         shape = {{ type = \"quad\", origin = [-1.2, 0, -0.4], edge_u = {u}, edge_v = {v} }}\n\
         [[object]]\nname = \"light\"\nmaterial = \"{light}\"\nemission = 1\n\
         shape = {{ type = \"quad\", origin = [-1.6, 1, -0.1], edge_u = [0.2, 0, 0], edge_v = [0, 0, 0.2] }}\n\
         [[object]]\nname = \"receiver\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"quad\", origin = [0.3, 1, -0.2], edge_u = [0.4, 0, 0], edge_v = [0, 0, 0.4] }}\n"
    )
}

/// Irradiance at `x` on the receiver (normal -y) from the emitter's mirror image (the emitter
/// reflected in y = 0: the plane y = -1, facing up), per unit reflectance: pi L_e F, with the
/// exact point-to-polygon form factor (shared with the light tracing tests, whose mirror scene
/// has the same mirror and emitter).
pub fn through_mirror(x: DVec3) -> f64 {
    let image = [
        DVec3::new(-1.6, -1.0, -0.1),
        DVec3::new(-1.4, -1.0, -0.1),
        DVec3::new(-1.4, -1.0, 0.1),
        DVec3::new(-1.6, -1.0, 0.1),
    ];
    PI * point_to_polygon(x, -DVec3::Y, &image, Some(DVec3::Y))
}

#[test]
fn irradiance_through_a_mirror_is_the_mirrored_emitters_times_the_reflectance() {
    let r = [0.9, 0.6, 0.3];
    let s = mirror_scene(r);
    assert!(decide(&s).0, "{}", decide(&s).1);
    let options = Options {
        patch_size: Some(0.3),
        element_size: Some(0.1),
        adaptive: None,
        stop: Stop {
            unshot_fraction: 1e-6,
            ..Stop::default()
        },
        specular: Some(SpecularOptions {
            rays: 1 << 22,
            ..SpecularOptions::default()
        }),
        ..Options::default()
    };
    let mut solver = ProgressiveSolver::new(&s, options.clone()).unwrap();
    run(&mut solver);
    let (_, deposits) = solver.specular_transfer().expect("the transfer runs");
    let mesh = solver.mesh().clone();
    let b = solver.vertex_radiosity();
    let receiver = s.objects.iter().position(|o| o.name == "receiver").unwrap() as u32;
    // Per receiver vertex, what the splat estimates: the irradiance averaged with the vertex's
    // hat function (its barycentric weight in each element around it) over the area it
    // stands for, by a 66-point barycentric rule per element.
    let (mut area, mut weighted) = (vec![0.0; b.len()], vec![0.0; b.len()]);
    let m = 10;
    for leaf in mesh.leaves() {
        let node = &mesh.nodes[leaf as usize];
        if mesh.vertices[node.vertices[0] as usize].object != receiver {
            continue;
        }
        let p = mesh.corners(leaf);
        let mut sum = [0.0; 3];
        let mut count = 0.0;
        for i in 0..=m {
            for j in 0..=m - i {
                let w = [i as f64, j as f64, (m - i - j) as f64].map(|x| x / m as f64);
                let x = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
                let e = through_mirror(x);
                for (s, w) in sum.iter_mut().zip(w) {
                    *s += w * e;
                }
                count += 1.0;
            }
        }
        let a = f64::from(node.area);
        for (&v, s) in node.vertices.iter().zip(sum) {
            weighted[v as usize] += a * s / count;
            area[v as usize] += a / 3.0;
        }
    }
    let (mut power, mut expected_power, mut vertices) = (DVec3::ZERO, 0.0, 0);
    // Poisson bound on the estimate's noise: about 1.5 % of the rays that leave the emitter
    // toward the mirror land on the receiver (its solid angle seen from the emitter's image,
    // 0.014 sr, over the cone the mirror's bounding sphere subtends, 0.95 sr), a vertex gets
    // the share of its area; five standard deviations of a count n are 5 / sqrt(n). The
    // stratified rays do better than Poisson; the bound must hold regardless.
    let landed = deposits as f64;
    let receiver_area = 0.16;
    for v in 0..b.len() {
        if area[v] == 0.0 {
            continue;
        }
        vertices += 1;
        let expected = weighted[v] / area[v];
        let tolerance = 5.0 / (landed * area[v] / receiver_area).sqrt();
        for c in 0..3 {
            let measured = b[v][c] / 0.5;
            let want = expected * r[c];
            assert!(
                (measured - want).abs() < tolerance * want,
                "vertex {v} channel {c}: irradiance {measured} vs {want} through the mirror \
                 (tolerance {tolerance})"
            );
        }
        power += b[v] / 0.5 * area[v];
        expected_power += weighted[v];
    }
    assert!(vertices >= 25, "{vertices} receiver vertices");
    // The power on the whole receiver: every deposit counted once.
    let tolerance = 5.0 / landed.sqrt();
    for c in 0..3 {
        let want = expected_power * r[c];
        assert!(
            (power[c] - want).abs() < tolerance * want,
            "receiver power {} vs {want} (tolerance {tolerance})",
            power[c]
        );
    }
    // Without the transfer the receiver gets nothing at all: the mirror is an absorber.
    let mut dark = ProgressiveSolver::new(
        &s,
        Options {
            specular: None,
            ..options
        },
    )
    .unwrap();
    run(&mut dark);
    let b = dark.vertex_radiosity();
    assert!((0..b.len()).all(|v| area[v] == 0.0 || b[v] == DVec3::ZERO));
}

/// A closed unit cube whose face 0 (z = 0) is a perfect mirror and whose five other faces emit
/// L_e = 1 and reflect `rho`, all facing in.
fn mirror_furnace(rho: f64) -> Scene {
    let mut text = format!(
        "version = 1\n[camera]\nposition = [0.5, 0.5, 0.1]\nlook_at = [0.5, 0.5, 1]\nfov_y = 60\n\
         [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = {rho}\n\
         [[material]]\nname = \"m\"\ntype = \"mirror\"\nreflectance = 1\n"
    );
    for (i, (o, u, v)) in CUBE_FACES.iter().enumerate() {
        let (material, emission) = if i == 0 {
            ("m", "")
        } else {
            ("w", "emission = 1\n")
        };
        text += &format!(
            "[[object]]\nname = \"face{i}\"\nmaterial = \"{material}\"\n{emission}\
             shape = {{ type = \"quad\", origin = {o:?}, edge_u = {u:?}, edge_v = {v:?} }}\n"
        );
    }
    load_toml(&text, Path::new("mirror-furnace.toml"))
        .unwrap()
        .0
}

/// The mirror furnace's solve: to an unshot fraction of 1e-5, with the transfer `specular`.
fn furnace_options(specular: Option<SpecularOptions>) -> Options {
    Options {
        stop: Stop {
            unshot_fraction: 1e-5,
            ..Stop::default()
        },
        specular,
        ..Options::default()
    }
}

#[test]
fn furnace_with_a_perfect_mirror_wall_stays_uniform() {
    // In a closed room whose diffuse walls all emit E and reflect rho, a lossless mirror wall
    // sends every diffuse point the radiance it would see from a diffuse wall in its place, so
    // the radiosity is E / (1 - rho) everywhere, as in the all-diffuse furnace. Without the
    // transfer the mirror absorbs what falls on it and the walls are darker.
    let rho = 0.5;
    let s = mirror_furnace(rho);
    let expected = PI / (1.0 - rho);
    // Per wall: the mean radiosity over its area (each vertex standing for a third of the
    // elements around it, as in the solver's power bookkeeping), and the worst vertex.
    let solve = |specular| {
        let options = Options {
            patch_size: Some(1.0),
            element_size: Some(0.25),
            adaptive: None,
            ..furnace_options(specular)
        };
        let mut solver = ProgressiveSolver::new(&s, options).unwrap();
        run(&mut solver);
        let mesh = solver.mesh();
        let b = solver.vertex_radiosity();
        let (mut sum, mut area) = ([0.0; 6], [0.0; 6]);
        for leaf in mesh.leaves() {
            let node = &mesh.nodes[leaf as usize];
            for &v in &node.vertices {
                let o = mesh.vertices[v as usize].object as usize;
                sum[o] += b[v as usize].x * f64::from(node.area) / 3.0;
                area[o] += f64::from(node.area) / 3.0;
            }
        }
        let worst_wall = (1..6)
            .map(|o| (sum[o] / area[o] - expected).abs() / expected)
            .fold(0.0, f64::max);
        let worst_vertex = b
            .iter()
            .flat_map(|b| b.to_array())
            .map(|x| (x - expected).abs() / expected)
            .fold(0.0, f64::max);
        (worst_wall, worst_vertex, solver.progress().energy)
    };
    let (wall, vertex, e) = solve(Some(SpecularOptions {
        rays: 1 << 21,
        ..SpecularOptions::default()
    }));
    let (dark_wall, dark_vertex, _) = solve(None);
    // The light through the mirror is about a fifth of what a wall receives (the form factor
    // of a face to the opposite one is 0.2), carried by more than 10^5 deposits per wall: the
    // walls' means are within 5 / sqrt(10^5) of that fifth, under 1 % of the radiosity.
    assert!(
        wall < 1e-2,
        "worst wall mean off by {wall} (without the transfer {dark_wall})"
    );
    assert!(dark_wall > 5e-2, "the mirror as an absorber: {dark_wall}");
    // Vertex by vertex the deposits are a mean over the elements around the vertex while the
    // form factors are exact at it: along the edges that touch the mirror, where the light
    // through it changes fastest, the two differ by a few per cent at this element size
    // (ARCHITECTURE.md, "Specular transfer"). Still far closer than the mirror as an absorber.
    assert!(
        vertex < 0.05 && vertex < dark_vertex / 2.0,
        "worst vertex off by {vertex} (without the transfer {dark_vertex})"
    );
    // Nothing escapes a closed room and a perfect mirror absorbs nothing: what the walls emit
    // they absorb, up to the vertex rule's discretization of the form factors (as in the
    // all-diffuse furnace) and the rays still in the glass after the bounce limit (none here).
    assert!((e.escaped / e.emitted).abs().max_element() < 1e-3, "{e:?}");
}

#[test]
fn spheres_balance_power_and_solve_alike_on_one_or_two_threads() {
    let (s, _) = load(scene_path("cornell-spheres.toml")).unwrap();
    let (needed, why) = decide(&s);
    assert!(
        needed && why.contains("mirror-sphere, glass-sphere"),
        "{why}"
    );
    let options = Options {
        patch_size: Some(150.0),
        element_size: Some(80.0),
        adaptive: None,
        stop: Stop {
            unshot_fraction: 1e-2,
            ..Stop::default()
        },
        specular: Some(SpecularOptions {
            rays: 1 << 16,
            ..SpecularOptions::default()
        }),
        ..Options::default()
    };
    let solve = |threads: usize| {
        on_threads(threads, || {
            let mut solver = ProgressiveSolver::new(&s, options.clone()).unwrap();
            run(&mut solver);
            let (rays, deposits) = solver.specular_transfer().unwrap();
            assert!(rays > 0 && deposits > 0);
            let e = solver.progress().energy;
            (bits(&solver.vertex_radiosity()), e)
        })
    };
    let (one, two) = (solve(1), solve(2));
    assert_eq!(one.0, two.0, "one and two threads differ");
    // The room is open toward the camera, so light escapes; what the spheres used to swallow
    // (they take no part in the form factors) now reaches the walls: less escapes.
    let mut dark = ProgressiveSolver::new(
        &s,
        Options {
            specular: None,
            ..options.clone()
        },
    )
    .unwrap();
    run(&mut dark);
    let (with, without) = (one.1.escaped, dark.progress().energy.escaped);
    assert!(
        with.cmplt(without * 0.95).all(),
        "escaped {with:?} with the transfer, {without:?} without"
    );
}

/// Mean radiance over the image rectangle `[x0, x1) x [y0, y1)` (fractions of the image).
fn region_mean(image: &twopass_image::Image, x: (f32, f32), y: (f32, f32)) -> DVec3 {
    let (w, h) = (image.width() as f32, image.height() as f32);
    let (mut sum, mut n) = (DVec3::ZERO, 0.0);
    for py in (y.0 * h) as u32..(y.1 * h) as u32 {
        for px in (x.0 * w) as u32..(x.1 * w) as u32 {
            sum += image.pixels()[(py * image.width() + px) as usize].as_dvec3();
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn the_tracer_adds_no_light_through_glass_again() {
    // Under the glass sphere the floor is hidden from the light: shadow rays stop at the glass
    // (an occluder) and the solution's direct part is zero there, so the caustic lives only in
    // the solution's indirect part. The classic hybrid (the whole solution) and hybrid-direct
    // (shadow rays plus the indirect part) must then agree on the caustic, and both must see it.
    use twopass_trace::hybrid::{DirectLight, hybrid};
    use twopass_trace::{RenderProgress, RenderSettings, WhittedSettings, render};
    let (s, _) = load(scene_path("cornell-spheres.toml")).unwrap();
    let options = |specular| coarse(specular, 1e-2);
    let camera = s.camera.with_resolution(Some(64), Some(64));
    let settings = RenderSettings {
        samples_per_pixel: 16,
        seed: 3,
        ..RenderSettings::default()
    };
    // The caustic on the floor, to the camera's right of the glass sphere's foot (the
    // regions of docs/benchmarks.md's specular-transfer figures, as fractions of the image).
    let (x, y) = (
        (150.0 / 256.0, 186.0 / 256.0),
        (222.0 / 256.0, 238.0 / 256.0),
    );
    let caustic = |specular| {
        let mut solver = ProgressiveSolver::new(&s, options(specular)).unwrap();
        run(&mut solver);
        let solution = solver.solution();
        let p = RenderProgress::new();
        let h = render(
            &s,
            &camera,
            &hybrid(
                &s,
                &solution,
                DirectLight::FromSolution,
                WhittedSettings::default(),
            ),
            &settings,
            &p,
        );
        let hd = render(
            &s,
            &camera,
            &hybrid(
                &s,
                &solution,
                DirectLight::PerPixel,
                WhittedSettings::default(),
            ),
            &settings,
            &p,
        );
        (
            region_mean(&h.layers.composite(), x, y),
            region_mean(&hd.layers.composite(), x, y),
        )
    };
    let (h, hd) = caustic(Some(SpecularOptions {
        rays: 1 << 18,
        ..SpecularOptions::default()
    }));
    let (dark, _) = caustic(None);
    assert!(
        h.cmpgt(dark * 3.0).all(),
        "the caustic: {h} with the transfer, {dark} without"
    );
    // The two differ only by the shadow rays' noise against the mesh's direct light around
    // the caustic's edge; a second copy of the caustic would double it.
    let off = ((hd - h).abs() / h).max_element();
    assert!(off < 0.02, "hybrid {h} vs hybrid-direct {hd}");
}

#[test]
fn a_mirror_facing_no_diffuse_surface_is_not_modelled() {
    // The receiver scene with its mirror turned over (facing down, away from the emitter and
    // the receiver above it): no light reaches its front and nothing it would reflect lands
    // anywhere, so the planner skips the transfer and the solve casts none of its rays.
    let camera = "position = [0, 3, 0.01]\nlook_at = [0, 0, 0]\nfov_y = 60";
    let text = mirror_text(camera, [1.0; 3], true, "grey");
    let s = load_toml(&text, Path::new("turned.toml")).unwrap().0;
    let (needed, why) = decide(&s);
    assert!(!needed, "{why}");
    assert!(
        why.contains("mirror is lit by and seen from no diffuse surface"),
        "{why}"
    );
    let solver = ProgressiveSolver::new(&s, Options::default()).unwrap();
    assert_eq!(solver.specular_transfer(), None);
    // The same mirror facing up is modelled (the scene of the closed-form test).
    assert!(decide(&mirror_scene([1.0; 3])).0);
}

#[test]
fn per_pixel_caustics_replace_the_meshs_focused_light_once() {
    // The classic hybrid shows the light the glass sphere focuses either from the element mesh
    // (caustic_paths = 0) or per pixel by light tracing, with the mesh's focused part taken
    // out where the camera sees it. Each counts it once: the image's and the caustic's mean
    // agree. Per pixel the caustic is sharper, so closer to the reference there.
    use twopass_trace::hybrid::{DirectLight, hybrid};
    use twopass_trace::{
        Reference, ReferenceSettings, RenderProgress, RenderSettings, WhittedSettings, render,
    };
    let (s, _) = load(scene_path("cornell-spheres.toml")).unwrap();
    let mut solver = ProgressiveSolver::new(
        &s,
        coarse(
            Some(SpecularOptions {
                rays: 1 << 18,
                ..SpecularOptions::default()
            }),
            1e-2,
        ),
    )
    .unwrap();
    run(&mut solver);
    let solution = solver.solution();
    let focused = solution.focused_caustics().expect("the solve separates it");
    assert!(focused.iter().any(|f| f.max_element() > 0.0));
    let camera = s.camera.with_resolution(Some(48), Some(48));
    let settings = RenderSettings {
        samples_per_pixel: 64,
        seed: 9,
        ..RenderSettings::default()
    };
    let image = |paths: f32| {
        let h = hybrid(
            &s,
            &solution,
            DirectLight::FromSolution,
            WhittedSettings {
                caustic_paths: paths,
                ..WhittedSettings::default()
            },
        );
        let out = render(&s, &camera, &h, &settings, &RenderProgress::new());
        assert_eq!(out.stats.light_paths > 0, paths > 0.0);
        out.layers.composite()
    };
    let (mesh, per_pixel) = (image(0.0), image(4.0));
    // Same seed, same image on one thread (the light tracing pass included).
    let one = on_threads(1, || image(4.0));
    assert_eq!(one, per_pixel, "one and two threads differ");
    let reference = render(
        &s,
        &camera,
        &Reference::new(&s, ReferenceSettings::default()),
        &RenderSettings {
            samples_per_pixel: 1024,
            seed: 10,
            ..RenderSettings::default()
        },
        &RenderProgress::new(),
    )
    .layers
    .composite();
    let whole = ((0.0, 1.0), (0.0, 1.0));
    // The floor under and beside the glass sphere, where the focused light lands.
    let caustic = (
        (110.0 / 256.0, 200.0 / 256.0),
        (205.0 / 256.0, 250.0 / 256.0),
    );
    for (name, (x, y), tolerance) in [("image", whole, 0.01), ("caustic", caustic, 0.04)] {
        let (m, p) = (region_mean(&mesh, x, y), region_mean(&per_pixel, x, y));
        let off = ((p - m).abs() / m).max_element();
        assert!(off < tolerance, "{name}: mesh {m} vs per pixel {p}");
    }
    // Relative RMS difference from the reference over the caustic's pixels.
    let error = |img: &twopass_image::Image| {
        let (w, h) = (img.width() as f32, img.height() as f32);
        let (mut num, mut den) = (0.0, 0.0);
        for py in (caustic.1.0 * h) as u32..(caustic.1.1 * h) as u32 {
            for px in (caustic.0.0 * w) as u32..(caustic.0.1 * w) as u32 {
                let i = (py * img.width() + px) as usize;
                let (a, r) = (img.pixels()[i].as_dvec3(), reference.pixels()[i].as_dvec3());
                num += (a - r).length_squared();
                den += r.length_squared();
            }
        }
        (num / den).sqrt()
    };
    let (e_mesh, e_pixel) = (error(&mesh), error(&per_pixel));
    eprintln!("caustic region vs reference: mesh {e_mesh:.4}, per pixel {e_pixel:.4}");
    assert!(e_pixel < e_mesh, "mesh {e_mesh} vs per pixel {e_pixel}");
}

/// Area-weighted mean vertex radiosity (red channel) per object of a solution, each vertex
/// standing for a third of the elements around it. Vertices inside other objects (a ceiling
/// behind the light fixed just below it) have no light of their own, and the solvers show
/// them differently (progressive refinement its visible neighbours' light): left out.
fn wall_means(scene: &Scene, solution: &twopass_radiosity::Solution, objects: usize) -> Vec<f64> {
    let mesh = solution.mesh();
    let b = solution.vertex_radiosity();
    // The solvers' own test, at their receiving points and with their default seed.
    let seed = Options::default().seed;
    let (hidden, _) = twopass_radiosity::hidden::hidden_vertices(scene, mesh, 0, seed);
    let (mut sum, mut area) = (vec![0.0; objects], vec![0.0; objects]);
    for leaf in mesh.leaves() {
        let node = &mesh.nodes[leaf as usize];
        for &v in node.vertices.iter().filter(|&&v| !hidden[v as usize]) {
            let o = mesh.vertices[v as usize].object as usize;
            sum[o] += f64::from(b[v as usize].x) * f64::from(node.area) / 3.0;
            area[o] += f64::from(node.area) / 3.0;
        }
    }
    sum.iter().zip(&area).map(|(s, a)| s / a).collect()
}

#[test]
fn hierarchical_solver_carries_light_through_a_mirror_in_the_furnace() {
    // The mirror furnace (see above) solved by hierarchical radiosity: with the transfer the
    // walls' mean radiosity is E / (1 - rho), as if the mirror were one more wall; without it
    // the mirror absorbs and the walls are darker. The leaves that grew since they last sent
    // are sampled by their growth, so the estimate is unbiased whatever the leaf count.
    use twopass_radiosity::{HierarchicalSolver, Method};
    let rho = 0.5;
    let s = mirror_furnace(rho);
    let expected = PI / (1.0 - rho);
    let solve = |specular| {
        let options = Options {
            method: Method::Hierarchical,
            ..furnace_options(specular)
        };
        let mut solver = HierarchicalSolver::new(&s, options).unwrap();
        solver.run(|_| std::ops::ControlFlow::Continue(()));
        let transfer = solver.specular_transfer();
        let means = wall_means(&s, &solver.solution(), 6);
        let worst = (1..6)
            .map(|o| (means[o] - expected).abs() / expected)
            .fold(0.0, f64::max);
        (worst, transfer)
    };
    let (wall, transfer) = solve(Some(SpecularOptions {
        rays: 1 << 21,
        ..SpecularOptions::default()
    }));
    let (rays, deposits) = transfer.expect("the transfer runs");
    assert!(
        rays > 0 && deposits > 100_000,
        "{rays} rays, {deposits} deposits"
    );
    let (dark_wall, none) = solve(None);
    assert!(none.is_none());
    eprintln!("hierarchical mirror furnace: worst wall {wall:.4}, as an absorber {dark_wall:.4}");
    assert!(
        wall < 1e-2,
        "worst wall mean off by {wall} (without the transfer {dark_wall})"
    );
    assert!(dark_wall > 5e-2, "the mirror as an absorber: {dark_wall}");
}

#[test]
fn hierarchical_and_progressive_transfer_agree_on_the_spheres() {
    // The same scene, two solvers, one transfer: what the transfer adds to each wall's and the
    // floor's mean radiosity agrees (the meshes differ, so vertex by vertex they cannot, and
    // the two solvers' shadows of the spheres differ by a few per cent on the coarse mesh
    // with or without it), and the hierarchical solve gives the same bits on one and two
    // threads.
    use twopass_radiosity::{HierarchicalSolver, Method, Solution};
    let (s, _) = load(scene_path("cornell-spheres.toml")).unwrap();
    let transfer = Some(SpecularOptions {
        rays: 1 << 18,
        ..SpecularOptions::default()
    });
    let progressive = |specular| {
        // Patches of 75 mm: the coarse tests' 150 mm patches shoot too coarsely for the mirror
        // sphere's image of the light on the ceiling (11 % less there than finer patches).
        let options = Options {
            patch_size: Some(75.0),
            element_size: Some(40.0),
            ..coarse(specular, 1e-3)
        };
        let mut solver = ProgressiveSolver::new(&s, options).unwrap();
        run(&mut solver);
        wall_means(&s, &solver.solution(), s.objects.len())
    };
    let hierarchical = |specular, threads: usize| -> Solution {
        on_threads(threads, || {
            let mut solver = HierarchicalSolver::new(
                &s,
                Options {
                    method: Method::Hierarchical,
                    stop: Stop {
                        unshot_fraction: 1e-3,
                        ..Stop::default()
                    },
                    specular,
                    // A tenth of the default link tolerance: at the default the hierarchical
                    // solver's own refinement leaves the ceiling's visible part 4 % below
                    // progressive refinement's, with or without the transfer (the
                    // discretization bias `bench bakes` measures), which this test is not
                    // about; at 2e-6 the two agree on it within 1 %.
                    hierarchical: twopass_radiosity::HierarchicalOptions {
                        link_tolerance: 2e-6,
                        ..Default::default()
                    },
                    ..Options::default()
                },
            )
            .unwrap();
            solver.run(|_| std::ops::ControlFlow::Continue(()));
            solver.solution()
        })
    };
    let (one, two) = (hierarchical(transfer, 1), hierarchical(transfer, 2));
    let vertex_bits = |s: &Solution| {
        bits(
            &s.vertex_radiosity()
                .iter()
                .map(|v| v.as_dvec3())
                .collect::<Vec<_>>(),
        )
    };
    assert_eq!(
        vertex_bits(&one),
        vertex_bits(&two),
        "one and two threads differ"
    );
    assert!(
        one.focused_caustics()
            .is_some_and(|f| f.iter().any(|x| x.max_element() > 0.0)),
        "the glass sphere's focus is separated"
    );
    let n = s.objects.len();
    let (h, h0) = (
        wall_means(&s, &one, n),
        wall_means(&s, &hierarchical(None, 2), n),
    );
    let (p, p0) = (progressive(transfer), progressive(None));
    for (o, object) in s.objects.iter().enumerate() {
        if object.name.contains("sphere") || object.name == "light" {
            continue;
        }
        let (dh, dp) = (h[o] - h0[o], p[o] - p0[o]);
        eprintln!(
            "{}: transfer adds {dh:.4} (hierarchical) {dp:.4} (progressive)",
            object.name
        );
        assert!(dh > 0.0 && dp > 0.0, "{}: {dh} {dp}", object.name);
        assert!(
            (dh - dp).abs() < 0.03 * dp,
            "{}: hierarchical adds {dh}, progressive {dp}",
            object.name
        );
    }
}
