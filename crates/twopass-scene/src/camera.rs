//! The pinhole camera: an orthonormal basis, a vertical field of view and an image size.

use std::fmt;

use glam::{Vec2, Vec3};

/// A pinhole camera. Pixel (0, 0) is the top-left corner of the image; the camera looks along
/// `forward` with `up` on top; `right = forward x up` (right-handed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position, scene units.
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit image-right direction.
    pub right: Vec3,
    /// Unit image-up direction.
    pub up: Vec3,
    /// Vertical field of view, radians in (0, pi).
    pub fov_y: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

impl Camera {
    /// Longest image side, pixels.
    pub const MAX_SIDE: u32 = 65536;
    /// Most pixels in an image (2^25: 8K UHD, 7680 x 4320, fits). A render holds about 150
    /// bytes per pixel (six RGB layers while tracing and again as images), so this bounds a
    /// render's image memory at about 5 GB.
    pub const MAX_PIXELS: u64 = 1 << 25;
    /// Side of the largest square image, pixels.
    pub const MAX_PIXELS_SQUARE: u32 = 5792;

    /// Checks that a `width` x `height` image is within [`Camera::MAX_SIDE`] and
    /// [`Camera::MAX_PIXELS`] (and at least 1 x 1).
    pub fn check_resolution(width: u64, height: u64) -> Result<(), CameraProblem> {
        if width == 0
            || height == 0
            || width > u64::from(Self::MAX_SIDE)
            || height > u64::from(Self::MAX_SIDE)
            || width * height > Self::MAX_PIXELS
        {
            return Err(CameraProblem::Resolution { width, height });
        }
        Ok(())
    }

    /// [`Camera::with_resolution`], refusing a size beyond [`Camera::check_resolution`].
    pub fn try_with_resolution(
        self,
        width: Option<u32>,
        height: Option<u32>,
    ) -> Result<Self, CameraProblem> {
        let c = self.with_resolution(width, height);
        // The derived side saturates at u32::MAX, so it is refused rather than wrapped.
        Self::check_resolution(u64::from(c.width), u64::from(c.height))?;
        Ok(c)
    }

    /// A camera at `position` looking at `look_at` with `up` on top, vertical field of view
    /// `fov_y` (radians) and `width` x `height` pixels.
    pub fn look_at(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraProblem> {
        if !(position.is_finite() && look_at.is_finite() && up.is_finite()) {
            return Err(CameraProblem::NonFinite);
        }
        let view = look_at - position;
        if view.length_squared() == 0.0 || !view.length_squared().is_finite() {
            return Err(CameraProblem::NoViewDirection);
        }
        let forward = view.normalize();
        let right = forward.cross(up);
        // |forward x up| relative to |up|: the sine of the angle between them.
        let sine = right.length();
        if sine.is_nan() || sine <= 1e-6 * up.length() {
            return Err(CameraProblem::UpParallelToView);
        }
        let right = right.normalize();
        let fov_deg = fov_y.to_degrees();
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraProblem::FieldOfView(fov_deg));
        }
        Ok(Self {
            position,
            forward,
            right,
            up: right.cross(forward),
            fov_y,
            width: width.max(1),
            height: height.max(1),
        })
    }

    /// The same camera at another resolution. Given one dimension alone, the other follows the
    /// current aspect ratio (rounded, at least 1).
    pub fn with_resolution(mut self, width: Option<u32>, height: Option<u32>) -> Self {
        let aspect = self.width as f64 / self.height as f64;
        let (w, h) = match (width, height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, (w as f64 / aspect).round().max(1.0) as u32),
            (None, Some(h)) => ((h as f64 * aspect).round().max(1.0) as u32, h),
            (None, None) => (self.width, self.height),
        };
        self.width = w.max(1);
        self.height = h.max(1);
        self
    }

    /// Unit direction through the continuous image position `pixel` (pixels from the top-left
    /// corner; pixel centres at half-integers).
    pub fn direction(&self, pixel: Vec2) -> Vec3 {
        self.rays().direction(pixel)
    }

    /// [`Camera::direction`] with what every ray of the camera shares worked out once (the
    /// field of view's tangent), for a render loop that makes many.
    pub fn rays(&self) -> CameraRays {
        CameraRays {
            camera: *self,
            tan: (self.fov_y * 0.5).tan(),
        }
    }

    /// The continuous image position where a world direction from the eye lands, or `None`
    /// behind the camera. Inverse of [`Camera::direction`].
    pub fn project(&self, dir: Vec3) -> Option<Vec2> {
        let z = dir.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let tan = (self.fov_y * 0.5).tan();
        let h = self.height as f32;
        let sx = dir.dot(self.right) / z / tan;
        let sy = dir.dot(self.up) / z / tan;
        Some(Vec2::new(
            (sx * h + self.width as f32) * 0.5,
            (h - sy * h) * 0.5,
        ))
    }
}

/// A camera's ray directions ([`Camera::rays`]).
#[derive(Debug, Clone, Copy)]
pub struct CameraRays {
    camera: Camera,
    /// tan(fov_y / 2).
    tan: f32,
}

impl CameraRays {
    /// Unit direction through the continuous image position `pixel` (pixels from the top-left
    /// corner; pixel centres at half-integers): [`Camera::direction`].
    #[inline]
    pub fn direction(&self, pixel: Vec2) -> Vec3 {
        let c = &self.camera;
        let h = c.height as f32;
        let sx = (2.0 * pixel.x - c.width as f32) / h * self.tan;
        let sy = (h - 2.0 * pixel.y) / h * self.tan;
        (c.forward + c.right * sx + c.up * sy).normalize()
    }
}

/// What is wrong with a camera.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CameraProblem {
    /// `up` is parallel to the viewing direction (or zero), so the image has no orientation.
    UpParallelToView,
    /// `position` equals `look_at`, so there is no viewing direction.
    NoViewDirection,
    /// The vertical field of view (degrees) is not in (0, 180).
    FieldOfView(f32),
    /// The focal length or film size (mm) is not finite and > 0.
    Lens(f32),
    /// Both `fov_y` and `focal_length` were given.
    FovAndFocalLength,
    /// A position, target or up vector has a NaN or infinite component.
    NonFinite,
    /// The image would have more pixels than [`Camera::MAX_PIXELS`] or a side longer
    /// than [`Camera::MAX_SIDE`].
    Resolution {
        /// Requested width, pixels.
        width: u64,
        /// Requested height, pixels.
        height: u64,
    },
}

impl fmt::Display for CameraProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UpParallelToView => write!(f, "`up` is zero or parallel to the view direction"),
            Self::NoViewDirection => write!(f, "`position` equals `look_at`"),
            Self::FieldOfView(v) => write!(f, "`fov_y` = {v} degrees must be in (0, 180)"),
            Self::Lens(v) => write!(
                f,
                "focal length and film size must be finite and > 0 mm, got {v}"
            ),
            Self::FovAndFocalLength => write!(f, "give either `fov_y` or `focal_length`, not both"),
            Self::NonFinite => write!(f, "a position or direction is not finite"),
            Self::Resolution { width, height } => write!(
                f,
                "resolution {width} x {height} is out of range: each side must be 1 to {} pixels and the image at most {} pixels (8K UHD, 7680 x 4320, fits; a square at most {} x {})",
                Camera::MAX_SIDE,
                Camera::MAX_PIXELS,
                Camera::MAX_PIXELS_SQUARE,
                Camera::MAX_PIXELS_SQUARE
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Camera {
        let fov = 2.0 * (12.5_f32 / 35.0).atan();
        Camera::look_at(
            Vec3::new(278.0, 273.0, -800.0),
            Vec3::new(278.0, 273.0, 0.0),
            Vec3::Y,
            fov,
            512,
            512,
        )
        .unwrap()
    }

    #[test]
    fn centre_pixel_looks_forward_and_corners_span_the_fov() {
        let c = cornell();
        assert!(
            c.direction(Vec2::new(256.0, 256.0))
                .abs_diff_eq(Vec3::Z, 1e-6)
        );
        // Top edge centre: 12.5 mm over 35 mm focal length.
        let top = c.direction(Vec2::new(256.0, 0.0));
        assert!((top.y / top.z - 12.5 / 35.0).abs() < 1e-6);
        // Right-handed: looking +z with +y up, image right is -x.
        assert!(c.right.abs_diff_eq(-Vec3::X, 1e-6));
        assert!(c.direction(Vec2::new(512.0, 256.0)).x < 0.0);
    }

    #[test]
    fn project_inverts_direction() {
        let c = cornell();
        for p in [
            Vec2::new(0.5, 0.5),
            Vec2::new(100.25, 400.0),
            Vec2::new(511.5, 3.0),
        ] {
            assert!(c.project(c.direction(p)).unwrap().abs_diff_eq(p, 1e-3));
        }
        assert!(c.project(-Vec3::Z).is_none());
    }

    #[test]
    fn one_dimension_keeps_aspect() {
        let c = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 1.0, 640, 480).unwrap();
        let r = c.with_resolution(Some(320), None);
        assert_eq!((r.width, r.height), (320, 240));
        let r = c.with_resolution(None, Some(960));
        assert_eq!((r.width, r.height), (1280, 960));
    }

    #[test]
    fn bad_cameras_are_refused() {
        assert_eq!(
            Camera::look_at(Vec3::ZERO, Vec3::Y * 5.0, Vec3::Y, 1.0, 1, 1),
            Err(CameraProblem::UpParallelToView)
        );
        assert_eq!(
            Camera::look_at(Vec3::ONE, Vec3::ONE, Vec3::Y, 1.0, 1, 1),
            Err(CameraProblem::NoViewDirection)
        );
        assert!(matches!(
            Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 3.2, 1, 1),
            Err(CameraProblem::FieldOfView(_))
        ));
    }
}
