//! The `two-lights` room: a 0.5 x 0.5 and a 3 x 3 light of different power under the ceiling
//! of a 10 x 5 x 10 room, one red wall (0.6, 0.2, 0.2), a big sphere resting on the floor and
//! a thin slab leaning on a wall. Grey 0.5 elsewhere.

use glam::{Quat, Vec3};
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::shape;
use crate::workload::query::rng;

/// Radiance of the small light, warm white, W/(m^2 sr) (power pi * 144 * 0.25 in red).
const SMALL_EMISSION: [f32; 3] = [144.0, 130.0, 108.0];
/// Radiance of the big light, W/(m^2 sr) (power pi * 4.8 * 9, 1.2 times the small one's).
const BIG_EMISSION: [f32; 3] = [4.8; 3];

/// Generates the room.
pub(super) fn two_lights(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(10.0, 5.0, 10.0));
    let mut r = rng(settings.seed);
    let mut b = RoomBuilder::new("two-lights", min, max);
    b.walls(4, &["wall-x-min"]);
    b.quad("red-wall", "red", min, Vec3::Y * 5.0, Vec3::Z * 10.0, None);
    b.icosphere(
        "sphere",
        Vec3::new(
            6.0 + r.random_range(-0.3..0.3),
            1.5,
            6.5 + r.random_range(-0.3..0.3),
        ),
        1.5,
        4,
        true,
    );
    // A slab 0.08 thick, 3 long and 2 wide, leaning 20 degrees off vertical on the wall
    // x = 10: its top outer edge touches the wall, its bottom inner edge the floor.
    let (t, len, width) = (0.08f32, 3.0f32, 2.0f32);
    let tilt = (20.0f32 + r.random_range(-3.0..3.0)).to_radians();
    let z0 = 1.5 + r.random_range(0.0..0.5);
    let mut slab = shape::cuboid(Vec3::ZERO, Vec3::new(t, len, width)).expect("slab has extent");
    let turn = Quat::from_rotation_z(-tilt);
    let origin = Vec3::new(10.0 - t * tilt.cos() - len * tilt.sin(), t * tilt.sin(), z0);
    for p in &mut slab.positions {
        *p = turn * *p + origin;
    }
    b.mesh("slab", &slab);
    b.light(
        "light-small",
        Vec3::new(2.5, 4.98, 7.0),
        Vec3::NEG_Y,
        0.5,
        SMALL_EMISSION,
    );
    b.light(
        "light-big",
        Vec3::new(6.5, 4.98, 3.5),
        Vec3::NEG_Y,
        3.0,
        BIG_EMISSION,
    );
    let red = "\n[[material]]\nname = \"red\"\ntype = \"lambert\"\ndiffuse = [0.6, 0.2, 0.2]\n";
    b.finish(
        settings,
        Vec3::new(5.0, 2.5, 0.3),
        Vec3::new(5.0, 1.8, 10.0),
        80.0,
        0.5,
        red,
    )
}
