use glam::Vec3;

use super::*;
use crate::scene::Scene;

/// Writes `room` into a fresh folder and loads it as a user would, returning the scene and the
/// number of warnings.
fn load(room: &Room) -> (Scene, usize) {
    let dir = tempfile::tempdir().unwrap();
    for (file, text) in room.mesh_files() {
        std::fs::write(dir.path().join(file), text).unwrap();
    }
    let path = dir.path().join(room.scene_file());
    std::fs::write(&path, &room.scene).unwrap();
    let (scene, warnings) = crate::load(&path).unwrap_or_else(|e| panic!("{}: {e}", room.name));
    assert!(warnings.is_empty(), "{}: {warnings:?}", room.name);
    (scene, warnings.len())
}

/// The object a room's scene names `name`, as (lowest, highest) vertex.
fn extent(scene: &Scene, name: &str) -> (Vec3, Vec3) {
    let o = scene
        .objects
        .iter()
        .find(|o| o.name == name)
        .unwrap_or_else(|| panic!("no object {name}"));
    let p = &o
        .vertices
        .clone()
        .map(|v| scene.mesh.position(v))
        .collect::<Vec<_>>();
    (
        p.iter().copied().fold(Vec3::MAX, Vec3::min),
        p.iter().copied().fold(Vec3::MIN, Vec3::max),
    )
}

#[test]
fn every_room_loads_without_warnings_with_its_objects_and_the_camera_inside() {
    // Objects counted from each room's description: walls (six OBJ groups, or five and a
    // built-in coloured wall), its shapes and its lights.
    #[rustfmt::skip]
    let expected = [
        (RoomKind::Spheres,    6 + 5 + 26 + 1),
        (RoomKind::Grazing,    6 + 6 + 1 + 1 + 1),
        (RoomKind::NearLight,  6 + 6 + 1),
        (RoomKind::TwoLights,  5 + 1 + 1 + 1 + 2),
        (RoomKind::Terminator, 6 + 1 + 1),
        (RoomKind::Chrome,     6 + 1 + 3 + 3 + 3 + 4 + 17),
    ];
    for (kind, objects) in expected {
        let room = room(kind, &RoomSettings::default());
        let (scene, warnings) = load(&room);
        assert_eq!(warnings, 0);
        assert_eq!(scene.objects.len(), objects, "{}", room.name);
        assert_eq!(room.objects, objects, "{}", room.name);
        assert_eq!(scene.mesh.triangle_count(), room.triangles, "{}", room.name);
        let (lo, hi) = room.interior;
        let c = scene.camera.position;
        assert!(
            c.cmpgt(lo).all() && c.cmplt(hi).all(),
            "{}: camera {c} outside",
            room.name
        );
        assert_eq!(c, room.camera);
        assert_eq!((scene.camera.width, scene.camera.height), (256, 256));
        // The walls enclose everything: the scene's bounds are the room's.
        assert!(
            scene.bounds.min.abs_diff_eq(lo, 1e-5) && scene.bounds.max.abs_diff_eq(hi, 1e-5),
            "{}: bounds {:?} against {lo} {hi}",
            room.name,
            scene.bounds
        );
        assert!(!scene.emitters.is_empty());
        // An export without normals or texture coordinates.
        assert!(
            room.mesh
                .lines()
                .all(|l| !l.starts_with("vn") && !l.starts_with("vt")),
            "{}",
            room.name
        );
        // Without `vn`, every triangle is flat: its shading normal is its geometric one.
        let m = &scene.mesh;
        let flat = (0..m.triangle_count() as u32).all(|t| {
            let g = m.geometric_normal(t);
            m.shading_normal(t, [0.6, 0.3, 0.1]).abs_diff_eq(g, 1e-5)
        });
        assert!(flat, "{}: smooth shading normals", room.name);
    }
}

#[test]
fn the_spheres_room_has_the_triangles_asked_for_within_ten_percent() {
    for triangles in [20_000, 100_000, 400_000] {
        let settings = RoomSettings {
            triangles,
            ..RoomSettings::default()
        };
        let room = room(RoomKind::Spheres, &settings);
        let (scene, _) = load(&room);
        let n = scene.mesh.triangle_count() as f64;
        assert!(
            (n / triangles as f64 - 1.0).abs() <= 0.10,
            "{n} triangles for {triangles} asked"
        );
    }
}

#[test]
fn rooms_are_deterministic_for_a_seed_and_vary_with_it() {
    for kind in RoomKind::ALL {
        let a = room(kind, &RoomSettings::default());
        let b = room(kind, &RoomSettings::default());
        assert_eq!(a, b, "{}", kind.name());
        let other = room(
            kind,
            &RoomSettings {
                seed: 7,
                ..RoomSettings::default()
            },
        );
        assert_ne!(
            a.mesh,
            other.mesh,
            "{}: seed 7 gives the layout of seed 0",
            kind.name()
        );
    }
}

#[test]
fn rooms_are_found_by_name() {
    for kind in RoomKind::ALL {
        assert_eq!(RoomKind::from_name(kind.name()), Some(kind));
    }
    assert_eq!(RoomKind::from_name("cornell"), None);
}

#[test]
fn the_terminator_sphere_is_a_level_two_icosphere_resting_on_the_floor() {
    let room = room(RoomKind::Terminator, &RoomSettings::default());
    let (scene, _) = load(&room);
    let sphere = scene
        .objects
        .iter()
        .find(|o| o.name == "room/sphere")
        .unwrap();
    assert_eq!(sphere.triangles.len(), 320);
    let (lo, hi) = extent(&scene, "room/sphere");
    assert_eq!(lo.y, 0.0, "touches the floor");
    assert!(hi.y > 4.5 && hi.y <= 5.0, "2.5 in radius: top at {}", hi.y);
}

#[test]
fn resting_objects_touch_the_floor_and_the_slab_leans_on_its_wall() {
    let grazing = load(&room(RoomKind::Grazing, &RoomSettings::default())).0;
    for name in ["room/sphere", "room/box"] {
        assert_eq!(extent(&grazing, name).0.y, 0.0, "{name}");
    }
    let two = load(&room(RoomKind::TwoLights, &RoomSettings::default())).0;
    assert_eq!(extent(&two, "room/sphere").0.y, 0.0);
    let (lo, hi) = extent(&two, "room/slab");
    assert!(lo.y.abs() < 1e-5, "slab on the floor: {lo}");
    assert!(
        (hi.x - 10.0).abs() < 1e-5,
        "slab against the wall x = 10: {hi}"
    );
    // The shelves are 0.05 thick.
    let (lo, hi) = extent(&grazing, "room/shelf0");
    assert!((hi.y - lo.y - 0.05).abs() < 1e-5);
}

#[test]
fn the_chrome_room_has_glass_and_mirror_balls_and_thin_rings_resting_on_the_plate() {
    let room = room(RoomKind::Chrome, &RoomSettings::default());
    let (scene, _) = load(&room);
    // 3 glass balls of level 5 (20,480 triangles), 3 chrome and 3 diffuse of level 4 (5,120),
    // 4 rings of 96 x 12 x 2, the walls' 6 x 8 x 8 x 2, the plate's 12, 17 strips of 2.
    let want = 3 * 20_480 + 6 * 5_120 + 4 * 96 * 12 * 2 + 768 + 12 + 34;
    assert_eq!(scene.mesh.triangle_count(), want);
    let material = |name: &str| {
        let o = scene.objects.iter().find(|o| o.name == name).unwrap();
        scene.materials[o.material as usize].name.clone()
    };
    for (object, want) in [
        ("glass/glass-ball-0", "glass"),
        ("chrome/chrome-ball-2", "chrome"),
        ("chrome/ring-3", "chrome"),
        ("room/grey-ball-1", "grey"),
    ] {
        assert_eq!(material(object), want, "{object}");
    }
    for ball in [
        "glass/glass-ball-1",
        "chrome/chrome-ball-0",
        "room/grey-ball-2",
    ] {
        let (lo, _) = extent(&scene, ball);
        assert!((lo.y - 0.4).abs() < 1e-5, "{ball} floats at {}", lo.y);
    }
    // A ring stands upright, 2 (0.7 + 0.035) high; a torus's vertices lie between 0.7 - 0.035
    // and 0.7 + 0.035 from its centre (the centre of its extent), whatever its turn.
    for ring in ["chrome/ring-0", "chrome/ring-3"] {
        let (lo, hi) = extent(&scene, ring);
        assert!(((hi - lo).y - 1.47).abs() < 1e-3, "{ring}: {lo} {hi}");
        let o = scene.objects.iter().find(|o| o.name == ring).unwrap();
        let p = &o
            .vertices
            .clone()
            .map(|v| scene.mesh.position(v))
            .collect::<Vec<_>>();
        let c = Vec3::new(
            0.5 * (lo.x + hi.x),
            0.5 * (lo.y + hi.y),
            0.5 * (lo.z + hi.z),
        );
        for v in p {
            let d = (*v - c).length();
            assert!((0.665 - 1e-3..=0.735 + 1e-3).contains(&d), "{ring}: {d}");
        }
    }
}

#[test]
fn every_light_of_every_room_faces_into_the_room() {
    // An emitter is one-sided: one facing the ceiling or a wall it hangs by lights only that
    // surface (the chrome room's strips did, 0.02 under the ceiling).
    for kind in RoomKind::ALL {
        let room = room(kind, &RoomSettings::default());
        let (scene, _) = load(&room);
        let centre = 0.5 * (scene.bounds.min + scene.bounds.max);
        for o in scene
            .objects
            .iter()
            .filter(|o| o.emission.max_element() > 0.0)
        {
            for t in o.triangles.clone() {
                let n = scene.mesh.geometric_normal(t);
                let p = scene.mesh.corners(t)[0];
                assert!(
                    n.dot(centre - p) > 0.0,
                    "{}: {} faces {n}, away from the room's centre",
                    kind.name(),
                    o.name
                );
            }
        }
    }
}
