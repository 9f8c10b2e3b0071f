//! The bake's final gather end to end: the element-mesh outputs re-estimated at their vertices
//! match the closed form of a floor under a square emitter, and a gathered lightmap is the same
//! bit for bit on one thread or two.

use twopass_bake::{ColorMapping, LightmapSettings, TexelSource, bake_lightmap, gathered_solution};
use twopass_radiosity::{Options, Solver};
use twopass_scene::Scene;
use twopass_trace::gather::{GatherSettings, Gatherer};

use crate::closed_form::{floor_under_square, square_form_factor};
use crate::{on_threads, scene_path};

fn solved(scene: &Scene) -> twopass_radiosity::Solution {
    let mut solver = Solver::new(scene, Options::default()).unwrap();
    solver.run(|_| std::ops::ControlFlow::Continue(()));
    solver.solution()
}

#[test]
fn gathered_element_vertices_match_the_closed_form() {
    let (scene, _) = twopass_scene::load_toml(
        &floor_under_square(10.0),
        std::path::Path::new("floor.toml"),
    )
    .unwrap();
    let solution = solved(&scene);
    let gatherer = Gatherer::new(
        &scene,
        &solution,
        GatherSettings {
            // 64 x 64 strata: the check is of the estimator's mean, not of its noise.
            shadow_rays: 4096,
            ..GatherSettings::default()
        },
    );
    let gathered = gathered_solution(&solution, &scene, &gatherer);
    let mesh = gathered.mesh();
    let mut checked = 0;
    for (v, direct) in mesh.vertices.iter().zip(gathered.direct()) {
        if v.object != 0 {
            continue;
        }
        let (x, z) = (f64::from(v.position.x), f64::from(v.position.z));
        let f = square_form_factor(x, z);
        // Radiosity B = rho L_e pi F, W/m^2 (the solution's unit).
        let exact = 0.5 * 10.0 * std::f64::consts::PI * f;
        let got = f64::from(direct.x);
        assert!(
            (got - exact).abs() < 0.01 * exact + 1e-4,
            "vertex at ({x}, {z}): direct B {got} vs {exact}"
        );
        checked += 1;
    }
    assert!(checked >= 4, "{checked} floor vertices");
    // On the floor (no emission) the total is the sum of the two parts.
    for (((v, b), d), i) in mesh
        .vertices
        .iter()
        .zip(gathered.shot_radiosity())
        .zip(gathered.direct())
        .zip(gathered.indirect())
    {
        if v.object == 0 {
            assert!(((*d + *i) - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0));
        }
    }
}

#[test]
fn a_gathered_lightmap_is_the_same_on_one_thread_or_two() {
    let (scene, _) = twopass_scene::load(scene_path("cornell-box.toml")).unwrap();
    let solution = solved(&scene);
    let settings = LightmapSettings {
        texel_size: Some(20.0),
        ..LightmapSettings::default()
    };
    let bake = |threads| {
        on_threads(threads, || {
            let gatherer = Gatherer::new(
                &scene,
                &solution,
                GatherSettings {
                    seed: 9,
                    ..GatherSettings::default()
                },
            );
            bake_lightmap(
                TexelSource::Gather(&gatherer),
                &scene,
                &settings,
                ColorMapping { exposure: 1.0 },
            )
            .unwrap()
        })
    };
    let (a, b) = (bake(1), bake(2));
    assert!(a.rays > 0 && a.shadow_rays > 0);
    assert_eq!(a.exr, b.exr, "the EXR bit for bit");
    assert_eq!((a.rays, a.shadow_rays), (b.rays, b.shadow_rays));
}
