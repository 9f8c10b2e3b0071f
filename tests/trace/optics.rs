//! The Whitted tracer against exact optics: a mirror shows the mirrored scene pixel for pixel;
//! a glass slab transmits (1 - R) / (1 + R) of what is behind it, R the exact Fresnel
//! reflectance at each ray's incidence (both interfaces and every internal reflection). That
//! rays leaving a surface never hit it again is `accel::spawned_rays_never_rehit_their_own_surface`.

use glam::{Vec2, Vec3};
use twopass_trace::{Layer, RenderProgress, RenderSettings, Whitted, WhittedSettings, render};

use super::common::scene;

const PATTERN: &str = "[[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
    [[object]]\nname = \"a\"\nmaterial = \"black\"\nemission = [3, 1, 0.5]\n\
    shape = { type = \"quad\", origin = [0.23, 0.17, 2.8], edge_u = [0, 0.43, 0], edge_v = [0.51, 0, 0] }\n\
    [[object]]\nname = \"b\"\nmaterial = \"black\"\nemission = [0.2, 2, 0.7]\n\
    shape = { type = \"quad\", origin = [-0.87, 0.11, 2.7], edge_u = [0, 0.37, 0], edge_v = [0.47, 0, 0] }\n\
    [[object]]\nname = \"c\"\nmaterial = \"black\"\nemission = [0.4, 0.3, 5]\n\
    shape = { type = \"quad\", origin = [-0.13, -0.91, 2.75], edge_u = [0, 0.53, 0], edge_v = [0.61, 0, 0] }\n";

fn centres() -> RenderSettings {
    RenderSettings {
        samples_per_pixel: 1,
        seed: 1,
        jitter: false,
        tile_size: 8,
        adaptive: None,
    }
}

#[test]
fn mirror_shows_the_mirrored_scene_pixel_for_pixel() {
    // Camera A looks at a mirror (plane z = 0, reflectance 0.8) with emitters behind and
    // beside the camera, outside its direct view; camera B is A mirrored in the plane and sees
    // the same emitters directly (no mirror). A mirrored camera has its image flipped.
    let with_mirror = scene(&format!(
        "version = 1\n[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [32, 32]\n\
         [[material]]\nname = \"mirror\"\ntype = \"mirror\"\nreflectance = 0.8\n\
         [[object]]\nname = \"mirror\"\nmaterial = \"mirror\"\n\
         shape = {{ type = \"quad\", origin = [-2, -2, 0], edge_u = [4, 0, 0], edge_v = [0, 4, 0] }}\n{PATTERN}"
    ));
    let direct = scene(&format!(
        "version = 1\n[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [32, 32]\n{PATTERN}"
    ));
    let w = Whitted::new(&with_mirror, Vec3::ZERO, WhittedSettings::default());
    let a = render(
        &with_mirror,
        &with_mirror.camera,
        &w,
        &centres(),
        &RenderProgress::new(),
    );
    let b = render(
        &direct,
        &direct.camera,
        &w,
        &centres(),
        &RenderProgress::new(),
    );
    let (ra, eb) = (
        a.layers.layer(Layer::Reflection),
        b.layers.layer(Layer::Emission),
    );
    assert_eq!(a.layers.layer(Layer::Emission).mean(), Vec3::ZERO);
    let mut lit = 0;
    for y in 0..32 {
        for x in 0..32 {
            let seen = ra.get(x, y);
            let want = eb.get(31 - x, y) * 0.8;
            assert!(
                seen.abs_diff_eq(want, 1e-6 * want.max_element().max(1.0)),
                "pixel ({x}, {y}): {seen} in the mirror, {want} mirrored"
            );
            lit += usize::from(want.max_element() > 0.0);
        }
    }
    assert!(lit > 40, "the pattern is visible: {lit} pixels");
}

#[test]
fn glass_slab_transmits_per_exact_fresnel() {
    let s = scene(
        "version = 1\n[camera]\nposition = [0.05, 0.02, 3]\nlook_at = [0, 0, 0]\nfov_y = 20\nresolution = [16, 16]\n\
         [[material]]\nname = \"glass\"\ntype = \"dielectric\"\nior = 1.5\n\
         [[material]]\nname = \"black\"\ntype = \"lambert\"\ndiffuse = 0\n\
         [[object]]\nname = \"slab\"\nmaterial = \"glass\"\nshape = { type = \"box\", min = [-1, -1, -0.1], max = [1, 1, 0.1] }\n\
         [[object]]\nname = \"light\"\nmaterial = \"black\"\nemission = 1\n\
         shape = { type = \"quad\", origin = [-3, -3, -2], edge_u = [6, 0, 0], edge_v = [0, 6, 0] }\n",
    );
    // Follow internal reflections until they carry less than 1e-9: the truncation error is
    // then far below the tolerance.
    let w = Whitted::new(
        &s,
        Vec3::ZERO,
        WhittedSettings {
            max_depth: 32,
            min_throughput: 1e-9,
            shadow_grid: 1,
            ..WhittedSettings::default()
        },
    );
    let out = render(&s, &s.camera, &w, &centres(), &RenderProgress::new());
    let t = out.layers.layer(Layer::Refraction);
    for y in 0..16 {
        for x in 0..16 {
            let d = s
                .camera
                .direction(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let r = twopass_brdf::fresnel::dielectric(d.z.abs(), 1.5);
            let want = (1.0 - r) / (1.0 + r);
            let got = t.get(x, y);
            assert!(
                got.abs_diff_eq(Vec3::splat(want), 2e-5),
                "pixel ({x}, {y}): {got}, exact {want} (R = {r})"
            );
        }
    }
    // Normal incidence, index 1.5: R = 0.04, T = 0.96 / 1.04.
    assert!((twopass_brdf::fresnel::dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    // Nothing reflected toward the camera comes back: the scene behind the camera is empty.
    assert_eq!(out.layers.layer(Layer::Reflection).mean(), Vec3::ZERO);
}
