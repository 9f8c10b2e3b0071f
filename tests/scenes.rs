//! The real scenes load as published, and every built-in shape and transform is correct.

use std::f32::consts::PI;
use std::path::Path;

use glam::{Vec2, Vec3};
use twopass_scene::{Ray, Scene, load, load_toml};

use crate::scene_path;

fn inline(objects: &str) -> Scene {
    let text = format!(
        "version = 1\n[camera]\nposition = [0, 0, 50]\nlook_at = [0, 0, 0]\nfov_y = 40\n\n\
         [[material]]\nname = \"white\"\ntype = \"lambert\"\ndiffuse = 0.5\n{objects}"
    );
    load_toml(&text, Path::new("inline.toml")).unwrap().0
}

fn object_area(scene: &Scene, i: usize) -> f64 {
    scene.objects[i]
        .triangles
        .clone()
        .map(|t| f64::from(scene.mesh.area(t)))
        .sum()
}

#[test]
fn cornell_box_matches_the_measured_data() {
    let (scene, warnings) = load(scene_path("cornell-box.toml")).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    // 5 walls + light + 2 blocks of 5 faces, each a quad: 16 objects, 32 triangles.
    assert_eq!(scene.objects.len(), 16);
    assert_eq!(scene.mesh.triangle_count(), 32);
    assert_eq!(scene.emitters.len(), 1);
    let light = &scene.emitters[0];
    assert!((light.area - 130.0 * 105.0).abs() < 1e-2);
    let expected_power = Vec3::new(17.0, 12.0, 4.0) * (PI * 130.0 * 105.0);
    assert!(light.power.abs_diff_eq(expected_power, 1.0));
    // The light faces down, 0.1 mm below the ceiling.
    let t = scene.objects[light.object as usize].triangles.start;
    assert!(scene.mesh.geometric_normal(t).abs_diff_eq(-Vec3::Y, 1e-6));
    assert!((scene.mesh.position(scene.mesh.triangle(t)[0]).y - 548.7).abs() < 1e-4);
    assert!(scene.bounds.min.abs_diff_eq(Vec3::ZERO, 1e-6));
    assert!(
        scene
            .bounds
            .max
            .abs_diff_eq(Vec3::new(556.0, 548.8, 559.2), 1e-4)
    );
    // Floor area from the published corners (a trapezoid-like quad): shoelace in x-z.
    let floor = [(552.8, 0.0), (0.0, 0.0), (0.0, 559.2), (549.6, 559.2)];
    let shoelace: f64 = (0..4)
        .map(|i| {
            let (a, b) = (floor[i], floor[(i + 1) % 4]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        .abs()
        / 2.0;
    let floor_id = scene
        .objects
        .iter()
        .position(|o| o.name == "floor")
        .unwrap();
    assert!(
        (object_area(&scene, floor_id) - shoelace).abs() < 0.5,
        "{shoelace}"
    );
    // Every wall faces into the room: its normal points toward the room's centre.
    let centre = Vec3::new(278.0, 274.4, 279.6);
    for o in scene
        .objects
        .iter()
        .filter(|o| o.name.ends_with("wall") || o.name == "floor" || o.name == "ceiling")
    {
        for t in o.triangles.clone() {
            let p = scene.mesh.position(scene.mesh.triangle(t)[0]);
            assert!(
                scene.mesh.geometric_normal(t).dot(centre - p) > 0.0,
                "{} faces out",
                o.name
            );
        }
    }
    // The published camera: 35 mm lens on 25 mm film.
    assert!((scene.camera.fov_y - 2.0 * (12.5f32 / 35.0).atan()).abs() < 1e-6);
}

#[test]
fn camera_rays_hit_where_the_measured_data_says() {
    let (scene, _) = load(scene_path("cornell-box.toml")).unwrap();
    let c = &scene.camera;
    // The centre ray (x = 278, y = 273) meets the tall block's face from (265, 296) to
    // (423, 247) in the x-z plane at z = 296 - 13 * 49 / 158.
    let hit = scene
        .intersect(&Ray::new(c.position, c.direction(Vec2::new(256.0, 256.0))))
        .unwrap();
    assert_eq!(scene.objects[hit.object as usize].name, "tall-block-side-4");
    let z = 296.0 - 13.0 * 49.0 / 158.0;
    assert!((hit.t - (800.0 + z)).abs() < 1e-3, "t = {}", hit.t);
    assert!(hit.front_face);
    // Higher up, the ray clears the block and the light and reaches the back wall.
    let target = Vec3::new(278.0, 450.0, 559.2);
    let hit = scene
        .intersect(&Ray::new(c.position, (target - c.position).normalize()))
        .unwrap();
    assert_eq!(scene.objects[hit.object as usize].name, "back-wall");
    assert!(
        (hit.t - (target - c.position).length()).abs() < 1e-3,
        "t = {}",
        hit.t
    );
}

#[test]
fn obj_version_of_the_box_equals_the_toml_version() {
    let (a, _) = load(scene_path("cornell-box.toml")).unwrap();
    let (b, warnings) = load(scene_path("cornell-obj.toml")).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(a.mesh.triangle_count(), b.mesh.triangle_count());
    assert!((a.total_area() - b.total_area()).abs() < 1e-6 * a.total_area());
    assert_eq!(
        b.emitters.len(),
        1,
        "Ke in the MTL makes the light an emitter"
    );
    assert!(a.emitters[0].power.abs_diff_eq(b.emitters[0].power, 1.0));
    let red = b
        .materials
        .iter()
        .find(|m| m.name.ends_with(":red"))
        .unwrap();
    assert_eq!(red.material.diffuse_albedo(), Vec3::new(0.63, 0.065, 0.05));
    // A bare OBJ gets a camera that frames it.
    let (bare, _) = load(scene_path("meshes/cornell-box.obj")).unwrap();
    let centre = bare
        .camera
        .project(bare.bounds.center() - bare.camera.position)
        .unwrap();
    assert!(centre.abs_diff_eq(Vec2::splat(256.0), 1e-2));
    for corner in [bare.bounds.min, bare.bounds.max] {
        let p = bare.camera.project(corner - bare.camera.position).unwrap();
        assert!(
            p.cmpge(Vec2::ZERO).all() && p.cmple(Vec2::splat(512.0)).all(),
            "{corner} is off screen at {p}"
        );
    }
}

#[test]
fn every_scene_in_the_repository_loads() {
    for entry in std::fs::read_dir(scene_path("")).unwrap() {
        let path = entry.unwrap().path();
        // Beside the scenes: their measured presets (`twopass bench tradeoff`), not scenes.
        let presets = path.to_string_lossy().ends_with(".presets.toml");
        if path.extension().is_some_and(|e| e == "toml") && !presets {
            let (scene, _) = load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.has_light(), "{} has no light", path.display());
            let cornell = path
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("cornell"));
            if !cornell {
                continue;
            }
            assert!(!scene.emitters.is_empty(), "{}", path.display());
            // Every Cornell room here is about 0.55 m wide: stated in millimetres.
            assert_eq!(
                scene.unit,
                twopass_scene::Unit::Millimetre,
                "{}",
                path.display()
            );
            let width_m = (scene.bounds.max.x - scene.bounds.min.x) as f64 * scene.unit.metres();
            assert!(
                (0.5..0.6).contains(&width_m),
                "{}: {width_m} m",
                path.display()
            );
        }
    }
    // A bare OBJ states no unit: metres.
    let (bare, _) = load(scene_path("meshes/cornell-box.obj")).unwrap();
    assert_eq!(bare.unit, twopass_scene::Unit::Metre);
}

#[test]
fn quad_and_polygon_shapes() {
    let s = inline(
        "[[object]]\nname = \"q\"\nmaterial = \"white\"\nshape = { type = \"quad\", origin = [0, 0, 0], edge_u = [3, 0, 0], edge_v = [0, 0, -2] }\n\
         [[object]]\nname = \"p\"\nmaterial = \"white\"\nshape = { type = \"polygon\", vertices = [[0, 0, 0], [4, 0, 0], [4, 4, 0], [2, 1, 0], [0, 4, 0]] }\n",
    );
    assert!((object_area(&s, 0) - 6.0).abs() < 1e-5);
    assert!(
        s.mesh.geometric_normal(0).abs_diff_eq(Vec3::Y, 1e-6),
        "edge_u x edge_v = x x -z = +y"
    );
    // Concave pentagon: 16 minus the notch triangle (4, 4), (2, 1), (0, 4) of area 6.
    assert!((object_area(&s, 1) - 10.0).abs() < 1e-5);
    assert_eq!(s.objects[1].triangles.len(), 3);
    assert_eq!(
        s.objects[1].vertices.len(),
        5,
        "vertices are shared, not duplicated"
    );
}

#[test]
fn box_shape_is_closed_and_outward() {
    let s = inline(
        "[[object]]\nname = \"b\"\nmaterial = \"white\"\nshape = { type = \"box\", min = [0, 0, 0], max = [1, 2, 3] }\n",
    );
    assert_eq!(s.mesh.triangle_count(), 12);
    assert!((object_area(&s, 0) - 22.0).abs() < 1e-5);
    // A ray from inside hits a face from behind; one from outside hits its front.
    let inside = s
        .intersect(&Ray::new(Vec3::new(0.5, 1.0, 1.5), Vec3::X))
        .unwrap();
    assert!(!inside.front_face && (inside.t - 0.5).abs() < 1e-6);
    let outside = s
        .intersect(&Ray::new(Vec3::new(-1.0, 1.0, 1.5), Vec3::X))
        .unwrap();
    assert!(outside.front_face && (outside.t - 1.0).abs() < 1e-6);
}

#[test]
fn sphere_shape_has_smooth_normals_and_size_driven_tessellation() {
    let s = inline(
        "[[object]]\nname = \"small\"\nmaterial = \"white\"\nshape = { type = \"sphere\", center = [0, 0, 0], radius = 1 }\n\
         [[object]]\nname = \"big\"\nmaterial = \"white\"\nshape = { type = \"sphere\", center = [0, 0, -200], radius = 100 }\n\
         [[object]]\nname = \"fixed\"\nmaterial = \"white\"\nshape = { type = \"sphere\", center = [0, 0, 5], radius = 1, subdivisions = 2 }\n",
    );
    assert!(
        s.objects[1].triangles.len() > s.objects[0].triangles.len(),
        "bigger sphere, finer mesh"
    );
    assert_eq!(s.objects[2].triangles.len(), 20 * 16);
    let hit = s
        .intersect(&Ray::new(Vec3::new(0.3, 0.2, 10.0), -Vec3::Z))
        .unwrap();
    assert_eq!(hit.object, 2);
    // The interpolated normal of a sphere points along the hit position from the centre.
    let radial = (hit.point.position - Vec3::new(0.0, 0.0, 5.0)).normalize();
    assert!(
        hit.shading_normal.dot(radial) > 0.999,
        "{} vs {radial}",
        hit.shading_normal
    );
}

#[test]
fn transforms_place_and_orient_objects() {
    let s = inline(
        "[[object]]\nname = \"t\"\nmaterial = \"white\"\nshape = { type = \"quad\", origin = [0, 0, 0], edge_u = [1, 0, 0], edge_v = [0, 1, 0] }\n\
         transform = { scale = [2, 3, 1], rotate = [{ axis = [0, 1, 0], degrees = 90 }], translate = [10, 0, 0] }\n\
         [[object]]\nname = \"m\"\nmaterial = \"white\"\nshape = { type = \"box\", min = [0, 0, 0], max = [1, 1, 1] }\n\
         transform = { scale = [-1, 1, 1] }\n",
    );
    // Corner (1, 1, 0): scaled to (2, 3, 0), rotated 90 deg about y to (0, 3, -2), moved to (10, 3, -2).
    let quad: Vec<Vec3> = s.objects[0]
        .vertices
        .clone()
        .map(|v| s.mesh.position(v))
        .collect();
    assert!(
        quad.iter()
            .any(|p| p.abs_diff_eq(Vec3::new(10.0, 3.0, -2.0), 1e-5)),
        "{quad:?}"
    );
    // The normal +z turns into +x.
    assert!(s.mesh.geometric_normal(0).abs_diff_eq(Vec3::X, 1e-6));
    // A mirroring transform keeps the box's faces pointing out.
    for t in s.objects[1].triangles.clone() {
        let p = s.mesh.position(s.mesh.triangle(t)[0]);
        let n = s.mesh.geometric_normal(t);
        assert!(
            n.dot(p - Vec3::new(-0.5, 0.5, 0.5)) > 0.0,
            "mirrored box face {t} points in"
        );
    }
}
