use glam::Vec3;

use super::*;
use crate::scene::Scene;

/// Writes `room` into a fresh folder and loads it as a user would, returning the scene and the
/// number of warnings.
fn load(room: &Room) -> (Scene, usize) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(&room.mesh_file), &room.mesh).unwrap();
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
    let p = &scene.mesh.positions[o.vertices.start as usize..o.vertices.end as usize];
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
    ];
    for (kind, objects) in expected {
        let room = room(kind, &RoomSettings::default());
        let (scene, warnings) = load(&room);
        assert_eq!(warnings, 0);
        assert_eq!(scene.objects.len(), objects, "{}", room.name);
        assert_eq!(room.objects, objects, "{}", room.name);
        assert_eq!(scene.mesh.triangles.len(), room.triangles, "{}", room.name);
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
        let flat = (0..m.triangles.len() as u32).all(|t| {
            let g = m.geometric_normals[t as usize];
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
        let n = scene.mesh.triangles.len() as f64;
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
