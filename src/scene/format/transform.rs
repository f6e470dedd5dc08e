//! `Transform(translate, rotate, scale)` as written, and the matrix it stands for.

use glam::{Affine3A, EulerRot, Mat3, Quat, Vec3};
use serde::Deserialize;

use super::number::{V3, or_default};
use crate::scene::error::vector;

/// `Transform(translate, rotate, scale)`: `world = T · R · S · object`, every part optional.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawTransform")]
pub struct TransformDesc {
    /// Translation.
    pub translate: Vec3,
    /// Rotation in degrees about x, then y, then z (right-handed).
    pub rotate: Vec3,
    /// Scale per axis (non-zero).
    pub scale: Vec3,
}

impl Default for TransformDesc {
    fn default() -> Self {
        Self {
            translate: Vec3::ZERO,
            rotate: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl TransformDesc {
    /// `parent_from_object = T · R · S`, with `R = Rz · Ry · Rx` (x applied first).
    pub fn matrix(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            self.rotation() * Mat3::from_diagonal(self.scale),
            self.translate,
        )
    }

    /// The rotation `R = Rz · Ry · Rx` alone.
    pub fn rotation(&self) -> Mat3 {
        let r = self.rotate * (std::f32::consts::PI / 180.0);
        Mat3::from_quat(Quat::from_euler(EulerRot::ZYX, r.z, r.y, r.x))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Transform")]
struct RawTransform {
    translate: Option<V3>,
    rotate: Option<V3>,
    scale: Option<V3>,
}

impl TryFrom<RawTransform> for TransformDesc {
    type Error = String;
    fn try_from(raw: RawTransform) -> Result<Self, String> {
        let d = Self::default();
        let t = Self {
            translate: or_default(raw.translate, d.translate),
            rotate: or_default(raw.rotate, d.rotate),
            scale: or_default(raw.scale, d.scale),
        };
        if t.scale.abs().min_element() < 1e-12 {
            return Err(format!(
                "scale must be non-zero on every axis (got {})",
                vector(t.scale)
            ));
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trs(translate: Vec3, rotate: Vec3, scale: Vec3) -> Affine3A {
        TransformDesc {
            translate,
            rotate,
            scale,
        }
        .matrix()
    }

    #[test]
    fn rotation_about_y_matches_rtiow() {
        // +θ about y maps (x, z) to (x cosθ + z sinθ, −x sinθ + z cosθ).
        let m = trs(Vec3::ZERO, Vec3::new(0.0, 30.0, 0.0), Vec3::ONE);
        let p = m.transform_point3(Vec3::new(1.0, 0.0, 2.0));
        let (s, c) = 30f32.to_radians().sin_cos();
        assert!(
            (p - Vec3::new(c + 2.0 * s, 0.0, -s + 2.0 * c)).length() < 1e-5,
            "{p}"
        );
    }

    #[test]
    fn rotations_apply_x_then_y_then_z() {
        let m = trs(Vec3::ZERO, Vec3::new(90.0, 90.0, 0.0), Vec3::ONE);
        // Rx(90): y → z; then Ry(90): z → x.
        let p = m.transform_point3(Vec3::Y);
        assert!((p - Vec3::X).length() < 1e-6, "{p}");
    }

    #[test]
    fn translate_rotate_scale_compose_in_that_order() {
        let m = trs(
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 90.0),
            Vec3::new(2.0, 1.0, 1.0),
        );
        // S: (1,0,0) → (2,0,0); Rz(90): → (0,2,0); T: → (10,2,0).
        let p = m.transform_point3(Vec3::X);
        assert!((p - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    }
}
