//! The `grazing` room: a long low room (6 wide, 4 high, 30 long) lit by one light mounted on
//! an end wall and facing along the room, so its light reaches the floor and the ceiling at
//! grazing angles; thin shelves (0.05 thick) on the side walls, a sphere resting on the floor
//! and a box standing on it. Grey 0.5.

use glam::Vec3;
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::workload::query::rng;

/// Radiance of the light, W/(m^2 sr).
const EMISSION: f32 = 100.0;
/// Shelf thickness, scene units.
const SHELF: f32 = 0.05;

/// Generates the room.
pub(super) fn grazing(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(6.0, 4.0, 30.0));
    let mut r = rng(settings.seed);
    let mut b = RoomBuilder::new("grazing", min, max);
    // The long walls and the floor are split finely enough that the radiosity mesher starts
    // from cells a few units long.
    b.walls(6, &[]);
    // Three shelves on each side wall, at jittered heights, one after another down the room.
    for k in 0..6 {
        let left = k % 2 == 0;
        let z0 = 4.0 + 4.0 * k as f32 + r.random_range(0.0..1.0);
        let y0 = r.random_range(1.2..3.0);
        let depth = r.random_range(0.4..0.7);
        let (x0, x1) = if left {
            (0.0, depth)
        } else {
            (6.0 - depth, 6.0)
        };
        b.cuboid(
            &format!("shelf{k}"),
            Vec3::new(x0, y0, z0),
            Vec3::new(x1, y0 + SHELF, z0 + r.random_range(2.0..3.5)),
        );
    }
    let sphere = Vec3::new(
        2.2 + r.random_range(-0.3..0.3),
        0.8,
        11.0 + r.random_range(-1.0..1.0),
    );
    b.icosphere("sphere", sphere, 0.8, 4, true);
    let lo = Vec3::new(3.6, 0.0, 17.0 + r.random_range(-1.0..1.0));
    b.cuboid("box", lo, lo + Vec3::new(1.2, 1.0, 1.4));
    // On the end wall z = 0, just off it, facing down the room.
    b.light(
        "light",
        Vec3::new(3.0, 2.4, 0.01),
        Vec3::Z,
        1.5,
        [EMISSION; 3],
    );
    b.finish(
        settings,
        Vec3::new(3.0, 2.0, 1.0),
        Vec3::new(3.0, 1.6, 30.0),
        70.0,
        0.5,
        "",
    )
}
