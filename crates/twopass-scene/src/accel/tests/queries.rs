//! The queries' own cases: the bound's one-add form, hits very close to the origin, rays along
//! the axes with negative zeros.

use glam::Vec3;

use crate::accel::Accel;
use crate::accel::hit::four_ulps_up;

/// The one-add form is `next_up` four times over on every distance a hit can have: from
/// the smallest subnormal through the largest float to infinity.
#[test]
fn four_ulps_up_is_next_up_four_times() {
    let steps = |t: f32| t.next_up().next_up().next_up().next_up();
    let mut cases = vec![
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MAX.next_down(),
        f32::MAX.next_down().next_down().next_down().next_down(),
        f32::INFINITY,
        f32::from_bits(1),
        f32::from_bits(0x007f_ffff),
    ];
    let mut bits = 1u32;
    while bits < 0x7f80_0000 {
        cases.push(f32::from_bits(bits));
        bits += 0x1357;
    }
    for t in cases {
        assert_eq!(four_ulps_up(t).to_bits(), steps(t).to_bits(), "{t:e}");
    }
}

/// Two triangles forming the unit square in the plane z = 0.
fn square() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    (p, vec![[0, 1, 2], [0, 2, 3]])
}

#[test]
fn hits_very_close_to_the_origin_with_long_directions() {
    let (p, t) = square();
    let accel = Accel::build(&p, &t);
    // 1e-3 units away along a direction of length 1000: t = 1e-6.
    let origin = Vec3::new(0.3, 0.6, 1e-3);
    let dir = Vec3::new(0.0, 0.0, -1000.0);
    let hit = accel.closest(origin, dir, f32::INFINITY).expect("hit");
    assert_eq!(hit.triangle, 1);
    assert!((hit.t - 1e-6).abs() < 1e-9);
    assert!(accel.any_hit(origin, dir, 1.0));
    assert!(!accel.any_hit(origin, dir, 0.5e-6));
}

#[test]
fn axis_aligned_rays_with_negative_zeros_hit() {
    let (p, t) = square();
    let accel = Accel::build(&p, &t);
    for (o, d) in [
        (Vec3::new(0.25, 0.5, 2.0), -Vec3::Z),
        (Vec3::new(0.25, 0.5, -2.0), Vec3::new(-0.0, -0.0, 1.0)),
        // Exactly through the shared diagonal.
        (Vec3::new(0.5, 0.5, 2.0), -Vec3::Z),
    ] {
        let hit = accel.closest(o, d, f32::INFINITY).expect("hit");
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!(accel.any_hit(o, d, f32::INFINITY));
        let b = hit.barycentric;
        assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-6);
    }
}

/// Issue 43, finding 3: a light panel a millionth of the room from a wall shot its light
/// through it. The f32 bound on `t` grows with the triangle's size, so a 1 x 1 wall could not
/// be told from an origin 1e-6 above it (about 3e-6 along the ray); the f64 decision
/// (`near_t`) finds the hit. From 1e-6 of the square's size above it (at 1e-4, 1 and 1e5
/// units), rays in every downward direction hit it at the distance of the plane, in every
/// query; half that distance away they do not.
#[test]
fn rays_a_millionth_of_a_wall_s_size_from_it_hit_it() {
    use rand::{Rng, SeedableRng};
    let mut r = rand_pcg::Pcg64Mcg::seed_from_u64(43);
    for scale in [1e-4f32, 1.0, 1e5] {
        let (p, t) = square();
        let p: Vec<Vec3> = p.iter().map(|&v| v * scale).collect();
        let accel = Accel::build(&p, &t);
        let gap = 1e-6 * scale;
        let mut rays = Vec::new();
        for _ in 0..2000 {
            let origin = Vec3::new(
                0.1 + 0.8 * r.random::<f32>(),
                0.1 + 0.8 * r.random::<f32>(),
                0.0,
            ) * scale
                + Vec3::Z * gap;
            // Down at any angle, to 84 degrees from the normal.
            let d = Vec3::new(
                r.random::<f32>() - 0.5,
                r.random::<f32>() - 0.5,
                -0.05 - r.random::<f32>(),
            )
            .normalize();
            let expected = (origin.z / -d.z) as f64;
            let hit = accel
                .closest(origin, d, f32::INFINITY)
                .unwrap_or_else(|| panic!("{origin:?} {d:?} at {scale}: missed"));
            // Hits the f32 test accepts carry its rounding, up to its bound (near it, a few
            // percent of so short a distance).
            assert!(
                ((hit.t as f64 - expected) / expected).abs() < 0.05,
                "{} against {expected}",
                hit.t
            );
            assert!(accel.any_hit(origin, d, f32::INFINITY));
            assert!(!accel.any_hit(origin, d, (0.5 * expected) as f32));
            rays.push(crate::accel::Ray::new(origin, d));
        }
        let mut hits = vec![None; rays.len()];
        accel.closest_many(&rays, &mut hits);
        assert!(hits.iter().all(Option::is_some), "closest_many at {scale}");
        let mut blocked = vec![false; rays.len()];
        accel.any_hit_many(&rays, &mut blocked);
        assert!(blocked.iter().all(|&b| b), "any_hit_many at {scale}");
    }
}
