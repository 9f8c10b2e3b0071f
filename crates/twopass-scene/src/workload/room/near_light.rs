//! The `near-light` room: small curved objects close to the walls and very close under a
//! small bright 1 x 1 light, in a 5 x 3.5 x 5 room of albedo 0.8 (light bounces many times
//! before it is absorbed).

use glam::Vec3;
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::workload::query::rng;

/// Radiance of the light, W/(m^2 sr).
const EMISSION: f32 = 15.0;

/// Generates the room.
pub(super) fn near_light(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(5.0, 3.5, 5.0));
    let mut r = rng(settings.seed);
    let mut j = |s: f32| r.random_range(-s..s);
    let light = Vec3::new(2.5, 3.48, 3.0);
    let mut b = RoomBuilder::new("near-light", min, max);
    b.walls(4, &[]);
    // Just under the light: the top 0.08 below it, and one off its edge, 0.15 below.
    b.icosphere(
        "under-light",
        light - Vec3::Y * (0.08 + 0.25),
        0.25,
        3,
        false,
    );
    b.icosphere(
        "beside-light",
        Vec3::new(3.4 + j(0.05), 3.1, 3.0 + j(0.1)),
        0.25,
        3,
        false,
    );
    // Close to the walls: 0.05 from the left wall, 0.1 from the back wall, in a corner on the
    // floor.
    b.icosphere(
        "near-wall",
        Vec3::new(0.35, 1.4 + j(0.2), 2.0 + j(0.3)),
        0.3,
        3,
        false,
    );
    b.icosphere(
        "near-back",
        Vec3::new(2.0 + j(0.3), 1.0 + j(0.2), 4.7),
        0.2,
        3,
        false,
    );
    b.icosphere("corner", Vec3::new(4.6, 0.4, 4.6), 0.4, 3, true);
    b.icosphere(
        "floor-ball",
        Vec3::new(1.6 + j(0.2), 0.3, 2.6 + j(0.2)),
        0.3,
        3,
        true,
    );
    b.light("light", light, Vec3::NEG_Y, 1.0, [EMISSION; 3]);
    // High albedo: every surface of this room reflects 0.8.
    b.finish(
        settings,
        Vec3::new(2.5, 1.7, 0.3),
        Vec3::new(2.5, 1.9, 5.0),
        80.0,
        0.8,
        "",
    )
}
