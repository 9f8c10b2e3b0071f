//! The BVH answers exactly what testing every triangle answers; spawned rays never re-hit their
//! own surface; rays cannot slip between the triangles of a closed mesh.

use glam::{Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;
use twopass_scene::workload::{self, rng};
use twopass_scene::{Accel, Ray, Scene, load, load_toml};

use crate::scene_path;

/// A uniform point in [0, 1)^2, x drawn first.
fn random_vec2(r: &mut Pcg64Mcg) -> Vec2 {
    let x = r.random::<f32>();
    Vec2::new(x, r.random::<f32>())
}

/// Random directions, uniform on the sphere.
fn random_dir(r: &mut Pcg64Mcg) -> Vec3 {
    let z = 2.0 * r.random::<f32>() - 1.0;
    let phi = std::f32::consts::TAU * r.random::<f32>();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// A uniform random point in the box from `lo` to `hi` (x, y, z drawn in that order).
fn point_in(lo: Vec3, hi: Vec3, r: &mut Pcg64Mcg) -> Vec3 {
    let (x, y) = (r.random::<f32>(), r.random::<f32>());
    lo + (hi - lo) * Vec3::new(x, y, r.random::<f32>())
}

/// Rays of every awkward kind: random in the bounds, leaving surfaces, and aimed exactly at
/// shared vertices and edge midpoints.
fn awkward_rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let mut r = rng(seed);
    let (lo, hi) = (scene.bounds.min, scene.bounds.max);
    let mut rays: Vec<Ray> = (0..n)
        .map(|_| {
            let o = point_in(lo, hi, &mut r);
            Ray::new(o, random_dir(&mut r))
        })
        .collect();
    rays.extend(workload::incoherent_rays(scene, n, seed + 1));
    rays.extend(workload::camera_rays(scene).into_iter().step_by(97));
    // Axis-aligned rays, with negative zeros in their other components (as `-Vec3::Z` has).
    for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        for _ in 0..n / 20 {
            rays.push(Ray::new(point_in(lo, hi, &mut r), axis));
        }
    }
    let m = &scene.mesh;
    for _ in 0..n {
        let t = m.triangle(r.random_range(0..m.triangle_count() as u32));
        let [a, b] = [t[0], t[1]].map(|i| m.position(i));
        let target = if r.random::<bool>() { a } else { (a + b) * 0.5 };
        let o = point_in(lo, hi, &mut r);
        if (target - o).length() > 1e-3 {
            rays.push(Ray::new(o, (target - o).normalize()));
        }
    }
    rays
}

fn assert_bvh_equals_brute_force(scene: &Scene, rays: &[Ray]) {
    let m = &scene.mesh;
    let (positions, triangles) = m.flattened();
    for ray in rays {
        let fast = scene.accel().closest(ray.origin, ray.direction, ray.t_max);
        let slow = Accel::closest_brute_force(
            &positions,
            &triangles,
            ray.origin,
            ray.direction,
            ray.t_max,
        );
        match (fast, slow) {
            (None, None) => {}
            (Some(f), Some(s)) => {
                // Same distance to the last bit but for ties between triangles sharing the point.
                assert!(
                    f.t == s.t || (f.t - s.t).abs() <= 1e-6 * s.t,
                    "{ray:?}: bvh t {} vs {}",
                    f.t,
                    s.t
                );
                if f.triangle != s.triangle {
                    // A tie at a shared edge or vertex: the BVH's triangle is hit there too.
                    let own = [m.triangle(f.triangle)];
                    let alone = Accel::closest_brute_force(
                        &positions,
                        &own,
                        ray.origin,
                        ray.direction,
                        ray.t_max,
                    );
                    assert!(
                        alone.is_some_and(|a| (a.t - s.t).abs() <= 1e-6 * s.t),
                        "{ray:?}: {f:?} is no tie with {s:?}"
                    );
                }
            }
            (f, s) => panic!("{ray:?}: bvh {f:?} vs brute force {s:?}"),
        }
        // Occlusion agrees with the closest hit.
        let blocked = scene.accel().any_hit(ray.origin, ray.direction, ray.t_max);
        assert_eq!(blocked, slow.is_some(), "{ray:?}");
        if let Some(s) = slow {
            assert!(
                !scene
                    .accel()
                    .any_hit(ray.origin, ray.direction, s.t * (1.0 - 1e-4))
                    || s.t < 1e-3
            );
        }
    }
}

#[test]
fn bvh_equals_brute_force_on_the_cornell_scenes() {
    for name in [
        "cornell-box.toml",
        "cornell-spheres.toml",
        "cornell-materials.toml",
    ] {
        let (scene, _) = load(scene_path(name)).unwrap();
        assert_bvh_equals_brute_force(&scene, &awkward_rays(&scene, 700, 7));
    }
}

#[test]
fn bvh_equals_brute_force_on_a_generated_scene() {
    let (scene, _) = workload::synthetic_scene(30_000, 3).unwrap();
    assert!(scene.mesh.triangle_count() >= 30_000);
    // The room's walls face in, so rays leaving them stay inside but for the open front.
    let centre = scene.bounds.center();
    for o in scene
        .objects
        .iter()
        .filter(|o| !o.name.starts_with("sphere"))
    {
        let t = o.triangles.start as usize;
        let p = scene.mesh.position(scene.mesh.triangle(t as u32)[0]);
        assert!(
            scene.mesh.geometric_normal(t as u32).dot(centre - p) > 0.0,
            "{} faces out",
            o.name
        );
    }
    assert_bvh_equals_brute_force(&scene, &awkward_rays(&scene, 150, 11));
}

#[test]
fn spawned_rays_never_rehit_their_own_surface() {
    let (scene, _) = load(scene_path("cornell-spheres.toml")).unwrap();
    let m = &scene.mesh;
    let mut r = rng(5);
    let coplanar = |a: u32, b: u32| {
        let (na, nb) = (m.geometric_normal(a), m.geometric_normal(b));
        let (pa, pb) = (m.corners(a)[0], m.corners(b)[0]);
        na.dot(nb).abs() > 1.0 - 1e-6 && (na.dot(pb - pa)).abs() < 1e-3
    };
    for i in 0..20_000 {
        let t = r.random_range(0..m.triangle_count() as u32);
        let p = m.sample_triangle(t, random_vec2(&mut r));
        // Both sides, including directions within a hair of the surface.
        let mut d = random_dir(&mut r);
        if i % 4 == 0 {
            d = (d - p.normal * d.dot(p.normal) * 0.999_99).normalize();
        }
        if let Some(hit) = scene.intersect_from(&p, d) {
            assert!(
                hit.point.triangle != t,
                "ray {i} re-hit its own triangle {t} at t = {}",
                hit.t
            );
            assert!(
                !coplanar(hit.point.triangle, t),
                "ray {i} hit a coplanar neighbour at t = {}",
                hit.t
            );
        }
        // A point on a surface sees itself unoccluded.
        let q = m.sample_triangle(t, random_vec2(&mut r));
        assert!(
            !scene.occluded_between(&p, &q),
            "ray {i}: point to point on one triangle {t} is occluded"
        );
    }
}

/// Centre of [`icosphere_targets`]'s sphere.
const SPHERE_CENTRE: Vec3 = Vec3::new(0.1, -0.2, 0.3);

/// A scene of one icosphere (radius 1.7 about [`SPHERE_CENTRE`], `subdivisions` deep), and the
/// points where its triangles meet: every vertex and every edge midpoint. An icosphere has
/// shared vertices and edges everywhere; rays aimed exactly at them find any gap.
fn icosphere_targets(subdivisions: u32) -> (Scene, Vec<Vec3>) {
    let text = format!(
        "version = 1\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
         [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"s\"\nmaterial = \"w\"\nshape = {{ type = \"sphere\", \
         center = [0.1, -0.2, 0.3], radius = 1.7, subdivisions = {subdivisions} }}\n"
    );
    let (scene, _) = load_toml(&text, std::path::Path::new("sphere.toml")).unwrap();
    let m = &scene.mesh;
    let mut targets: Vec<Vec3> = m.positions().collect();
    for t in m.triangles() {
        for k in 0..3 {
            targets.push((m.position(t[k]) + m.position(t[(k + 1) % 3])) * 0.5);
        }
    }
    (scene, targets)
}

#[test]
fn rays_from_inside_a_closed_mesh_never_escape() {
    let (scene, targets) = icosphere_targets(4);
    let mut r = rng(9);
    for (i, target) in targets.iter().enumerate() {
        let o = SPHERE_CENTRE + random_dir(&mut r) * r.random::<f32>() * 0.5;
        let d = (*target - o).normalize();
        assert!(
            scene.intersect(&Ray::new(o, d)).is_some(),
            "ray {i} to {target} escaped"
        );
    }
}

#[test]
fn batch_queries_equal_single_queries() {
    let (scene, _) = load(scene_path("cornell-box.toml")).unwrap();
    let rays = workload::incoherent_rays(&scene, 5000, 1);
    let batch = scene.intersect_batch(&rays);
    for (ray, b) in rays.iter().zip(&batch) {
        assert_eq!(*b, scene.intersect(ray));
    }
    let pairs = workload::occlusion_pairs(&scene, 5000, 2);
    let blocked = scene.occluded_batch(&pairs);
    for ((a, b), o) in pairs.iter().zip(&blocked) {
        assert_eq!(*o, scene.occluded_between(a, b));
    }
    // Some pairs are blocked by the blocks, most see the light.
    let n = blocked.iter().filter(|&&b| b).count();
    assert!(
        n > 0 && n < pairs.len() / 2,
        "{n} of {} blocked",
        pairs.len()
    );
}

/// A point strictly inside scene triangle `t` (every barycentric at least 0.05): away from the
/// triangle's edges and so from any crease.
fn interior_point(scene: &Scene, t: u32, r: &mut Pcg64Mcg) -> twopass_scene::SurfacePoint {
    let (a, b) = (0.1 + 0.8 * r.random::<f32>(), r.random::<f32>());
    let (b1, b2) = (a * (1.0 - b) * 0.875 + 0.05, a * b * 0.875 + 0.05);
    scene.mesh.surface_point(t, [1.0 - b1 - b2, b1, b2])
}

/// The scenes the shaft tests run on: the two Cornell scenes and a generated room.
fn shaft_scenes() -> Vec<Scene> {
    let mut scenes: Vec<Scene> = ["cornell-box.toml", "cornell-spheres.toml"]
        .iter()
        .map(|n| load(scene_path(n)).unwrap().0)
        .collect();
    scenes.push(workload::synthetic_scene(10_000, 5).unwrap().0);
    scenes
}

/// A shaft test must clear a fair share of the pairs and keep others (it is neither "never
/// clear" nor "always clear").
fn fair_share(scene: usize, clear: u32, pairs: u32) {
    let share = f64::from(clear) / f64::from(pairs);
    println!("scene {scene}: {clear} of {pairs} pairs cleared");
    assert!(
        (0.05..0.95).contains(&share),
        "scene {scene}: {clear} of {pairs} pairs cleared"
    );
}

/// A uniform point of triangle `p`.
fn point_in_triangle(p: [Vec3; 3], r: &mut Pcg64Mcg) -> Vec3 {
    let (u, v) = (r.random::<f32>(), r.random::<f32>());
    let (u, v) = if u + v > 1.0 {
        (1.0 - u, 1.0 - v)
    } else {
        (u, v)
    };
    p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v
}

/// Whenever the shaft test says nothing can come between a point and a triangle, no segment
/// between them is blocked: 64 shadow rays per cleared pair, on the Cornell scenes and a
/// generated room, from points and to triangles strictly inside scene triangles. The test must
/// also clear a fair share of the pairs and keep others (it is not "never clear").
#[test]
fn shaft_clear_never_hides_a_blocker() {
    for (k, scene) in shaft_scenes().iter().enumerate() {
        let mut r = rng(40 + k as u64);
        let n = scene.mesh.triangle_count() as u32;
        let (mut clear, mut pairs) = (0, 0);
        for _ in 0..4000 {
            let from = interior_point(scene, r.random_range(0..n), &mut r);
            let t = r.random_range(0..n);
            let base = [0, 1, 2].map(|_| interior_point(scene, t, &mut r).position);
            let centre = (base[0] + base[1] + base[2]) / 3.0;
            if t == from.triangle || (centre - from.position).dot(from.normal) <= 0.0 {
                continue;
            }
            pairs += 1;
            if !scene
                .accel()
                .shaft_clear(from.position, Some(from.normal), base)
            {
                continue;
            }
            clear += 1;
            for _ in 0..64 {
                let p = point_in_triangle(base, &mut r);
                let to = scene.mesh.surface_point_at(t, p);
                assert!(
                    !scene.occluded_between(&from, &to),
                    "scene {k}: shaft from {:?} (triangle {}) to triangle {t} {base:?} said clear, \
                     but the segment to {p:?} is blocked",
                    from.position,
                    from.triangle
                );
            }
        }
        fair_share(k, clear, pairs);
    }
}

/// Whenever the shaft test between two triangles says nothing can come between them, no
/// segment between them is blocked: 64 shadow rays per cleared pair between points strictly
/// inside both, on the Cornell scenes and a generated room. Each triangle is a random part of a
/// scene triangle, as patches are. The test must also clear a fair share of the pairs and keep
/// others.
#[test]
fn shaft_clear_between_never_hides_a_blocker() {
    for (k, scene) in shaft_scenes().iter().enumerate() {
        let mut r = rng(70 + k as u64);
        let n = scene.mesh.triangle_count() as u32;
        let (mut clear, mut pairs) = (0, 0);
        for _ in 0..3000 {
            let (s, t) = (r.random_range(0..n), r.random_range(0..n));
            let part =
                |t: u32, r: &mut Pcg64Mcg| [0, 1, 2].map(|_| interior_point(scene, t, r).position);
            let (a, b) = (part(s, &mut r), part(t, &mut r));
            let (na, nb) = (
                scene.mesh.geometric_normal(s),
                scene.mesh.geometric_normal(t),
            );
            let centre = |p: [Vec3; 3]| (p[0] + p[1] + p[2]) / 3.0;
            if s == t || (centre(b) - centre(a)).dot(na) <= 0.0 {
                continue;
            }
            pairs += 1;
            if !scene.accel().shaft_clear_between(a, na, b, nb) {
                continue;
            }
            clear += 1;
            for _ in 0..64 {
                let mut point = |p: [Vec3; 3], t: u32| {
                    scene.mesh.surface_point_at(t, point_in_triangle(p, &mut r))
                };
                let (from, to) = (point(a, s), point(b, t));
                assert!(
                    !scene.occluded_between(&from, &to),
                    "scene {k}: triangles {s} {a:?} and {t} {b:?} said clear, but the segment \
                     from {:?} to {:?} is blocked",
                    from.position,
                    to.position
                );
            }
        }
        fair_share(k, clear, pairs);
    }
}

/// Two unit squares facing each other one unit apart: clear; a small square between them on
/// the axis blocks the shaft from the centre; moved well to the side, it does not; lying in
/// the receiver's own plane (beside it), it cannot block.
#[test]
fn shaft_clear_between_facing_squares() {
    let quad = |name: &str, origin: [f32; 3], u: [f32; 3], v: [f32; 3]| {
        format!(
            "[[object]]\nname = \"{name}\"\nmaterial = \"w\"\nshape = {{ type = \"quad\", origin = {origin:?}, edge_u = {u:?}, edge_v = {v:?} }}\n"
        )
    };
    let room = |extra: &str| {
        let text = format!(
            "version = 1\n[camera]\nposition = [0.5, 0.5, -3]\nlook_at = [0.5, 0.5, 0]\nfov_y = 40\n\
             [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n{}{}{extra}",
            quad("bottom", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
            quad("top", [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        );
        load_toml(&text, std::path::Path::new("squares.toml"))
            .unwrap()
            .0
    };
    let apex = Vec3::new(0.5, 0.0, 0.5);
    let up = Vec3::Y;
    let top = [
        Vec3::new(0.2, 1.0, 0.2),
        Vec3::new(0.8, 1.0, 0.2),
        Vec3::new(0.5, 1.0, 0.8),
    ];
    let clear = |scene: &Scene| scene.accel().shaft_clear(apex, Some(up), top);
    assert!(clear(&room("")));
    let on_axis = quad("b", [0.45, 0.5, 0.45], [0.1, 0.0, 0.0], [0.0, 0.0, 0.1]);
    assert!(!clear(&room(&on_axis)));
    let aside = quad("b", [2.0, 0.5, 0.45], [0.1, 0.0, 0.0], [0.0, 0.0, 0.1]);
    assert!(clear(&room(&aside)));
    let in_plane = quad("b", [-1.0, 0.0, 0.2], [0.0, 0.0, 0.5], [0.9, 0.0, 0.0]);
    assert!(clear(&room(&in_plane)));
}

/// Rays from far outside the scene, aimed exactly at a closed mesh's vertices and edge
/// midpoints (a long lens on a small object): the box test's rounding grows with the ray's
/// origin, not only with the scene's size, and must still never cull the triangles met there.
/// Every such ray hits, and hits what testing every triangle hits.
#[test]
fn rays_from_far_away_hit_what_they_aim_at() {
    let (scene, targets) = icosphere_targets(3);
    let mut r = rng(17);
    for distance in [1e2f32, 1e3, 1e4, 1e5] {
        let mut rays = Vec::new();
        for target in &targets {
            // From the side the target faces, so the ray meets the sphere there first.
            let out = (*target - SPHERE_CENTRE).normalize();
            let o = *target + (out + random_dir(&mut r) * 0.5).normalize() * distance;
            rays.push(Ray::new(o, *target - o));
        }
        for (i, ray) in rays.iter().enumerate() {
            assert!(
                scene
                    .accel()
                    .closest(ray.origin, ray.direction, ray.t_max)
                    .is_some(),
                "from {distance}: ray {i} {ray:?} missed"
            );
        }
        assert_bvh_equals_brute_force(&scene, &rays);
    }
}
