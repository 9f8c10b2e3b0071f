//! The scene's camera as a glTF camera: a perspective camera and the node that places it, for
//! the lightmap `.glb` and the user's asset written back; and the same camera as the record
//! of `asset.extras.twopass.camera` that the page of `twopass view` reads ([`CameraRecord`]).
//!
//! glTF cameras look down their node's local -Z with +Y up and +X to the image's right
//! (glTF 2.0, "Cameras"), so the node's rotation is the matrix whose columns are the camera's
//! right, up and backward (-forward) directions. The translation is the eye in metres;
//! `yfov` is the scene's vertical field of view in radians and `aspectRatio` the image's
//! width over height. `znear` is the scene's bounding-box diagonal over
//! [`ZNEAR_PER_DIAGONAL`] (a millimetre in a one-metre room, a metre in a kilometre of
//! terrain), and `zfar` twice the distance from the eye to the box's farthest corner, so the
//! whole scene lies between the planes.

use glam::{DVec3, Mat3, Quat, Vec3};
use serde::Serialize;
use serde_json::{Value, json};
use twopass_scene::Scene;

/// The scene's bounding-box diagonal over the glTF camera's `znear`.
pub const ZNEAR_PER_DIAGONAL: f64 = 1000.0;

/// The name of the camera and of its node in the `.glb` files.
pub const CAMERA_NAME: &str = "twopass camera";

/// A scene camera in glTF terms, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GltfCamera {
    /// Vertical field of view, radians.
    pub yfov: f32,
    /// Image width over height.
    pub aspect_ratio: f32,
    /// Near clipping distance, metres.
    pub znear: f32,
    /// Far clipping distance, metres.
    pub zfar: f32,
    /// The eye, metres.
    pub translation: Vec3,
    /// The node's rotation: maps the glTF camera's -Z to the viewing direction and +Y to the
    /// image's up.
    pub rotation: Quat,
}

/// The rotation of a glTF camera node looking along unit `forward` with unit `up` (orthogonal
/// to it) on top: local -Z to `forward`, +Y to `up`, +X to `forward x up`.
pub fn camera_rotation(forward: Vec3, up: Vec3) -> Quat {
    let right = forward.cross(up).normalize();
    let up = right.cross(forward).normalize();
    Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize()
}

impl GltfCamera {
    /// The glTF camera of `scene`'s camera, in metres.
    pub fn of(scene: &Scene) -> Self {
        let c = &scene.camera;
        let m = scene.unit.metres();
        let (min, max) = (scene.bounds.min.as_dvec3(), scene.bounds.max.as_dvec3());
        let eye = c.position.as_dvec3();
        let farthest = (0..8)
            .map(|i| {
                let corner = DVec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                corner.distance(eye)
            })
            .fold(0.0, f64::max);
        let znear = (f64::from(scene.bounds.diagonal()) * m / ZNEAR_PER_DIAGONAL).max(1e-6);
        Self {
            yfov: c.fov_y,
            aspect_ratio: c.width as f32 / c.height as f32,
            znear: znear as f32,
            zfar: (2.0 * farthest * m).max(2.0 * znear) as f32,
            translation: (eye * m).as_vec3(),
            rotation: camera_rotation(c.forward, c.up),
        }
    }

    /// The glTF `cameras[]` entry.
    pub(super) fn camera_json(&self) -> Value {
        json!({
            "name": CAMERA_NAME,
            "type": "perspective",
            "perspective": {
                "yfov": self.yfov,
                "aspectRatio": self.aspect_ratio,
                "znear": self.znear,
                "zfar": self.zfar,
            },
        })
    }

    /// The glTF `nodes[]` entry showing camera `index`.
    pub(super) fn node_json(&self, index: usize) -> Value {
        json!({
            "name": CAMERA_NAME,
            "camera": index,
            "translation": self.translation.to_array(),
            "rotation": self.rotation.to_array(),
        })
    }
}

/// The scene's camera as the lightmap `.glb` records it (`asset.extras.twopass.camera`), so
/// a viewer (the page of `twopass view`) can show the bake from the view twopass renders.
/// Positions in metres, in the `.glb`'s frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CameraRecord {
    /// Eye position, metres.
    pub position: [f32; 3],
    /// The point looked at, metres: on the viewing axis, as far along it as the centre of
    /// the scene's bounding box (the point a viewer orbits around).
    pub target: [f32; 3],
    /// Unit image-up direction.
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    pub vertical_fov_degrees: f32,
    /// The scene's image width, pixels.
    pub width: u32,
    /// The scene's image height, pixels.
    pub height: u32,
}

impl CameraRecord {
    /// The record of `scene`'s camera.
    pub fn of(scene: &Scene) -> Self {
        let c = &scene.camera;
        let m = scene.unit.metres();
        let centre = (scene.bounds.min + scene.bounds.max) * 0.5;
        let along = c.forward.dot(centre - c.position).max(f32::EPSILON);
        let metres = |p: Vec3| (p.as_dvec3() * m).as_vec3().to_array();
        Self {
            position: metres(c.position),
            target: metres(c.position + c.forward * along),
            up: c.up.to_array(),
            vertical_fov_degrees: c.fov_y.to_degrees(),
            width: c.width,
            height: c.height,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotation_maps_minus_z_to_the_view_and_y_to_up() {
        // Looking down +x with +y up (a quarter turn about y), along a diagonal with a tilted
        // up, and straight down with -z up: each maps -Z, +Y, +X where the camera has them.
        #[rustfmt::skip]
        let cases = [
            (Vec3::X, Vec3::Y),
            (Vec3::new(1.0, -1.0, 2.0).normalize(), Vec3::new(1.0, 3.0, 1.0).normalize()),
            (Vec3::NEG_Y, Vec3::NEG_Z),
            (Vec3::Z, Vec3::Y),
        ];
        for (forward, up) in cases {
            let q = camera_rotation(forward, up);
            let right = forward.cross(up).normalize();
            let true_up = right.cross(forward);
            assert!(
                (q * Vec3::NEG_Z - forward).length() < 1e-6,
                "{forward} {up}"
            );
            assert!((q * Vec3::Y - true_up).length() < 1e-6, "{forward} {up}");
            assert!((q * Vec3::X - right).length() < 1e-6, "{forward} {up}");
            assert!((q.length() - 1.0).abs() < 1e-6);
        }
        // A quarter turn about +y takes -Z to -X: looking down -x is (0, sin 45, 0, cos 45).
        let q = camera_rotation(Vec3::NEG_X, Vec3::Y);
        let q = if q.w < 0.0 { -q } else { q };
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!(q.abs_diff_eq(Quat::from_xyzw(0.0, h, 0.0, h), 1e-6), "{q}");
    }
}
