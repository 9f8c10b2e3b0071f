//! The `spheres` room of issue 39: 20 x 20 x 8, floating spheres of many sizes (one about 3
//! across lit from above at a slant, one big sphere in front of the camera), boxes on the
//! floor, one 4 x 4 light just under the ceiling, off-centre; every surface grey 0.5. The
//! spheres are longitude-latitude meshes (a modeller's UV sphere) sized so the scene has the
//! triangles asked for.

use glam::Vec3;
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::workload::query::rng;

/// Radiance of the light, W/(m^2 sr): a mean pixel radiance of about 0.8 (the light in view
/// included).
const EMISSION: f32 = 30.0;
/// Floating spheres besides the two placed ones.
const FLOATING: usize = 24;
/// Boxes on the floor.
const BOXES: usize = 5;
/// Cells per wall edge.
const WALL_CELLS: u32 = 2;

/// A sphere placed in the room: centre and radius.
type Ball = (Vec3, f32);

/// Slices around of a UV sphere of about `target` triangles (`n (n - 2)` for `n` slices and
/// `n / 2` stacks), even and at least 8.
fn slices_for(target: f64) -> u32 {
    let n = 1.0 + (1.0 + target.max(0.0)).sqrt();
    ((n / 2.0).round() as u32 * 2).max(8)
}

/// Generates the room.
pub(super) fn spheres(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(20.0, 8.0, 20.0));
    let camera = Vec3::new(10.0, 4.2, 0.6);
    let light = Vec3::new(12.5, 7.9, 12.0);
    let mut r = rng(settings.seed);
    // The large sphere, about 3 across, off the light's axis so it is lit at a slant, and
    // the big sphere in front of the camera.
    let mut balls: Vec<Ball> = vec![
        (Vec3::new(8.0, 4.8, 12.5), 1.5),
        (Vec3::new(11.2, 2.6, 4.2), 1.2),
    ];
    let mut boxes: Vec<(Vec3, Vec3)> = Vec::new();
    while boxes.len() < BOXES {
        let w = Vec3::new(
            r.random_range(0.8..2.5),
            r.random_range(0.5..2.5),
            r.random_range(0.8..2.5),
        );
        let lo = Vec3::new(
            r.random_range(1.0..19.0 - w.x),
            0.0,
            r.random_range(6.0..19.0 - w.z),
        );
        let hi = lo + w;
        let apart = |(a, b): &(Vec3, Vec3)| {
            lo.x > b.x + 0.5 || hi.x < a.x - 0.5 || lo.z > b.z + 0.5 || hi.z < a.z - 0.5
        };
        let clear_of_balls = balls.iter().all(|&(c, rad)| {
            let nearest = c.clamp(lo, hi);
            nearest.distance(c) > rad + 0.3
        });
        if boxes.iter().all(apart) && clear_of_balls {
            boxes.push((lo, hi));
        }
    }
    while balls.len() < 2 + FLOATING {
        // Log-uniform radii from 0.15 to 0.9: many small spheres, a few large.
        let rad = 0.15 * 6f32.powf(r.random::<f32>());
        let c = Vec3::new(
            r.random_range(0.3 + rad..19.7 - rad),
            r.random_range(0.8 + rad..7.3 - rad),
            r.random_range(2.5 + rad..19.7 - rad),
        );
        let free = balls.iter().all(|&(o, ro)| o.distance(c) > ro + rad + 0.2)
            && boxes
                .iter()
                .all(|&(lo, hi)| c.clamp(lo, hi).distance(c) > rad + 0.2)
            && c.distance(camera) > rad + 1.5
            && (c.y + rad < light.y - 0.4
                || (c.x - light.x).abs() > 2.0 + rad
                || (c.z - light.z).abs() > 2.0 + rad);
        if free {
            balls.push((c, rad));
        }
    }
    let mut b = RoomBuilder::new("spheres", min, max);
    b.walls(WALL_CELLS, &[]);
    for (k, &(lo, hi)) in boxes.iter().enumerate() {
        b.cuboid(&format!("box{k}"), lo, hi);
    }
    let fixed = 6 * 2 * (WALL_CELLS * WALL_CELLS) as usize + 12 * BOXES + 2;
    let left = settings.triangles.saturating_sub(fixed) as f64;
    let area: f64 = balls.iter().map(|&(_, rad)| f64::from(rad * rad)).sum();
    for (k, &(c, rad)) in balls.iter().enumerate() {
        let n = slices_for(left * f64::from(rad * rad) / area);
        let name = match k {
            0 => "sphere-large".to_owned(),
            1 => "sphere-front".to_owned(),
            _ => format!("sphere{k}"),
        };
        b.uv_sphere(&name, c, rad, n, n / 2);
    }
    b.light("light", light, Vec3::NEG_Y, 4.0, [EMISSION; 3]);
    b.finish(settings, camera, Vec3::new(10.0, 3.0, 12.0), 80.0, 0.5, "")
}
