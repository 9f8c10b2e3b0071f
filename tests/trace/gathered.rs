//! The gathered hybrid (`twopass_trace::hybrid::gathered`: direct light by shadow rays and a
//! final gather over the solution per camera sample) against closed forms and the path tracer:
//! the furnace reads L_e / (1 - rho) exactly in expectation; the pixels seen through the glass
//! sphere of the Cornell spheres and the floor along a box's contact agree with the reference
//! within the two renders' own noise (along the contact the classic hybrid, which shows the
//! solution there, does not); the per-pixel caustics and the gather rays count the light
//! focused by glass once; no NaN or infinity reaches the image even from a solution that holds some.

use std::ops::ControlFlow;

use twopass_brdf::Rgb;
use twopass_image::Image;
use twopass_scene::{Camera, DiffuseRadiance, Ray, Scene};
use twopass_trace::hybrid::{DirectLight, gathered, hybrid};
use twopass_trace::{
    Integrator, Reference, ReferenceSettings, RenderOutput, RenderProgress, RenderSettings,
    WhittedSettings, render,
};

use super::common::{mean_and_error, repo_scene, scene};

/// A solution of radiance `value` everywhere (indirect part: half of it).
struct Uniform(Rgb);

impl DiffuseRadiance for Uniform {
    fn radiance(&self, _: u32, _: [f32; 3]) -> Rgb {
        self.0
    }
    fn indirect_radiance(&self, _: u32, _: [f32; 3]) -> Rgb {
        self.0 * 0.5
    }
}

fn settings(spp: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: spp,
        seed,
        ..RenderSettings::default()
    }
}

fn run(
    scene: &Scene,
    camera: &Camera,
    integrator: &dyn Integrator,
    spp: u32,
    seed: u64,
) -> RenderOutput {
    render(
        scene,
        camera,
        integrator,
        &settings(spp, seed),
        &RenderProgress::new(),
    )
}

/// A converged-enough solve of `scene` with elements of `element_size` (scene units).
pub(super) fn solve(scene: &Scene, element_size: f32) -> twopass_radiosity::Solution {
    solve_with(scene, element_size, twopass_radiosity::Method::Auto)
}

/// [`solve`] by `method`.
fn solve_with(
    scene: &Scene,
    element_size: f32,
    method: twopass_radiosity::Method,
) -> twopass_radiosity::Solution {
    let options = twopass_radiosity::Options {
        method,
        element_size: Some(element_size),
        stop: twopass_radiosity::Stop {
            unshot_fraction: 1e-3,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut solver = twopass_radiosity::Solver::new(scene, options).unwrap();
    solver.run(|_| ControlFlow::Continue(()));
    solver.solution()
}

/// The pixels whose centre's camera ray satisfies `keep` at its first hit.
pub(super) fn pixels_where(
    scene: &Scene,
    camera: &Camera,
    keep: impl Fn(&twopass_scene::Hit) -> bool,
) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for y in 0..camera.height {
        for x in 0..camera.width {
            let p = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = Ray::new(camera.position, camera.direction(p));
            if scene.intersect(&ray).is_some_and(|h| keep(&h)) {
                out.push((x, y));
            }
        }
    }
    out
}

/// Mean luminance-like sum of the channels over `pixels`.
fn region_mean(image: &Image, pixels: &[(u32, u32)]) -> f64 {
    let sum: f64 = pixels
        .iter()
        .map(|&(x, y)| f64::from(image.get(x, y).element_sum()) / 3.0)
        .sum();
    sum / pixels.len() as f64
}

/// The region mean of two independent renders, and the standard error of one of them (two
/// estimates differing by d have each an error of about |d| / sqrt(2); the larger of that and
/// the spread of the per-pixel differences over the region, which is a steadier estimate).
fn mean_and_noise(a: &Image, b: &Image, pixels: &[(u32, u32)]) -> (f64, f64) {
    let diffs: Vec<f64> = pixels
        .iter()
        .map(|&(x, y)| f64::from(a.get(x, y).element_sum() - b.get(x, y).element_sum()) / 3.0)
        .collect();
    // The region mean of the difference has the standard error of the mean of `diffs`; each
    // render's region mean has 1 / sqrt(2) of it.
    let (_, err) = mean_and_error(&diffs);
    let mean = 0.5 * (region_mean(a, pixels) + region_mean(b, pixels));
    (mean, err / std::f64::consts::SQRT_2)
}

/// Per pixel of `pixels`, the squared difference of the means of two renders `a` and two
/// references `r`, over what the four renders' noise alone gives it (estimated from the
/// differences within each pair): about 1 when the image agrees with the reference pixel by
/// pixel, more where it errs.
fn excess(a: [&Image; 2], r: [&Image; 2], pixels: &[(u32, u32)]) -> f64 {
    let v = |img: &Image, x, y| f64::from(img.get(x, y).element_sum()) / 3.0;
    let (mut diff, mut noise) = (0.0, 0.0);
    for &(x, y) in pixels {
        let (a0, a1, r0, r1) = (v(a[0], x, y), v(a[1], x, y), v(r[0], x, y), v(r[1], x, y));
        diff += (0.5 * (a0 + a1) - 0.5 * (r0 + r1)).powi(2);
        // Var(mean of two) = E[(x0 - x1)^2] / 4 for each pair.
        noise += 0.25 * ((a0 - a1).powi(2) + (r0 - r1).powi(2));
    }
    diff / noise
}

#[test]
fn gathered_furnace_reads_le_over_one_minus_rho() {
    // Every face has albedo 0.5 and emits 0.5: the radiance is 1 everywhere, and a solution
    // that says so gives, per pixel, 0.5 (emission) + 0.5 * 0.5 (shadow rays: E = pi L_e) +
    // 0.5 * (1 - 0.5) (gather rays: the solution less the emission where they land).
    let s = scene(super::furnace::CUBE);
    let solution = Uniform(Rgb::ONE);
    let h = gathered(&s, &solution, WhittedSettings::default());
    let out = run(&s, &s.camera, &h, 4, 5);
    assert_eq!(out.stats.non_finite, 0);
    super::furnace::assert_reads_one(&out.layers.composite(), 0.01);
    assert!(out.stats.shadow_rays > 0 && out.stats.rays > out.stats.samples);
}

#[test]
fn no_nan_or_infinity_reaches_the_image() {
    // A solution holding NaN and infinity on some triangles: the gather rays that read them are
    // dropped, so every sample stays finite and none is lost.
    struct Broken;
    impl DiffuseRadiance for Broken {
        fn radiance(&self, t: u32, _: [f32; 3]) -> Rgb {
            match t % 7 {
                0 => Rgb::splat(f32::NAN),
                1 => Rgb::splat(f32::INFINITY),
                _ => Rgb::splat(0.2),
            }
        }
        fn indirect_radiance(&self, t: u32, b: [f32; 3]) -> Rgb {
            self.radiance(t, b)
        }
    }
    let s = repo_scene("cornell-spheres.toml");
    let camera = s.camera.with_resolution(Some(24), Some(24));
    for solution in [&Broken as &dyn DiffuseRadiance, &Uniform(Rgb::splat(0.1))] {
        let out = run(
            &s,
            &camera,
            &gathered(&s, solution, WhittedSettings::default()),
            4,
            1,
        );
        assert_eq!(out.stats.non_finite, 0);
        for layer in &out.layers.images {
            assert!(layer.pixels().iter().all(|p| p.is_finite()));
        }
    }
}

/// The gathered and the classic hybrid (16 spp, two renders each) and the path tracer (1024
/// spp, two renders) over the pixels `region` of `scene` seen by `camera`.
pub(super) struct Agreement {
    /// The reference's region mean and its standard error.
    pub(super) reference: (f64, f64),
    /// The gathered hybrid's region mean and its standard error.
    pub(super) gathered: (f64, f64),
    /// The classic hybrid's region mean.
    classic: f64,
    /// [`excess`] of the gathered and the classic hybrid.
    pub(super) excess: (f64, f64),
}

impl Agreement {
    pub(super) fn measure(
        s: &Scene,
        camera: &Camera,
        solution: &dyn DiffuseRadiance,
        region: &[(u32, u32)],
        seed: u64,
    ) -> Self {
        let pair = |integrator: &dyn Integrator, spp| {
            [0, 1].map(|i| run(s, camera, integrator, spp, seed + i).layers.composite())
        };
        let r = pair(&Reference::new(s, ReferenceSettings::default()), 1024);
        let h = pair(&gathered(s, solution, WhittedSettings::default()), 16);
        let c = pair(
            &hybrid(
                s,
                solution,
                DirectLight::FromSolution,
                WhittedSettings::default(),
            ),
            16,
        );
        Self {
            reference: mean_and_noise(&r[0], &r[1], region),
            gathered: mean_and_noise(&h[0], &h[1], region),
            classic: 0.5 * (region_mean(&c[0], region) + region_mean(&c[1], region)),
            excess: (
                excess([&h[0], &h[1]], [&r[0], &r[1]], region),
                excess([&c[0], &c[1]], [&r[0], &r[1]], region),
            ),
        }
    }

    /// Asserts that the gathered hybrid agrees with the reference over the region `name` of
    /// `n` pixels: the region means within four standard errors of their difference, and pixel
    /// by pixel: its [`excess`], a ratio of two means of squares over the region that is 1 in
    /// expectation when only noise separates them, within four of its standard deviations
    /// (about sqrt(3 / n): the numerator's relative spread sqrt(2 / n), the denominator's,
    /// from twice as many pair differences, sqrt(1 / n)).
    pub(super) fn assert_agrees(&self, name: &str, n: usize) {
        let ((r, r_noise), (h, h_noise)) = (self.reference, self.gathered);
        eprintln!(
            "{name} ({n} px): reference {r:.5} +- {r_noise:.5}, gathered {h:.5} +- {h_noise:.5}, \
             classic {:.5}; excess gathered {:.3}, classic {:.3}",
            self.classic, self.excess.0, self.excess.1
        );
        let sigma = self.sigma();
        assert!(
            (h - r).abs() < 4.0 * sigma,
            "{name}: gathered {h} vs reference {r} (sigma {sigma})"
        );
        let bound = 1.0 + 4.0 * (3.0 / n as f64).sqrt();
        assert!(
            self.excess.0 < bound,
            "{name}: gathered excess {} over {n} pixels (bound {bound})",
            self.excess.0
        );
    }

    /// The standard error of the difference of the two region means.
    pub(super) fn sigma(&self) -> f64 {
        self.reference.1.hypot(self.gathered.1)
    }
}

#[test]
fn pixels_seen_through_the_glass_sphere_match_the_path_tracer() {
    let s = repo_scene("cornell-spheres.toml");
    let camera = s.camera.with_resolution(Some(48), Some(48));
    let glass = pixels_where(&s, &camera, |h| {
        s.materials[h.material as usize].material.is_dielectric()
    });
    assert!(glass.len() > 50, "{} glass pixels", glass.len());
    let solution = solve(&s, s.bounds.diagonal() / 24.0);
    Agreement::measure(&s, &camera, &solution, &glass, 11)
        .assert_agrees("glass sphere", glass.len());
}

/// A 1 m grey box standing on a 6 m grey floor under a 1 m square light 2.5 m up, seen from
/// the side the light leans to: the floor strip along the box's foot.
const CONTACT: &str = "version = 1\n\
    [camera]\nposition = [0.3, 2.2, 3.2]\nlook_at = [0.3, 0.2, 0.5]\nfov_y = 50\nresolution = [48, 48]\n\
    [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.7\n\
    [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
    shape = { type = \"quad\", origin = [-3, 0, -3], edge_u = [0, 0, 6], edge_v = [6, 0, 0] }\n\
    [[object]]\nname = \"box\"\nmaterial = \"grey\"\n\
    shape = { type = \"box\", min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }\n\
    [[object]]\nname = \"light\"\nmaterial = \"grey\"\nemission = 8\n\
    shape = { type = \"quad\", origin = [0, 2.5, 0.5], edge_u = [1, 0, 0], edge_v = [0, 0, 1] }\n";

#[test]
fn the_floor_along_a_contact_matches_the_path_tracer() {
    let s = scene(CONTACT);
    let camera = s.camera;
    // Floor pixels within 0.15 m of the box's front face (z = 0.5), beside it.
    let strip = pixels_where(&s, &camera, |h| {
        let p = h.point.position;
        h.object == 0 && p.z > 0.5 && p.z < 0.65 && p.x.abs() < 0.45
    });
    assert!(strip.len() > 20, "{} strip pixels", strip.len());
    // A coarse solve: elements of 0.4 m straddle the contact. The hierarchical solver spreads
    // a link's blocked share over the whole receiver, so its floor elements under the box
    // darken the strip beside it.
    let solution = solve_with(&s, 0.4, twopass_radiosity::Method::Hierarchical);
    let a = Agreement::measure(&s, &camera, &solution, &strip, 21);
    a.assert_agrees("contact strip", strip.len());
    let (r, sigma) = (a.reference.0, a.sigma());
    // The test sees the leak: the classic hybrid shows the coarse solution there.
    assert!(a.excess.1 > 100.0, "classic excess {}", a.excess.1);
    assert!(a.classic < r - 20.0 * sigma, "classic {} vs {r}", a.classic);
    // Progressive refinement shoots each patch's light from its visible area and shows the
    // vertices under the box with their neighbours' light: its solution alone is within 3 %
    // there (16 % dark when the patches spread their light over the part under the box).
    let solution = solve_with(&s, 0.4, twopass_radiosity::Method::Progressive);
    let p = Agreement::measure(&s, &camera, &solution, &strip, 21);
    p.assert_agrees("contact strip, progressive", strip.len());
    assert!(
        (p.classic - r).abs() < 0.03 * r,
        "progressive classic {} vs {r}",
        p.classic
    );
}

#[test]
fn caustics_are_counted_once() {
    // Where the camera sees the floor lit through the glass sphere, the gathered hybrid leaves
    // that light to the light tracer (caustic_paths > 0) or finds it with its own gather rays
    // through the glass (caustic_paths = 0): one or the other, never both, so the region's
    // mean is the same either way within the renders' noise.
    let s = repo_scene("cornell-spheres.toml");
    let camera = s.camera.with_resolution(Some(48), Some(48));
    // The caustic on the floor to the camera's right of the glass sphere's foot (the region of
    // docs/benchmarks.md's specular-transfer figures, as fractions of the image).
    let region: Vec<(u32, u32)> = (0..camera.height)
        .flat_map(|y| (0..camera.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let (fx, fy) = (x as f32 / 48.0, y as f32 / 48.0);
            (150.0 / 256.0..186.0 / 256.0).contains(&fx)
                && (222.0 / 256.0..238.0 / 256.0).contains(&fy)
        })
        .collect();
    let solution = solve(&s, s.bounds.diagonal() / 24.0);
    let mean = |paths: f32, seed| {
        let g = gathered(
            &s,
            &solution,
            WhittedSettings {
                caustic_paths: paths,
                ..WhittedSettings::default()
            },
        );
        let pair = [0u64, 1].map(|i| run(&s, &camera, &g, 64, seed + i));
        assert_eq!(pair[0].stats.light_paths > 0, paths > 0.0);
        let [a, b] = pair.map(|o| o.layers.composite());
        mean_and_noise(&a, &b, &region)
    };
    let (light_traced, e1) = mean(4.0, 31);
    let (gathered_only, e2) = mean(0.0, 33);
    let sigma = e1.hypot(e2);
    eprintln!(
        "caustic ({} px): light-traced {light_traced:.5} +- {e1:.5}, gathered {gathered_only:.5} +- {e2:.5}",
        region.len()
    );
    assert!(
        (light_traced - gathered_only).abs() < 4.0 * sigma,
        "{light_traced} vs {gathered_only} (sigma {sigma})"
    );
}
