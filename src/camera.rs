//! The pinhole camera: position, view direction, up vector and vertical field of view.

use glam::Vec3;

use crate::geometry::ray::Ray;

/// A pinhole camera. Image x grows to the right of the view, image y downwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// `tan(fov / 2)`.
    half_height: f32,
}

impl Camera {
    /// A camera at `position` looking along `direction` (any length > 0) with vertical field of
    /// view `fov_degrees` in (0, 180). `up` must not be parallel to `direction`; the loader checks
    /// both before calling this.
    pub fn new(position: Vec3, direction: Vec3, up: Vec3, fov_degrees: f32) -> Self {
        let forward = direction.normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Self {
            position,
            forward,
            right,
            up,
            half_height: (0.5 * fov_degrees.to_radians()).tan(),
        }
    }

    /// The ray through film position `(x, y)` in pixels (continuous; (0,0) is the top-left corner
    /// of the top-left pixel) of a `width` × `height` image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * x / width as f32 - 1.0) * self.half_height * aspect;
        let sy = (1.0 - 2.0 * y / height as f32) * self.half_height;
        let d = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.position, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_goes_forward_and_corners_span_the_field_of_view() {
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0);
        let c = cam.ray(50.0, 50.0, 100, 100);
        assert!((c.direction - Vec3::Z).length() < 1e-6);
        // Top edge centre: 45° up.
        let top = cam.ray(50.0, 0.0, 100, 100).direction;
        assert!((top - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn image_right_is_forward_cross_up() {
        // Looking along +z with +y up, the image's right is −x (right-handed), so the Cornell
        // box's x = 555 wall appears on the left.
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0);
        assert!(cam.ray(100.0, 50.0, 100, 100).direction.x < 0.0);
        assert!(cam.ray(0.0, 50.0, 100, 100).direction.x > 0.0);
    }
}
