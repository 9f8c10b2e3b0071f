//! The `terminator` room: one large coarsely tessellated sphere (icosphere level 2, 320
//! triangles) resting on the floor of a 12 x 8 x 12 room, lit at a slant by one 2 x 2 light,
//! the camera looking across the line where light meets shadow: the sawtooth test scene.

use glam::Vec3;
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::workload::query::rng;

/// Radiance of the light, W/(m^2 sr).
const EMISSION: f32 = 120.0;

/// Generates the room.
pub(super) fn terminator(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(12.0, 8.0, 12.0));
    let mut r = rng(settings.seed);
    let mut b = RoomBuilder::new("terminator", min, max);
    b.walls(2, &[]);
    let center = Vec3::new(6.5, 2.5, 7.0 + r.random_range(-0.2..0.2));
    b.icosphere("sphere", center, 2.5, 2, true);
    // Up and to the side, facing the sphere: light arrives 45 degrees off vertical, across
    // the camera's view.
    let light = Vec3::new(2.2, 6.6, center.z);
    b.light("light", light, center - light, 2.0, [EMISSION; 3]);
    b.finish(settings, Vec3::new(6.5, 2.8, 0.8), center, 60.0, 0.5, "")
}
