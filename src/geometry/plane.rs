//! Ray–plane intersection. Planes are infinite and live outside the BVH.

use glam::{Vec2, Vec3};

use super::ray::Ray;

/// Distance along `ray` to the plane through `point` with unit `normal`, if in `(0, t_max)`.
///
/// Rays parallel to the plane, including rays lying in it, miss: the division by a zero
/// denominator yields ±∞ or NaN, and both fail the range comparison.
#[inline(always)]
pub fn intersect_plane(ray: &Ray, point: Vec3, normal: Vec3, t_max: f32) -> Option<f32> {
    let denom = ray.direction.dot(normal);
    let t = (point - ray.origin).dot(normal) / denom;
    (t > 0.0 && t < t_max).then_some(t)
}

/// Planar texture coordinates: the hit point's offset from `point`, expressed in an orthonormal
/// frame `(tangent, bitangent)` of the plane.
#[inline]
pub fn plane_uv(p: Vec3, point: Vec3, tangent: Vec3, bitangent: Vec3) -> Vec2 {
    let d = p - point;
    Vec2::new(d.dot(tangent), d.dot(bitangent))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perpendicular_ray_hits_at_the_distance() {
        let ray = Ray::new(Vec3::new(1.0, 3.0, 2.0), -Vec3::Y);
        assert_eq!(
            intersect_plane(&ray, Vec3::ZERO, Vec3::Y, f32::INFINITY),
            Some(3.0)
        );
    }

    #[test]
    fn parallel_and_in_plane_rays_miss_without_nan() {
        let parallel = Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::X);
        assert_eq!(
            intersect_plane(&parallel, Vec3::ZERO, Vec3::Y, f32::INFINITY),
            None
        );
        let in_plane = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(
            intersect_plane(&in_plane, Vec3::ZERO, Vec3::Y, f32::INFINITY),
            None
        );
    }

    #[test]
    fn plane_behind_is_missed() {
        let ray = Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::Y);
        assert_eq!(
            intersect_plane(&ray, Vec3::ZERO, Vec3::Y, f32::INFINITY),
            None
        );
    }
}
