//! The scene file's camera table, validated into a [`Camera`].

use glam::Vec3;
use toml::Spanned;

use super::loader::{Loader, MAX_COORDINATE, in_range};
use crate::camera::Camera;
use crate::camera::CameraProblem;
use crate::description::CameraDesc;
use crate::error::{SceneError, Warning};

impl Loader {
    pub(super) fn camera(&mut self, c: &Spanned<CameraDesc>) -> Result<Camera, SceneError> {
        let line = self.line(c);
        let err = |problem| SceneError::Camera {
            path: self.path.clone(),
            line: Some(line),
            problem,
        };
        let d = c.get_ref();
        let [w, h] = d.resolution;
        if w == 0 || h == 0 {
            return Err(SceneError::Toml {
                path: self.path.clone(),
                line,
                column: 1,
                message: format!("camera resolution {w} x {h} must be at least 1 x 1"),
            });
        }
        Camera::check_resolution(u64::from(w), u64::from(h)).map_err(err)?;
        for (key, v) in [("position", d.position), ("look_at", d.look_at)] {
            if let Some(c) = v.iter().find(|c| !in_range(**c)) {
                return Err(SceneError::Toml {
                    path: self.path.clone(),
                    line,
                    column: 1,
                    message: format!(
                        "camera `{key}` value {c:e} is not finite or outside the supported range of +-{MAX_COORDINATE:e} scene units"
                    ),
                });
            }
        }
        let fov_y = match (d.fov_y, d.focal_length) {
            (Some(_), Some(_)) => return Err(err(CameraProblem::FovAndFocalLength)),
            (Some(f), None) => f.to_radians(),
            (None, focal) => {
                let focal = focal.unwrap_or(50.0);
                let [fw, fh] = d.film_size.unwrap_or([36.0, 24.0]);
                for v in [focal, fw, fh] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(err(CameraProblem::Lens(v)));
                    }
                }
                let (film, image) = (fw / fh, w as f32 / h as f32);
                if (film / image - 1.0).abs() > 0.01 {
                    self.warnings.push(Warning::FilmAspect {
                        path: self.path.clone(),
                        film,
                        image,
                    });
                }
                2.0 * (0.5 * fh / focal).atan()
            }
        };
        Camera::look_at(
            Vec3::from_array(d.position),
            Vec3::from_array(d.look_at),
            Vec3::from_array(d.up),
            fov_y,
            w,
            h,
        )
        .map_err(err)
    }
}
