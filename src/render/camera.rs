//! The camera: position, view direction, up vector and vertical field of view; a pinhole, or a
//! thin lens with an aperture and a focus distance.

use glam::{Vec2, Vec3};

use crate::geometry::ray::Ray;
use crate::shading::sampling::concentric_disk;

/// A pinhole or thin-lens camera. Image x grows to the right of the view, image y downwards.
///
/// The thin lens (pbrt-v4 §5.2.3) is a disk of radius `lens_radius` around the eye,
/// perpendicular to the view: every ray through a film position passes through the point the
/// pinhole ray of that position meets on the plane of focus (perpendicular to the view, at
/// `focus_distance` along it), so that plane is sharp, and a point at depth `z` is spread over a
/// disk of radius `lens_radius · |1 − focus_distance / z|` on it (the circle of confusion).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// `tan(fov / 2)`.
    half_height: f32,
    /// Radius of the lens; 0 for a pinhole.
    lens_radius: f32,
    /// Distance of the plane of focus along the view direction.
    focus_distance: f32,
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
            lens_radius: 0.0,
            focus_distance: 1.0,
        }
    }

    /// The camera with a thin lens of radius `lens_radius` ≥ 0 (0 keeps the pinhole) focused at
    /// `focus_distance` > 0 along the view.
    pub fn with_lens(self, lens_radius: f32, focus_distance: f32) -> Self {
        Self {
            lens_radius,
            focus_distance,
            ..self
        }
    }

    /// The depth of point `p`: its distance from the eye along the view direction, the
    /// `focus_distance` that makes it sharp.
    #[inline]
    pub fn depth(&self, p: Vec3) -> f32 {
        (p - self.position).dot(self.forward)
    }

    /// Whether rays start on a lens of non-zero radius (and so need a lens sample).
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// The ray through film position `(x, y)` (as [`Camera::ray`]) from lens position `u` ∈
    /// [0, 1)², mapped onto the lens disk (concentric mapping); the pinhole ray if there is no
    /// lens. Always inlined, as [`crate::sky::Sun::sample`] is: once per camera ray.
    #[inline(always)]
    pub fn lens_ray(&self, x: f32, y: f32, width: u32, height: u32, u: Vec2) -> Ray {
        let pinhole = self.ray(x, y, width, height);
        if !self.has_lens() {
            return pinhole;
        }
        let d = pinhole.direction;
        let focus = self.position + d * (self.focus_distance / d.dot(self.forward));
        let disk = self.lens_radius * concentric_disk(u);
        let origin = self.position + disk.x * self.right + disk.y * self.up;
        Ray::new(origin, (focus - origin).normalize())
    }

    /// Where light leaving point `p` towards the lens reaches the film of a `width` × `height`
    /// image, for light tracing's connection to the camera (pbrt-v4's `Camera::SampleWi`): the
    /// lens point (the eye for a pinhole; for a thin lens the point `u` ∈ [0, 1)² maps to, as
    /// in [`Camera::lens_ray`]), the continuous film position of the ray from that point
    /// through `p`, and the camera's importance per steradian at the lens point for a pixel of
    /// the film: `1 / (A cos³θ)`, A the area of one pixel on the plane at distance 1 and θ the
    /// ray's angle to the view. A thin lens's own density (uniform over its area) cancels the
    /// importance's `1 / lens area`, so the same value holds for both. `None` if `p` is behind
    /// the lens or off the film.
    #[inline]
    pub fn importance(&self, p: Vec3, width: u32, height: u32, u: Vec2) -> Option<Importance> {
        let lens = if self.has_lens() {
            let disk = self.lens_radius * concentric_disk(u);
            self.position + disk.x * self.right + disk.y * self.up
        } else {
            self.position
        };
        let to = p - lens;
        let depth = to.dot(self.forward);
        if !(depth > 0.0 && depth.is_finite()) {
            return None;
        }
        // The pinhole direction of the film position: towards where the ray meets the plane
        // of focus (the ray's own direction for a pinhole).
        let d = if self.has_lens() {
            lens + to * (self.focus_distance / depth) - self.position
        } else {
            to
        };
        let forward = d.dot(self.forward);
        let (sx, sy) = (d.dot(self.right) / forward, d.dot(self.up) / forward);
        let aspect = width as f32 / height as f32;
        let x = (sx / (self.half_height * aspect) + 1.0) * 0.5 * width as f32;
        let y = (1.0 - sy / self.half_height) * 0.5 * height as f32;
        if !(x >= 0.0 && x < width as f32 && y >= 0.0 && y < height as f32) {
            return None;
        }
        let distance = to.length();
        let cos = depth / distance;
        let pixel_area =
            4.0 * self.half_height * self.half_height * aspect / (width as f32 * height as f32);
        Some(Importance {
            lens,
            film: Vec2::new(x, y),
            importance: 1.0 / (pixel_area * cos * cos * cos),
        })
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

/// A point's connection to the camera ([`Camera::importance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Importance {
    /// The point on the lens (the eye of a pinhole).
    pub lens: Vec3,
    /// The film position, in pixels.
    pub film: Vec2,
    /// The importance per steradian at `lens`, for the pixel the position is in.
    pub importance: f32,
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
    fn lens_rays_meet_on_the_plane_of_focus_and_leave_from_the_lens() {
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0).with_lens(0.5, 4.0);
        let pin = cam.ray(30.0, 70.0, 100, 100);
        let focus = pin.direction * (4.0 / pin.direction.z);
        for u in [
            Vec2::new(0.1, 0.9),
            Vec2::new(0.7, 0.2),
            Vec2::new(0.5, 0.5),
        ] {
            let r = cam.lens_ray(30.0, 70.0, 100, 100, u);
            assert!(r.origin.z.abs() < 1e-6 && r.origin.length() <= 0.5 + 1e-6);
            let t = (4.0 - r.origin.z) / r.direction.z;
            assert!((r.origin + t * r.direction - focus).length() < 1e-5);
        }
        let pinhole = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0);
        assert!(!pinhole.has_lens());
        assert_eq!(
            pinhole.lens_ray(3.0, 4.0, 10, 10, Vec2::splat(0.3)),
            pinhole.ray(3.0, 4.0, 10, 10)
        );
    }

    #[test]
    fn importance_inverts_the_camera_rays() {
        // A point on the ray through a film position lands back on that position, from the
        // eye and from any lens point (which the ray through the film position and that lens
        // point passes through).
        for cam in [
            Camera::new(Vec3::ZERO, Vec3::new(0.2, -0.1, 1.0), Vec3::Y, 40.0),
            Camera::new(Vec3::ONE, Vec3::Z, Vec3::Y, 60.0).with_lens(0.3, 5.0),
        ] {
            let u = Vec2::new(0.8, 0.3);
            let r = cam.lens_ray(37.25, 11.5, 64, 48, u);
            let p = r.origin + 7.0 * r.direction;
            let i = cam.importance(p, 64, 48, u).expect("in view");
            assert!(
                (i.film - Vec2::new(37.25, 11.5)).length() < 1e-3,
                "{}",
                i.film
            );
            assert!((i.lens - r.origin).length() < 1e-5);
            assert!(cam.importance(r.origin - r.direction, 64, 48, u).is_none());
        }
        // At the centre, a pixel of a 90° square image of 2×2 pixels covers 1 on the plane at
        // distance 1: importance 1.
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0);
        let i = cam.importance(Vec3::Z, 2, 2, Vec2::ZERO).expect("in view");
        assert!((i.importance - 1.0).abs() < 1e-6);
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
