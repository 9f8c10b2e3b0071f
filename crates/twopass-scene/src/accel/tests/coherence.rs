//! Which ray batches the many-ray calls count as coherent: camera rays are, bounces, shadow
//! rays, rays from one point and parallel rays from scattered origins are not.

use glam::Vec3;

use crate::accel::Ray;
use crate::scene::Scene;
use crate::workload;

#[test]
fn camera_rays_are_coherent_and_bounces_and_shadow_rays_are_not() {
    let scene = workload::synthetic_scene(10_000, 0).expect("scene").0;
    let accel = scene.accel();
    // The scene's extent, which the origins' distance is measured against: the root's
    // children's boxes are the exact bounds of the triangles.
    let corners = scene.mesh.triangles.iter().flatten();
    let points = corners.map(|&i| scene.mesh.position(i));
    let (lo, hi) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    assert_eq!(accel.bvh.bounds(), Some((lo, hi)));
    assert!(accel.coherent(&workload::camera_rays(&scene)));
    assert!(!accel.coherent(&workload::incoherent_rays(&scene, 1024, 1)));
    let shadow: Vec<Ray> = workload::occlusion_pairs(&scene, 1024, 2)
        .iter()
        .map(|(a, b)| Scene::segment_between(a, b))
        .collect();
    assert!(!accel.coherent(&shadow));
    // Rays from one point in random directions (a point light's) and parallel rays from
    // scattered origins (a directional light's) are not either.
    let spread = workload::incoherent_rays(&scene, 1024, 3);
    let from_one_point: Vec<Ray> = spread
        .iter()
        .map(|r| Ray::new(spread[0].origin, r.direction))
        .collect();
    assert!(!accel.coherent(&from_one_point));
    let parallel: Vec<Ray> = spread
        .iter()
        .map(|r| Ray::new(r.origin, spread[0].direction))
        .collect();
    assert!(!accel.coherent(&parallel));
    assert!(!accel.coherent(&[]));
}
