//! Instancing: a glTF mesh that several nodes show is stored once and placed again
//! ([`twopass_scene::Repeat`]). Every consumer must see the same scene as when each node has
//! its own copy of the mesh: the same triangles, the same ray answers, the same solve.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use twopass_radiosity::{Method, Options, Solver};
use twopass_scene::{DiffuseRadiance, Scene, load};
use twopass_tests::gltf::{GltfWriter, MaterialSpec, Trs};
use twopass_tests::instancing::{boxes_room, placements, turn, unit_box};

fn pair(copies: usize) -> (tempfile::TempDir, Scene, Scene) {
    let dir = tempfile::tempdir().unwrap();
    let (shared, w1) = load(boxes_room(dir.path(), copies, true)).unwrap();
    let (copied, w2) = load(boxes_room(dir.path(), copies, false)).unwrap();
    assert!(w1.is_empty() && w2.is_empty(), "{w1:?} {w2:?}");
    (dir, shared, copied)
}

fn close(a: Vec3, b: Vec3, scale: f32) -> bool {
    (a - b).abs().max_element() <= 1e-5 * scale
}

#[test]
fn placed_copies_are_the_triangles_of_copied_meshes() {
    let (_dir, shared, copied) = pair(20);
    let (s, c) = (&shared.mesh, &copied.mesh);
    // 2 + 2 floor and light triangles, one stored box of 12.
    assert_eq!(s.stored_triangle_count(), 16);
    assert_eq!(s.repeats().len(), 19);
    assert_eq!(c.stored_triangle_count(), 4 + 20 * 12);
    assert_eq!(s.triangle_count(), c.triangle_count());
    assert_eq!(s.vertex_count(), c.vertex_count());
    assert_eq!(shared.objects, copied.objects);
    for t in 0..s.triangle_count() as u32 {
        assert_eq!(s.triangle(t), c.triangle(t), "triangle {t}");
        assert_eq!(s.object_of(t), c.object_of(t));
        for (a, b) in s.corners(t).iter().zip(c.corners(t)) {
            assert!(close(*a, b, 10.0), "triangle {t}: {a} vs {b}");
        }
        assert!(close(s.geometric_normal(t), c.geometric_normal(t), 1.0));
        let b = [0.2, 0.3, 0.5];
        assert!(close(s.shading_normal(t, b), c.shading_normal(t, b), 1.0));
        assert!(
            (s.area(t) - c.area(t)).abs() <= 1e-5 * c.area(t),
            "area of {t}"
        );
    }
    assert!((shared.total_area() - copied.total_area()).abs() < 1e-6 * copied.total_area());
    // The mirrored box (i % 7 == 3) keeps its faces outward: its normals point away from its
    // centre, as the copied mesh's do.
    let mirrored = &shared.objects[2 + 3];
    let centre = mirrored
        .vertices
        .clone()
        .map(|v| s.position(v))
        .sum::<Vec3>()
        / 8.0;
    for t in mirrored.triangles.clone() {
        let [a, b, d] = s.corners(t);
        assert!(s.geometric_normal(t).dot((a + b + d) / 3.0 - centre) > 0.0);
    }
}

#[test]
fn rays_find_the_same_hits_in_placed_and_copied_boxes() {
    let (_dir, shared, copied) = pair(20);
    let mut rng = Pcg64::seed_from_u64(7);
    let (mut box_hits, mut blocked) = (0, 0);
    for _ in 0..20_000 {
        let o = Vec3::new(
            rng.random_range(-6.0..6.0),
            rng.random_range(0.01..5.9),
            rng.random_range(-6.0..6.0),
        );
        let d = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let ray = twopass_scene::Ray::new(o, d);
        let (a, b) = (shared.intersect(&ray), copied.intersect(&ray));
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                box_hits += usize::from(b.object >= 2);
                // The same surface: each hit within rounding of the other's plane. Along the
                // ray they may differ more: a ray grazing a face meets it far from its own
                // rounding (here the copy's ray is carried into the source's space).
                let n = b.point.normal;
                let off = (a.point.position - b.point.position).dot(n).abs();
                assert!(off <= 1e-5 * b.t.max(1.0), "{ray:?}: {a:?} {b:?}");
                assert_eq!(a.object, b.object, "{ray:?}: {a:?} {b:?}");
                assert!(close(a.point.normal, n, 1.0));
            }
            _ => panic!("{ray:?}: {a:?} against {b:?}"),
        }
        let end = o + d * rng.random_range(0.5..8.0);
        let (sa, sb) = (
            shared.accel().any_hit(o, end - o, 1.0),
            copied.accel().any_hit(o, end - o, 1.0),
        );
        assert_eq!(sa, sb, "segment {o} -> {end}");
        blocked += usize::from(sa);
    }
    // The rays meet the boxes often enough for the comparison to mean something.
    assert!(
        box_hits > 1_000 && blocked > 1_000,
        "{box_hits} box hits, {blocked} blocked"
    );
}

#[test]
fn rays_leaving_a_placed_copy_do_not_hit_it_again() {
    let (_dir, shared, _) = pair(20);
    let mut rng = Pcg64::seed_from_u64(3);
    let s = &shared.mesh;
    let mut checked = 0;
    for t in 16..s.triangle_count() as u32 {
        for _ in 0..50 {
            let (u, v): (f32, f32) = (rng.random(), rng.random());
            let p = s.sample_triangle(t, glam::Vec2::new(u, v));
            // Straight out and at grazing angles: nothing of its own box is in front.
            let n = p.normal;
            let tangent = n.any_orthonormal_vector();
            for d in [n, (n * 0.02 + tangent).normalize()] {
                let hit = shared.intersect_from(&p, d);
                assert!(
                    hit.is_none_or(
                        |h| s.object_of(h.point.triangle) != s.object_of(t) || h.t > 1e-3
                    ),
                    "triangle {t}: {hit:?}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 10_000);
}

#[test]
fn a_solve_over_placed_copies_is_the_solve_over_copied_meshes() {
    let (_dir, shared, copied) = pair(12);
    for method in [Method::Progressive, Method::Hierarchical] {
        // Elements of 0.37: no box edge is near a multiple of it, where a rounding of the
        // copies' corners could cut a face into another number of elements.
        let options = Options {
            method,
            element_size: Some(0.37),
            ..Options::default()
        };
        let solve = |scene: &Scene| {
            let mut solver = Solver::new(scene, options.clone()).unwrap();
            solver.run(|_| std::ops::ControlFlow::Continue(()));
            solver.check_energy().unwrap();
            (solver.solution(), solver.mesh().leaves().count())
        };
        let ((a, leaves_a), (b, leaves_b)) = (solve(&shared), solve(&copied));
        // Progressive refinement meshes to the element size alone: the same leaves. The
        // hierarchical solver refines where a link's estimated error passes a threshold, and
        // rounding tips a few of those decisions (6 of 1,150 leaves here): each changes the
        // light of the nodes it refines by about the link tolerance.
        let (same, tolerance) = match method {
            Method::Progressive => (leaves_a == leaves_b, 1e-4),
            _ => (leaves_a.abs_diff(leaves_b) * 100 <= leaves_b, 2e-3),
        };
        assert!(same, "{method:?}: {leaves_a} leaves against {leaves_b}");
        let third = [1.0 / 3.0; 3];
        let (mut sum, mut diff) = (0.0f64, 0.0f64);
        for t in 0..shared.mesh.triangle_count() as u32 {
            let (x, y) = (a.radiance(t, third), b.radiance(t, third));
            let area = f64::from(shared.mesh.area(t));
            sum += f64::from(y.max_element()) * area;
            diff += f64::from((x - y).abs().max_element()) * area;
        }
        assert!(sum > 0.0);
        let relative = diff / sum;
        assert!(
            relative <= tolerance,
            "{method:?}: relative difference {relative}"
        );
    }
}

/// 100 placed copies of a 10k-triangle mesh: the mesh is stored once, and the scene's mesh and
/// trees take a small multiple of one copy's, not 100.
#[test]
fn a_hundred_placed_copies_are_not_a_hundred_copies_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    // A 50 x 100 grid of quads, bent into a half cylinder: 10,000 triangles.
    let (nu, nv) = (50usize, 100usize);
    let mut p = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let a = std::f32::consts::PI * i as f32 / nu as f32;
            p.push([a.cos(), a.sin(), j as f32 / nv as f32 * 2.0]);
        }
    }
    let mut idx = Vec::new();
    for j in 0..nv as u32 {
        for i in 0..nu as u32 {
            let (a, b) = (j * (nu as u32 + 1) + i, (j + 1) * (nu as u32 + 1) + i);
            idx.extend([a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    let write = |copies: usize| {
        let mut w = GltfWriter::new();
        let lamp = w.material(
            "Lamp",
            MaterialSpec {
                emissive: [1.0, 1.0, 1.0],
                strength: Some(1.0),
                ..MaterialSpec::default()
            },
        );
        let mesh = w.mesh("Half pipe", &p, None, None, None, &idx, Some(lamp));
        let roots = (0..copies)
            .map(|i| {
                let trs = Trs {
                    t: [3.0 * (i % 10) as f32, 0.0, 3.0 * (i / 10) as f32],
                    r: turn([0.0, 1.0, 0.0], 7.0 * i as f32),
                    ..Trs::default()
                };
                w.node(&format!("Copy {i}"), Some(mesh), None, trs, vec![])
            })
            .collect();
        let path = dir.path().join(format!("pipes{copies}.glb"));
        std::fs::write(&path, w.glb(roots)).unwrap();
        load(&path).unwrap().0
    };
    let (one, hundred) = (write(1), write(100));
    assert_eq!(hundred.mesh.stored_triangle_count(), 10_000);
    assert_eq!(hundred.mesh.triangle_count(), 1_000_000);
    let bytes = |s: &Scene| s.mesh.bytes() + s.accel().bytes();
    let ratio = bytes(&hundred) as f64 / bytes(&one) as f64;
    // The stored mesh, its tree, the copies' shared tree and 100 placements: about twice one
    // copy (the shared tree is the stored one's twin), against 100 times for copies.
    assert!(
        ratio < 3.0,
        "100 copies take {ratio:.2} times one copy's bytes"
    );
    // Every copy answers rays: one aimed down the axis of each pipe's far end hits that copy.
    for (i, o) in hundred.objects.iter().enumerate() {
        let top = o.triangles.start + 2 * (nv as u32 - 1) * nu as u32 + nu as u32;
        let [a, b, c] = hundred.mesh.corners(top);
        let target = (a + b + c) / 3.0;
        let origin = target + Vec3::Y * 5.0;
        let hit = hundred
            .intersect(&twopass_scene::Ray::new(origin, target - origin))
            .unwrap_or_else(|| panic!("copy {i}: no hit"));
        assert_eq!(hit.object as usize, i);
    }
    // The emitters of the copies each have the mesh's area.
    assert_eq!(hundred.emitters.len(), 100);
    for e in &hundred.emitters {
        assert!((e.area - one.emitters[0].area).abs() < 1e-4 * e.area);
    }
}

/// A scene file whose objects name one OBJ file: placed again rather than read again, as the
/// same objects each naming its own copy of the file; a placement repeating another's is
/// dropped with the coincident-objects warning.
#[test]
fn objects_naming_one_mesh_file_place_it_again() {
    let dir = tempfile::tempdir().unwrap();
    let (p, idx) = unit_box();
    let mut obj = String::from("g box\n");
    for v in &p {
        obj += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for f in idx.chunks(3) {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let header = "version = 1\n[camera]\nposition = [0, 4, 12]\nlook_at = [0, 0, 0]\nfov_y = 50\n\
                  [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.6\n\
                  [[object]]\nname = \"light\"\nmaterial = \"grey\"\nemission = 5\n\
                  shape = { type = \"quad\", origin = [-1, 6, -1], edge_u = [0, 0, 2], edge_v = [2, 0, 0] }\n";
    let scene = |shared: bool, repeat_last: bool| {
        let mut text = header.to_owned();
        for (i, trs) in placements(10).iter().enumerate() {
            let file = if shared {
                "box.obj".to_owned()
            } else {
                format!("box{i}.obj")
            };
            std::fs::write(dir.path().join(&file), &obj).unwrap();
            let q = glam::Quat::from_array(trs.r);
            let (axis, angle) = q.to_axis_angle();
            let place = format!(
                "transform = {{ translate = {:?}, scale = {:?}, rotate = [{{ axis = {:?}, degrees = {} }}] }}\n",
                trs.t,
                trs.s,
                axis.to_array(),
                angle.to_degrees()
            );
            text += &format!(
                "[[object]]\nname = \"box {i}\"\nmaterial = \"grey\"\nshape = {{ type = \"obj\", file = \"{file}\" }}\n{place}"
            );
            if repeat_last && i == 9 {
                text += &format!(
                    "[[object]]\nname = \"box again\"\nmaterial = \"grey\"\nshape = {{ type = \"obj\", file = \"{file}\" }}\n{place}"
                );
            }
        }
        let path = dir.path().join("boxes.toml");
        std::fs::write(&path, text).unwrap();
        load(&path).unwrap()
    };
    let ((shared, w1), (copied, w2)) = (scene(true, false), scene(false, false));
    assert!(w1.is_empty() && w2.is_empty(), "{w1:?} {w2:?}");
    assert_eq!(shared.mesh.stored_triangle_count(), 2 + 12);
    assert_eq!(shared.mesh.repeats().len(), 9);
    assert_eq!(copied.mesh.stored_triangle_count(), 2 + 10 * 12);
    assert_eq!(shared.mesh.triangle_count(), copied.mesh.triangle_count());
    for t in 0..shared.mesh.triangle_count() as u32 {
        for (a, b) in shared.mesh.corners(t).iter().zip(copied.mesh.corners(t)) {
            assert!(close(*a, b, 10.0), "triangle {t}: {a} vs {b}");
        }
    }
    let (again, warnings) = scene(true, true);
    assert_eq!(again.objects.len(), shared.objects.len());
    assert_eq!(again.mesh.triangle_count(), shared.mesh.triangle_count());
    let text: Vec<String> = warnings.iter().map(ToString::to_string).collect();
    assert!(
        text.len() == 1
            && text[0].contains("dropped 12 triangle(s) in 1 object(s)")
            && text[0].contains("object `box again`"),
        "{text:?}"
    );
}
