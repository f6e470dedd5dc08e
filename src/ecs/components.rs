//! Components of scene entities: pure data, written by the reload system with `set_if_neq`.
//!
//! ```ron
//! Entity(name: "ball", material: "glass",
//!        shape: Sphere(center: (0, 1, 0), radius: 1),
//!        transform: Transform(translate: (2, 0, 0), rotate: (0, 45, 0), scale: (1, 1, 1)))
//! ```

use bevy_ecs::component::Component;
use glam::{Affine3A, EulerRot, Mat3, Quat, Vec3};

/// The entity's name in the scene file; the key by which reloads match entities.
#[derive(Component, Clone, Debug, PartialEq, Eq, Hash)]
pub struct EntityName(pub String);

/// Geometry of an entity in object space. Validated by the loader: finite, non-degenerate.
#[derive(Component, Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
    },
    /// An infinite plane.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
    },
    /// A triangle; geometric normal `(b − a) × (c − a)`.
    Triangle {
        /// First vertex.
        a: Vec3,
        /// Second vertex.
        b: Vec3,
        /// Third vertex.
        c: Vec3,
    },
    /// A quad `a b c d`, split into triangles `abc` and `acd`; geometric normal `(b − a) × (c − a)`.
    Quad {
        /// First corner.
        a: Vec3,
        /// Second corner.
        b: Vec3,
        /// Third corner.
        c: Vec3,
        /// Fourth corner.
        d: Vec3,
    },
    /// An axis-aligned box (six quads with outward normals) before its transform.
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
}

/// Placement of an entity: `world = T · R · S · object`.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Translation.
    pub translate: Vec3,
    /// Rotation in degrees about x, then y, then z (right-handed).
    pub rotate: Vec3,
    /// Scale per axis (non-zero).
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            translate: Vec3::ZERO,
            rotate: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl Transform {
    /// The rotation part, object to world.
    pub fn rotation(&self) -> Mat3 {
        let r = self.rotate * (std::f32::consts::PI / 180.0);
        // x first, then y, then z: R = Rz · Ry · Rx.
        Mat3::from_quat(Quat::from_euler(EulerRot::ZYX, r.z, r.y, r.x))
    }

    /// `world_from_object = T · R · S`.
    pub fn world_from_object(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            self.rotation() * Mat3::from_diagonal(self.scale),
            self.translate,
        )
    }

    /// Whether the scale is the same on all axes (up to sign), so spheres stay spheres.
    pub fn is_uniform(&self) -> bool {
        let s = self.scale.abs();
        (s.x - s.y).abs() <= 1e-6 * s.x && (s.x - s.z).abs() <= 1e-6 * s.x
    }
}

/// Name of the material in the scene's material table.
#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub struct MaterialRef(pub String);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_about_y_matches_rtiow() {
        // +θ about y maps (x, z) to (x cosθ + z sinθ, −x sinθ + z cosθ).
        let t = Transform {
            rotate: Vec3::new(0.0, 30.0, 0.0),
            ..Default::default()
        };
        let p = t
            .world_from_object()
            .transform_point3(Vec3::new(1.0, 0.0, 2.0));
        let (s, c) = 30f32.to_radians().sin_cos();
        assert!(
            (p - Vec3::new(c + 2.0 * s, 0.0, -s + 2.0 * c)).length() < 1e-5,
            "{p}"
        );
    }

    #[test]
    fn rotations_apply_x_then_y_then_z() {
        let t = Transform {
            rotate: Vec3::new(90.0, 90.0, 0.0),
            ..Default::default()
        };
        // Rx(90): y → z; then Ry(90): z → x.
        let p = t.world_from_object().transform_point3(Vec3::Y);
        assert!((p - Vec3::X).length() < 1e-6, "{p}");
    }

    #[test]
    fn translate_rotate_scale_compose_in_that_order() {
        let t = Transform {
            translate: Vec3::new(10.0, 0.0, 0.0),
            rotate: Vec3::new(0.0, 0.0, 90.0),
            scale: Vec3::new(2.0, 1.0, 1.0),
        };
        // S: (1,0,0) → (2,0,0); Rz(90): → (0,2,0); T: → (10,2,0).
        let p = t.world_from_object().transform_point3(Vec3::X);
        assert!((p - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
    }
}
