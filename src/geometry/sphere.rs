//! Ray–sphere intersection and the sphere's surface parameterisation.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::ray::Ray;

/// Distance to the nearest intersection of `ray` with the sphere in `(0, t_max)`, or `None`.
///
/// Uses the numerically careful form of Haines et al., "Precision Improvements for Ray/Sphere
/// Intersection", Ray Tracing Gems ch. 7 (2019): the discriminant is computed from the squared
/// distance of the centre to the ray line, which does not cancel catastrophically for distant or
/// small spheres, and the two roots come from the stable quadratic formula.
#[inline(always)]
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: f32, t_max: f32) -> Option<f32> {
    let f = ray.origin - center;
    let b = -f.dot(ray.direction);
    let l = f + b * ray.direction;
    let r2 = radius * radius;
    let disc = r2 - l.length_squared();
    if disc < 0.0 {
        return None;
    }
    let c = f.length_squared() - r2;
    let q = b + disc.sqrt().copysign(b);
    let (mut t0, mut t1) = (c / q, q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > 0.0 && t0 < t_max {
        Some(t0)
    } else if t1 > 0.0 && t1 < t_max {
        Some(t1)
    } else {
        None
    }
}

/// Texture coordinates of a point on the unit sphere, by the thesis's latitude/longitude formula:
/// longitude φ = atan2(y, x) about the z axis, latitude θ = asin(z),
/// `u = 1 − (φ + π) / 2π`, `v = (2θ + π) / 2π`.
#[inline]
pub fn sphere_uv(unit: Vec3) -> Vec2 {
    let phi = unit.y.atan2(unit.x);
    let theta = unit.z.clamp(-1.0, 1.0).asin();
    Vec2::new(
        1.0 - (phi + PI) / (2.0 * PI),
        (2.0 * theta + PI) / (2.0 * PI),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const C: Vec3 = Vec3::new(0.0, 0.0, 5.0);

    #[test]
    fn ray_from_outside_hits_the_near_side() {
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, f32::INFINITY), Some(4.0));
    }

    #[test]
    fn ray_from_inside_hits_the_far_side() {
        let ray = Ray::new(C, Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, f32::INFINITY), Some(1.0));
    }

    #[test]
    fn sphere_behind_the_ray_or_beyond_t_max_is_missed() {
        let ray = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, f32::INFINITY), None);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, 3.9), None);
    }

    #[test]
    fn tangent_ray_touches_once_and_a_slightly_offset_ray_misses() {
        let ray = Ray::new(Vec3::new(1.0, 0.0, 0.0), Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, f32::INFINITY), Some(5.0));
        let ray = Ray::new(Vec3::new(1.0001, 0.0, 0.0), Vec3::Z);
        assert_eq!(intersect_sphere(&ray, C, 1.0, f32::INFINITY), None);
    }

    #[test]
    fn tiny_far_sphere_is_found() {
        // The naive b² − 4ac form loses every digit here.
        let c = Vec3::new(0.0, 0.0, 1e5);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let t = intersect_sphere(&ray, c, 1e-2, f32::INFINITY).expect("hit");
        assert!((t - (1e5 - 1e-2)).abs() <= 1e-2, "{t}");
    }

    #[test]
    fn uv_follows_the_thesis_formula() {
        // North pole: θ = π/2 → v = 1. Point on −x: φ = π → u = 0.
        assert!((sphere_uv(Vec3::Z).y - 1.0).abs() < 1e-6);
        assert!((sphere_uv(-Vec3::Z).y).abs() < 1e-6);
        let uv = sphere_uv(Vec3::new(-1.0, 1e-7, 0.0));
        assert!(uv.x.abs() < 1e-5 && (uv.y - 0.5).abs() < 1e-6, "{uv}");
        let uv = sphere_uv(Vec3::Y); // φ = π/2 → u = 1 − (3π/2)/2π = 0.25
        assert!((uv.x - 0.25).abs() < 1e-6, "{uv}");
    }
}
