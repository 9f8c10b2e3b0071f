//! The final gather against closed forms: the direct part at a point under a parallel square
//! emitter is rho L_e F (Howell's C-11 form factor), the indirect part under a surface of known
//! radiance L_0 is rho L_0 F, a point inside a closed furnace reads rho L_0 exactly, a mirror
//! passes the solution's whole radiance (emission included) times its reflectance, a point
//! inside a closed object says so, and the estimate depends on its key alone.

use twopass_brdf::Rgb;
use twopass_scene::{DiffuseRadiance, RadianceEstimator, Scene};
use twopass_trace::gather::{GatherSettings, Gatherer};

use super::common::scene;
use crate::closed_form::square_form_factor;
use crate::on_threads;

/// A solution that is `value` on every triangle of the objects in `lit` and zero elsewhere
/// (radiance W/(m^2 sr), indirect part the same).
pub(super) struct Constant {
    value: Rgb,
    lit: Vec<u32>,
    triangle_object: Vec<u32>,
}

impl Constant {
    /// `value` on the objects `lit` of `scene`, zero elsewhere.
    pub(super) fn new(scene: &Scene, value: f32, lit: &[u32]) -> Self {
        Self {
            value: Rgb::splat(value),
            lit: lit.to_vec(),
            triangle_object: (0..scene.mesh.triangle_count() as u32)
                .map(|t| scene.mesh.object_of(t))
                .collect(),
        }
    }
}

impl DiffuseRadiance for Constant {
    fn radiance(&self, triangle: u32, _: [f32; 3]) -> Rgb {
        if self.lit.contains(&self.triangle_object[triangle as usize]) {
            self.value
        } else {
            Rgb::ZERO
        }
    }

    fn indirect_radiance(&self, triangle: u32, b: [f32; 3]) -> Rgb {
        self.radiance(triangle, b)
    }
}

/// The scene of [`crate::closed_form::floor_under_square`]: the floor is object 0, the square
/// object 1.
fn floor_under_square(emission: f32) -> Scene {
    scene(&crate::closed_form::floor_under_square(emission))
}

/// The point of the floor straight under (x, z): its triangle and barycentrics.
pub(super) fn floor_point(scene: &Scene, x: f32, z: f32) -> (u32, [f32; 3]) {
    let hit = scene
        .intersect(&twopass_scene::Ray::new(
            glam::Vec3::new(x, 0.25, z),
            glam::Vec3::NEG_Y,
        ))
        .expect("the floor");
    assert_eq!(hit.object, 0);
    (hit.point.triangle, hit.barycentric)
}

#[test]
fn direct_part_is_rho_le_f() {
    let scene = floor_under_square(10.0);
    let dark = Constant::new(&scene, 0.0, &[]);
    let g = Gatherer::new(
        &scene,
        &dark,
        GatherSettings {
            shadow_rays: 1024,
            ..GatherSettings::default()
        },
    );
    for (x, z) in [(0.0, 0.0), (0.3, -0.1), (1.2, 0.7)] {
        let (t, b) = floor_point(&scene, x, z);
        let e = g.estimate(t, b, 7);
        let exact = 0.5 * 10.0 * square_form_factor(f64::from(x), f64::from(z));
        let got = f64::from(e.direct.x);
        // 32 x 32 jittered strata over a smooth integrand: far below 0.5 % off.
        assert!(
            (got - exact).abs() < 5e-3 * exact,
            "({x}, {z}): direct {got} vs rho L_e F = {exact}"
        );
        assert_eq!(e.emitted, Rgb::ZERO);
        assert_eq!(e.indirect, Rgb::ZERO, "nothing but the emitter is lit");
        assert!(e.shadow_rays > 0);
    }
}

#[test]
fn indirect_part_is_rho_l0_f_within_its_error() {
    // The square does not emit; the solution says it has radiance 2 toward the floor. The
    // gather rays that land on it read that: rho L_0 F.
    let scene = floor_under_square(0.0);
    let solution = Constant::new(&scene, 2.0, &[1]);
    let g = Gatherer::new(
        &scene,
        &solution,
        GatherSettings {
            min_rays: 4096,
            max_rays: 4096,
            target_error: 0.0,
            ..GatherSettings::default()
        },
    );
    for (k, (x, z)) in [(0.0f32, 0.0f32), (0.4, 0.2)].into_iter().enumerate() {
        let (t, b) = floor_point(&scene, x, z);
        let e = g.estimate(t, b, k as u64);
        let exact = 0.5 * 2.0 * square_form_factor(f64::from(x), f64::from(z));
        let got = f64::from(e.indirect.x);
        // A Bernoulli estimate (the ray hits the square or not) of N = 4096 rays: its standard
        // error is rho L_0 sqrt(F (1 - F) / N); the estimate reports its own.
        let sigma = 0.5 * 2.0 * (exact / 1.0 * (1.0 - exact) / 4096.0).sqrt();
        assert!(
            (got - exact).abs() < 4.0 * sigma,
            "({x}, {z}): indirect {got} vs rho L_0 F = {exact} (sigma {sigma})"
        );
        assert!(
            (f64::from(e.indirect_error) - sigma).abs() < 0.2 * sigma,
            "reported error {} vs {sigma}",
            e.indirect_error
        );
        assert_eq!(e.direct, Rgb::ZERO, "no emitter");
        assert_eq!(e.back_faces, 0.0);
    }
}

/// A closed cube of six inward-facing grey quads (objects 0 to 5).
fn cube() -> Scene {
    let mut text = String::from(
        "version = 1\n\
         [camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 1]\nfov_y = 90\nresolution = [8, 8]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n",
    );
    for (name, origin, u, v) in [
        ("floor", "[-1, -1, -1]", "[0, 0, 2]", "[2, 0, 0]"),
        ("ceiling", "[-1, 1, -1]", "[2, 0, 0]", "[0, 0, 2]"),
        ("left", "[-1, -1, -1]", "[0, 2, 0]", "[0, 0, 2]"),
        ("right", "[1, -1, -1]", "[0, 0, 2]", "[0, 2, 0]"),
        ("back", "[-1, -1, -1]", "[2, 0, 0]", "[0, 2, 0]"),
        ("front", "[-1, -1, 1]", "[0, 2, 0]", "[2, 0, 0]"),
    ] {
        text += &format!(
            "[[object]]\nname = \"{name}\"\nmaterial = \"grey\"\n\
             shape = {{ type = \"quad\", origin = {origin}, edge_u = {u}, edge_v = {v} }}\n"
        );
    }
    scene(&text)
}

#[test]
fn inside_a_furnace_the_gather_reads_rho_l0_exactly() {
    // Every wall shows radiance 1: every gather ray reads 1, so the estimate is rho exactly
    // and its error zero, however few rays it takes.
    let scene = cube();
    let solution = Constant::new(&scene, 1.0, &[0, 1, 2, 3, 4, 5]);
    let g = Gatherer::new(&scene, &solution, GatherSettings::default());
    let (t, b) = (0, [0.2, 0.3, 0.5]);
    let e = g.estimate(t, b, 99);
    assert!((e.indirect.x - 0.5).abs() < 1e-5, "{}", e.indirect);
    assert_eq!(e.indirect_error, 0.0);
    assert_eq!(
        e.rays,
        u64::from(GatherSettings::default().min_rays),
        "converged after one batch"
    );
}

#[test]
fn a_mirror_passes_the_whole_solution_times_its_reflectance() {
    // The floor emits (L_e = 1) and the solution gives it radiance 1, emission included; the
    // square above it is a mirror of reflectance 0.8 facing down. A gather ray that hits the
    // mirror comes back to the floor, where no shadow ray looked, so it reads the whole
    // solution: rho 0.8 x 1 x F. Rays past the mirror escape. No emitter is seen directly.
    let scene = scene(
        "version = 1\n\
         [camera]\nposition = [0, 0.9, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = 0.8\n\
         [[object]]\nname = \"floor\"\nmaterial = \"grey\"\nemission = 1\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n\
         [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
         shape = { type = \"quad\", origin = [-0.25, 1, -0.25], edge_u = [0.5, 0, 0], edge_v = [0, 0, 0.5] }\n",
    );
    let solution = Constant::new(&scene, 1.0, &[0]);
    let g = Gatherer::new(
        &scene,
        &solution,
        GatherSettings {
            min_rays: 4096,
            max_rays: 4096,
            target_error: 0.0,
            ..GatherSettings::default()
        },
    );
    let (t, b) = floor_point(&scene, 0.1, -0.05);
    let e = g.estimate(t, b, 3);
    let f = square_form_factor(0.1, -0.05);
    let exact = 0.5 * 0.8 * f;
    let sigma = 0.5 * 0.8 * (f * (1.0 - f) / 4096.0).sqrt();
    let got = f64::from(e.indirect.x);
    assert!(
        (got - exact).abs() < 4.0 * sigma,
        "indirect {got} vs rho R F = {exact} (sigma {sigma})"
    );
    assert_eq!(e.emitted, Rgb::ONE, "the floor's own emission");
    assert_eq!(
        e.direct,
        Rgb::ZERO,
        "mirrors occlude shadow rays; the floor cannot see itself"
    );
}

#[test]
fn a_point_inside_a_closed_object_sees_its_back_faces() {
    // A closed box (built-in `box`) pushed halfway into the floor: floor points under it are
    // inside, points beside it are not.
    let scene = scene(
        "version = 1\n\
         [camera]\nposition = [0, 0.9, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n\
         [[object]]\nname = \"box\"\nmaterial = \"grey\"\n\
         shape = { type = \"box\", min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] }\n",
    );
    let dark = Constant::new(&scene, 0.0, &[]);
    let g = Gatherer::new(&scene, &dark, GatherSettings::default());
    let (t, b) = floor_point(&scene, 0.1, 0.2);
    assert_eq!(g.estimate(t, b, 1).back_faces, 1.0, "inside the box");
    let (t, b) = floor_point(&scene, 1.5, 0.2);
    assert_eq!(g.estimate(t, b, 2).back_faces, 0.0, "beside the box");
}

#[test]
fn an_estimate_depends_on_its_key_alone() {
    let scene = floor_under_square(10.0);
    let solution = Constant::new(&scene, 0.5, &[0, 1]);
    let points: Vec<(u32, [f32; 3])> = [(0.0, 0.0), (0.3, 0.4), (1.1, -0.6)]
        .iter()
        .map(|&(x, z)| floor_point(&scene, x, z))
        .collect();
    let run = |threads: usize, order_reversed: bool| {
        on_threads(threads, || {
            let g = Gatherer::new(&scene, &solution, GatherSettings::default());
            let mut keys: Vec<usize> = (0..points.len()).collect();
            if order_reversed {
                keys.reverse();
            }
            let mut out: Vec<_> = keys
                .iter()
                .map(|&k| (k, g.estimate(points[k].0, points[k].1, 1000 + k as u64)))
                .collect();
            out.sort_by_key(|(k, _)| *k);
            out
        })
    };
    let a = run(1, false);
    let b = run(2, true);
    for ((_, x), (_, y)) in a.iter().zip(&b) {
        assert_eq!(x, y, "the same key gives the same estimate, bit for bit");
    }
    let g = Gatherer::new(&scene, &solution, GatherSettings::default());
    let (t, bary) = points[1];
    assert_ne!(
        g.estimate(t, bary, 1).direct,
        g.estimate(t, bary, 2).direct,
        "another key, another sequence"
    );
}

#[test]
fn direct_noise_at_the_default_settings_is_below_one_percent() {
    // The target: direct-light noise below 1 % per point. The spread over 200 keys of
    // one point's direct estimate, relative to the closed form, at points under, beside and
    // far from the light (where the light subtends a small, oblique solid angle).
    let scene = floor_under_square(10.0);
    let dark = Constant::new(&scene, 0.0, &[]);
    let g = Gatherer::new(&scene, &dark, GatherSettings::default());
    for (x, z) in [(0.0f32, 0.0f32), (0.5, 0.1), (1.5, -0.4), (1.9, 1.9)] {
        let (t, b) = floor_point(&scene, x, z);
        let exact = 0.5 * 10.0 * square_form_factor(f64::from(x), f64::from(z));
        let values: Vec<f64> = (0..200)
            .map(|k| f64::from(g.estimate(t, b, k).direct.x))
            .collect();
        let (mean, error) = super::common::mean_and_error(&values);
        let spread = error * (values.len() as f64).sqrt();
        eprintln!(
            "({x}, {z}): spread {:.3} %, mean off {:.3} %",
            100.0 * spread / exact,
            100.0 * (mean / exact - 1.0)
        );
        assert!(
            spread < 0.01 * exact,
            "({x}, {z}): noise {} of {exact}",
            spread
        );
        assert!(
            (mean - exact).abs() < 4.0 * error + 1e-9,
            "({x}, {z}): biased"
        );
    }
}
