//! The `chrome` room: glass, chrome and diffuse balls and thin chrome rings standing on a
//! plate, under seventeen strip lights, in a 16 x 8 x 16 room: a two-pass renderer's hard case
//! (caustics through glass onto a diffuse plate, diffuse light seen through mirrors and glass,
//! contact shadows under balls, rings thinner than a pixel's footprint at their edges), about
//! 100,000 triangles.

use glam::Vec3;
use rand::Rng;

use super::build::{Room, RoomBuilder, RoomSettings};
use crate::shape;
use crate::workload::query::rng;

/// Radiance of each strip light, W/(m^2 sr).
const EMISSION: f32 = 60.0;
/// The plate's top, metres above the floor.
const PLATE_TOP: f32 = 0.4;

/// Generates the room.
pub(super) fn chrome(settings: &RoomSettings) -> Room {
    let (min, max) = (Vec3::ZERO, Vec3::new(16.0, 8.0, 16.0));
    let mut r = rng(settings.seed);
    let mut j = |s: f32| r.random_range(-s..s);
    let mut b = RoomBuilder::new("chrome", min, max);
    b.walls(8, &[]);
    b.cuboid(
        "plate",
        Vec3::new(3.0, 0.0, 4.0),
        Vec3::new(13.0, PLATE_TOP, 12.0),
    );
    // Three rows of three balls on the plate (glass at the front, chrome in the middle,
    // diffuse at the back), each resting on it.
    let kinds: [(&'static str, u32); 3] = [("glass", 5), ("chrome", 4), ("grey", 4)];
    for (row, (material, level)) in kinds.into_iter().enumerate() {
        for col in 0..3 {
            let radius = 0.55 + 0.1 * col as f32 + j(0.05);
            let center = Vec3::new(
                5.0 + 3.0 * col as f32 + j(0.3),
                PLATE_TOP + radius,
                6.0 + 2.2 * row as f32 + j(0.2),
            );
            let mut mesh =
                shape::sphere(center, radius, level).expect("generated spheres are valid");
            let low = mesh.positions.iter().map(|p| p.y).fold(f32::MAX, f32::min);
            for p in &mut mesh.positions {
                p.y += PLATE_TOP - low;
            }
            let name = format!("{material}-ball-{col}");
            if material == "grey" {
                b.group(&name, &mesh.positions, &mesh.triangles);
            } else {
                b.group_in(material, &name, &mesh.positions, &mesh.triangles);
            }
        }
    }
    // Four thin chrome rings standing on the plate between the rows, each turned about the
    // vertical: a tube 0.035 thick around a circle of radius 0.7.
    for k in 0..4 {
        let (major, minor) = (0.7f32, 0.035f32);
        let center = Vec3::new(
            4.2 + 2.6 * k as f32 + j(0.2),
            PLATE_TOP + major + minor,
            7.1,
        );
        let turn = (25.0 * k as f32 + j(10.0)).to_radians();
        let axis = Vec3::new(turn.sin(), 0.0, turn.cos());
        let (positions, triangles) = torus(center, axis, major, minor, 96, 12);
        b.group_in("chrome", &format!("ring-{k}"), &positions, &triangles);
    }
    // Seventeen strips 0.12 x 6 under the ceiling, across the room, facing down.
    for k in 0..17 {
        let x = 0.6 + 0.9 * k as f32;
        let origin = Vec3::new(x, max.y - 0.02, 5.0);
        // x cross z = -y: the front, which emits, faces the floor.
        let (u, v) = (Vec3::X * 0.12, Vec3::Z * 6.0);
        b.quad(
            &format!("strip-{k}"),
            "grey",
            origin,
            u,
            v,
            Some([EMISSION; 3]),
        );
    }
    let materials = "\n[[material]]\nname = \"glass\"\ntype = \"dielectric\"\nior = 1.5\n\
                     \n[[material]]\nname = \"chrome\"\ntype = \"mirror\"\nreflectance = 0.75\n";
    b.finish(
        settings,
        Vec3::new(8.0, 3.6, 0.5),
        Vec3::new(8.0, 0.8, 8.0),
        55.0,
        0.5,
        materials,
    )
}

/// A torus around `center` whose ring lies in the plane normal to unit `axis`: `around`
/// segments along the ring of radius `major`, `across` along the tube of radius `minor`,
/// `2 around across` triangles facing out.
fn torus(
    center: Vec3,
    axis: Vec3,
    major: f32,
    minor: f32,
    around: u32,
    across: u32,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (e1, e2) = axis.any_orthonormal_pair();
    let mut positions = Vec::with_capacity((around * across) as usize);
    for i in 0..around {
        let phi = std::f32::consts::TAU * i as f32 / around as f32;
        let radial = e1 * phi.cos() + e2 * phi.sin();
        for k in 0..across {
            let theta = std::f32::consts::TAU * k as f32 / across as f32;
            positions.push(
                center + radial * (major + minor * theta.cos()) + axis * (minor * theta.sin()),
            );
        }
    }
    let at = |i: u32, k: u32| (i % around) * across + k % across;
    let mut triangles = Vec::with_capacity((2 * around * across) as usize);
    for i in 0..around {
        for k in 0..across {
            // Seen from outside the tube, (i, k) -> (i + 1, k) -> (i + 1, k + 1) turns
            // counter-clockwise when e1 x e2 = axis.
            let flip = e1.cross(e2).dot(axis) < 0.0;
            let (a, b, c, d) = (at(i, k), at(i + 1, k), at(i + 1, k + 1), at(i, k + 1));
            if flip {
                triangles.push([a, c, b]);
                triangles.push([a, d, c]);
            } else {
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
    }
    (positions, triangles)
}
