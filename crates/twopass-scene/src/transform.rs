//! Object-to-world transforms: scale, then rotations in order, then translation.

use glam::{DMat3, DMat4, Mat3, Mat4, Quat, Vec3};

/// An affine object-to-world transform with its normal matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Point transform.
    pub matrix: Mat4,
    /// Normal transform: inverse transpose of the linear part.
    pub normal: Mat3,
    /// Whether the transform mirrors (negative determinant): triangle winding is flipped back.
    pub flips: bool,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            matrix: Mat4::IDENTITY,
            normal: Mat3::IDENTITY,
            flips: false,
        }
    }
}

impl Transform {
    /// Builds `T * R_n * ... * R_1 * S`. Rotation axes need not be unit; angles in degrees.
    /// Fails with a description when a value is not finite, an axis is zero or the scale is 0.
    pub fn new(scale: Vec3, rotations: &[(Vec3, f32)], translate: Vec3) -> Result<Self, String> {
        if !scale.is_finite() || !translate.is_finite() {
            return Err("transform has a NaN or infinite scale or translation".into());
        }
        if scale.abs().min_element() == 0.0 {
            return Err(format!("transform scale {scale} has a zero component"));
        }
        let mut rot = Quat::IDENTITY;
        for &(axis, degrees) in rotations {
            if !axis.is_finite() || !degrees.is_finite() || axis.length_squared() == 0.0 {
                return Err(format!(
                    "rotation axis {axis} by {degrees} degrees is zero or not finite"
                ));
            }
            rot = Quat::from_axis_angle(axis.normalize(), degrees.to_radians()) * rot;
        }
        let matrix = Mat4::from_scale_rotation_translation(scale, rot, translate);
        // The linear part is R S with R a rotation: its determinant is the product of the
        // scales (in f64, where it cannot overflow) and its inverse transpose is R S^-1, exact
        // without forming a determinant in f32.
        let det = scale.as_dvec3().element_product();
        let inverse_scale = scale.recip();
        if !inverse_scale.is_finite() {
            return Err(format!("transform scale {scale} is too small to invert"));
        }
        Ok(Self {
            matrix,
            normal: Mat3::from_quat(rot) * Mat3::from_diagonal(inverse_scale),
            flips: det < 0.0,
        })
    }

    /// Any affine transform given as its matrix (a glTF node's world matrix), in f64 so that
    /// a product of a deep hierarchy keeps its precision until this one rounding. Fails with
    /// a description when a value is not finite, the matrix is not affine (its last row is not
    /// 0, 0, 0, 1) or its linear part is singular (a zero scale).
    pub fn from_matrix(m: DMat4) -> Result<Self, String> {
        if !m.is_finite() {
            return Err("transform has a NaN or infinite entry".into());
        }
        if m.row(3) != glam::DVec4::W {
            return Err(format!(
                "transform is not affine (its last row is {} instead of 0, 0, 0, 1)",
                m.row(3)
            ));
        }
        let linear = DMat3::from_mat4(m);
        let det = linear.determinant();
        let scale = [linear.x_axis, linear.y_axis, linear.z_axis].map(|a| a.length());
        let largest = scale.iter().fold(0.0_f64, |a, &b| a.max(b));
        // Singular, or so flat that its inverse carries no precision in f32.
        if det == 0.0 || det.abs() <= largest.powi(3) * 1e-12 {
            return Err(format!(
                "transform's linear part is singular (a zero scale; determinant {det:e})"
            ));
        }
        let normal = linear.inverse().transpose();
        let matrix = m.as_mat4();
        let normal = normal.as_mat3();
        if !matrix.is_finite() || !normal.is_finite() {
            return Err("transform does not fit single precision".into());
        }
        Ok(Self {
            matrix,
            normal,
            flips: det < 0.0,
        })
    }

    /// Transforms a point.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.matrix.transform_point3(p)
    }

    /// Transforms a unit normal and renormalizes it.
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal * n).normalize_or_zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_is_scale_rotate_translate() {
        let t = Transform::new(
            Vec3::new(2.0, 1.0, 1.0),
            &[(Vec3::Y, 90.0)],
            Vec3::new(0.0, 0.0, 10.0),
        )
        .unwrap();
        // x scaled to 2, rotated +90 deg about y (x -> -z), then moved by +10 z.
        assert!(t.point(Vec3::X).abs_diff_eq(Vec3::new(0.0, 0.0, 8.0), 1e-5));
        assert!(!t.flips);
    }

    #[test]
    fn rotations_apply_in_order() {
        let t = Transform::new(Vec3::ONE, &[(Vec3::Z, 90.0), (Vec3::X, 90.0)], Vec3::ZERO).unwrap();
        // x -> y (about z), then y -> z (about x).
        assert!(t.point(Vec3::X).abs_diff_eq(Vec3::Z, 1e-6));
    }

    #[test]
    fn normals_stay_perpendicular_under_nonuniform_scale() {
        let t = Transform::new(Vec3::new(1.0, 4.0, 1.0), &[(Vec3::Z, 30.0)], Vec3::ZERO).unwrap();
        // A plane x + y = 0 has normal (1,1,0)/sqrt2 and contains the tangent (1,-1,0).
        let n = t.normal(Vec3::new(1.0, 1.0, 0.0).normalize());
        let tangent = t.point(Vec3::new(1.0, -1.0, 0.0)) - t.point(Vec3::ZERO);
        assert!(n.dot(tangent).abs() < 1e-5);
        assert!((n.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn mirroring_and_bad_values() {
        assert!(
            Transform::new(Vec3::new(-1.0, 1.0, 1.0), &[], Vec3::ZERO)
                .unwrap()
                .flips
        );
        assert!(Transform::new(Vec3::new(0.0, 1.0, 1.0), &[], Vec3::ZERO).is_err());
        assert!(Transform::new(Vec3::ONE, &[(Vec3::ZERO, 10.0)], Vec3::ZERO).is_err());
        assert!(Transform::new(Vec3::ONE, &[], Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
    }
}
