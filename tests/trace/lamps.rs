//! Lamps in the tracer against closed forms: a point lamp over a plane gives I cos(theta) /
//! r^2, a spot's profile across the floor follows glTF's smooth falloff, a directional lamp
//! gives E cos(theta) and a sharp shadow; the gathered hybrid agrees with the path tracer in a
//! box lit by a point lamp; a lamp lying on a surface puts no NaN in the image; one and two
//! threads give the same image.

use glam::Vec3;
use twopass_scene::Scene;
use twopass_trace::{
    Layer, Reference, ReferenceSettings, RenderProgress, RenderSettings, WhittedSettings, render,
};

use super::common::{pixel_means, scene};
use super::gathered::{Agreement, pixels_where, solve};
use crate::lamps::{RHO, gltf_falloff, in_blocker_shadow, plane_under};

/// Renders without jitter: every sample of a pixel lands on the centre of its stratum.
fn settings(spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: spp,
        seed,
        jitter: false,
        tile_size: 8,
        adaptive: None,
    }
}

/// Per pixel, the mean of `radiance` (W/(m^2 sr)) over the points of the plane (object 0,
/// seen from the front) a render of `spp` samples without jitter sees.
fn expected(scene: &Scene, spp: u32, radiance: impl Fn(Vec3) -> Option<f64>) -> Vec<Option<f64>> {
    pixel_means(scene, spp, |h| {
        (h.object == 0 && h.front_face)
            .then_some(h.point.position)
            .and_then(&radiance)
    })
}

/// The path tracer's image (composite, red channel) at 4 spp against `exact`: with one lamp
/// and nothing above the plane to bounce from, each sample's value is exact at its point
/// (one shadow ray to a delta light, no random choice), so the pixels match to f32 rounding.
/// Returns how many pixels were compared.
fn reference_matches(scene: &Scene, exact: &[Option<f64>]) -> usize {
    let r = Reference::new(scene, ReferenceSettings::default());
    let out = render(
        scene,
        &scene.camera,
        &r,
        &settings(4, 3),
        &RenderProgress::new(),
    );
    assert_eq!(out.stats.non_finite, 0);
    let img = out.layers.composite();
    let mut n = 0;
    for (i, e) in exact.iter().enumerate() {
        let got = f64::from(img.pixels()[i].x);
        match e {
            Some(e) if *e > 0.0 => {
                assert!((got / e - 1.0).abs() < 1e-4, "pixel {i}: {got} vs {e}");
                n += 1;
            }
            Some(_) => assert!(got.abs() < 1e-9, "pixel {i}: {got} in the shadow"),
            None => {}
        }
    }
    n
}

#[test]
fn a_point_lamp_lights_the_plane_with_i_cos_over_r_squared() {
    let (i, h) = (3.0, 1.0);
    let s = plane_under(
        &format!("[[light]]\nkind = \"point\"\nposition = [0, {h}, 0]\nintensity = {i}\n"),
        false,
    );
    // E = I cos / r^2 = I h / r^3; L = rho / pi E.
    let exact = expected(&s, 4, |p| {
        let p = p.as_dvec3();
        let r2 = p.x * p.x + h * h + p.z * p.z;
        Some(RHO / std::f64::consts::PI * i * h / (r2 * r2.sqrt()))
    });
    let n = reference_matches(&s, &exact);
    assert!(n > 700, "the plane fills the view: {n} pixels");
}

#[test]
fn a_spot_falls_off_across_the_floor_as_gltf_says() {
    let (i, h, inner, outer) = (5.0, 1.0, 20.0, 40.0);
    let s = plane_under(
        &format!(
            "[[light]]\nkind = \"spot\"\nposition = [0, {h}, 0]\ndirection = [0, -1, 0]\n\
             intensity = {i}\ninner_angle = {inner}\nouter_angle = {outer}\n"
        ),
        false,
    );
    let exact = expected(&s, 4, |p| {
        let p = p.as_dvec3();
        let r = (p.x * p.x + h * h + p.z * p.z).sqrt();
        let cos = h / r;
        Some(RHO / std::f64::consts::PI * i * gltf_falloff(cos, inner, outer) * cos / (r * r))
    });
    let n = reference_matches(&s, &exact);
    // The profile crosses the whole blend: lit, fading and dark pixels are all compared.
    let lit = exact.iter().flatten().filter(|&&e| e > 0.0).count();
    assert!(
        n > 50 && lit < exact.iter().flatten().count(),
        "{n} lit pixels"
    );
}

#[test]
fn a_directional_lamp_gives_e_cos_theta_and_a_sharp_shadow() {
    let e = 2.0;
    // Travelling along (1, -2, 0): cos(theta) = 2 / sqrt(5) on the plane; the blocker's
    // shadow is its square moved by +0.25 in x: x in [0, 0.5], z in [-0.25, 0.25].
    let s = plane_under(
        &format!("[[light]]\nkind = \"directional\"\ndirection = [1, -2, 0]\nirradiance = {e}\n"),
        true,
    );
    let cos = 2.0 / 5f64.sqrt();
    let mut shadowed = 0;
    let exact = expected(&s, 4, |p| {
        let inside = in_blocker_shadow(p, 1e-3)?;
        Some(if inside {
            0.0
        } else {
            RHO / std::f64::consts::PI * e * cos
        })
    });
    shadowed += exact.iter().filter(|e| **e == Some(0.0)).count();
    let n = reference_matches(&s, &exact);
    assert!(
        n > 500 && shadowed > 10,
        "{n} lit, {shadowed} shadowed pixels"
    );
}

/// A closed grey box 2 m wide (the unit cube's faces facing in, scaled and centred) with a
/// crate on its floor, seen from inside, lit by `light`.
fn lamp_box(light: &str) -> Scene {
    let walls: String = crate::radiosity::CUBE_FACES
        .iter()
        .enumerate()
        .map(|(i, (o, u, v))| {
            let o = o.map(|c| 2.0 * c - 1.0);
            let (u, v) = (u.map(|c| 2.0 * c), v.map(|c| 2.0 * c));
            format!(
                "[[object]]\nname = \"wall{i}\"\nmaterial = \"grey\"\n\
                 shape = {{ type = \"quad\", origin = {o:?}, edge_u = {u:?}, edge_v = {v:?} }}\n"
            )
        })
        .collect();
    scene(&format!(
        "version = 1\n\
         [camera]\nposition = [0, 0, 0.9]\nlook_at = [0, -0.2, -1]\nfov_y = 70\nresolution = [40, 40]\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.6\n{walls}\
         [[object]]\nname = \"crate\"\nmaterial = \"grey\"\n\
         shape = {{ type = \"box\", min = [-0.3, -1, -0.6], max = [0.2, -0.5, -0.1] }}\n{light}"
    ))
}

/// A point lamp of 10 W/sr off the box's centre.
const POINT_LAMP: &str =
    "[[light]]\nkind = \"point\"\nposition = [0.3, 0.6, 0.1]\nintensity = 10\n";

/// A small square emitter at the point lamp's place, facing down: the area-lit twin.
const SMALL_AREA: &str = "[[object]]\nname = \"bulb\"\nmaterial = \"grey\"\nemission = 1000\n\
    shape = { type = \"quad\", origin = [0.25, 0.6, 0.05], edge_u = [0.1, 0, 0], edge_v = [0, 0, 0.1] }\n";

#[test]
fn the_gathered_hybrid_agrees_with_the_path_tracer_in_a_box_lit_by_a_point_lamp() {
    let measure = |light: &str| {
        let s = lamp_box(light);
        let all = pixels_where(&s, &s.camera, |h| h.front_face);
        assert_eq!(all.len(), 1600, "the camera sees only the inside");
        let solution = solve(&s, s.bounds.diagonal() / 24.0);
        (
            Agreement::measure(&s, &s.camera, &solution, &all, 5),
            all.len(),
        )
    };
    let (lamp, n) = measure(POINT_LAMP);
    // Pixel by pixel the hybrid is within the renders' noise of the path tracer: the ratio
    // of their mean squared difference to the noise's is 1 within four of its standard
    // deviations (about sqrt(3 / n), see `Agreement::assert_agrees`).
    let bound = 1.0 + 4.0 * (3.0 / n as f64).sqrt();
    assert!(
        lamp.excess.0 < bound,
        "excess {} (bound {bound})",
        lamp.excess.0
    );
    // Over all 1600 pixels the region mean resolves the hybrid's own bias (the solution's
    // error one bounce away; the same solve lit by a small square emitter in the lamp's place
    // shows it too): the lamp adds none, its relative gap is at most the twin's, within four
    // standard errors of the two gaps.
    let (area, _) = measure(SMALL_AREA);
    let gap = |a: &Agreement| (a.gathered.0 - a.reference.0) / a.reference.0;
    let sigma = (lamp.sigma() / lamp.reference.0).hypot(area.sigma() / area.reference.0);
    eprintln!(
        "relative gap of the region means: lamp {:.2e}, area twin {:.2e} (sigma {sigma:.1e})",
        gap(&lamp),
        gap(&area)
    );
    assert!(
        gap(&lamp).abs() <= gap(&area).abs() + 4.0 * sigma,
        "lamp gap {} vs area twin {} (sigma {sigma})",
        gap(&lamp),
        gap(&area)
    );
}

#[test]
fn a_lamp_lying_on_a_surface_puts_no_nan_in_any_image() {
    // The lamp sits exactly on the plane (r = 0 at its foot) and on the blocker's corner.
    let s = plane_under(
        "[[light]]\nkind = \"point\"\nposition = [0, 0, 0]\nintensity = 1e6\n\
         [[light]]\nkind = \"spot\"\nposition = [-0.25, 0.5, -0.25]\ndirection = [0, -1, 0]\nintensity = 1e6\n",
        true,
    );
    let solution = solve(&s, 0.25);
    for v in solution.vertex_radiosity() {
        assert!(v.is_finite(), "{v}");
    }
    let integrators: Vec<Box<dyn twopass_trace::Integrator>> = vec![
        Box::new(Reference::new(&s, ReferenceSettings::default())),
        Box::new(twopass_trace::hybrid::gathered(
            &s,
            &solution,
            WhittedSettings::default(),
        )),
        Box::new(twopass_trace::Whitted::new(
            &s,
            Vec3::ZERO,
            WhittedSettings::default(),
        )),
    ];
    for integrator in &integrators {
        let out = render(
            &s,
            &s.camera,
            integrator.as_ref(),
            &settings(4, 1),
            &RenderProgress::new(),
        );
        assert_eq!(out.stats.non_finite, 0, "{}", integrator.name());
        for layer in [Layer::Diffuse, Layer::Emission] {
            assert!(
                out.layers
                    .layer(layer)
                    .pixels()
                    .iter()
                    .all(|p| p.is_finite()),
                "{}",
                integrator.name()
            );
        }
    }
}

#[test]
fn lamps_render_the_same_on_one_and_two_threads() {
    let s = lamp_box(POINT_LAMP);
    let camera = s.camera.with_resolution(Some(16), Some(16));
    let image = || {
        let r = Reference::new(&s, ReferenceSettings::default());
        render(&s, &camera, &r, &settings(16, 9), &RenderProgress::new())
            .layers
            .composite()
    };
    let one = crate::on_threads(1, image);
    let two = crate::on_threads(2, image);
    assert!(one.pixels() == two.pixels());
}
