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

/// Texture coordinates of a point on the unit sphere (its outward normal `unit`, in object
/// space): latitude–longitude with the pole on **+y**, the image's top row at the north pole and
/// its centre column facing +z, unmirrored seen from outside:
/// `u = atan2(−x, −z) / 2π` wrapped into [0, 1), `v = 1 − acos(y) / π` (v = 1 is the image's top
/// row). This is the environment maps' convention (`u = atan2(x, −z) / 2π`, for a direction seen
/// from inside) with x mirrored, because a sphere is seen from outside. (The thesis's formula put
/// the pole on +z and showed the image mirrored.)
#[inline]
pub fn sphere_uv(unit: Vec3) -> Vec2 {
    let u = (-unit.x).atan2(-unit.z) / (2.0 * PI);
    let u = if u < 0.0 { u + 1.0 } else { u };
    // atan2 of (−0, −1) is −π: u + 1 then rounds to 1, the same seam as 0.
    let u = if u >= 1.0 { 0.0 } else { u };
    Vec2::new(u, 1.0 - unit.y.clamp(-1.0, 1.0).acos() / PI)
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
    fn uv_is_latitude_longitude_about_y_and_unmirrored_from_outside() {
        // The north pole is the image's top row (v = 1), the south pole its bottom row.
        assert!((sphere_uv(Vec3::Y).y - 1.0).abs() < 1e-6);
        assert!(sphere_uv(-Vec3::Y).y.abs() < 1e-6);
        // The equator is v = ½; +z faces the image's centre column, −z the seam.
        let uv = sphere_uv(Vec3::Z);
        assert!((uv - Vec2::new(0.5, 0.5)).length() < 1e-6, "{uv}");
        assert!(sphere_uv(-Vec3::Z).x < 1e-6);
        assert!((sphere_uv(-Vec3::X).x - 0.25).abs() < 1e-6);
        assert!((sphere_uv(Vec3::X).x - 0.75).abs() < 1e-6);
        // Seen from outside, u grows to the right (the camera's right is forward × up): from
        // +z (right = +x), from −x (right = +z) and from +x (right = −z).
        let u = |n: Vec3| sphere_uv(n.normalize()).x;
        assert!(u(Vec3::new(0.1, 0.0, 1.0)) > u(Vec3::new(-0.1, 0.0, 1.0)));
        assert!(u(Vec3::new(-1.0, 0.0, 0.1)) > u(Vec3::new(-1.0, 0.0, -0.1)));
        assert!(u(Vec3::new(1.0, 0.0, -0.1)) > u(Vec3::new(1.0, 0.0, 0.1)));
        // The same as the environment map's u for the direction mirrored in x.
        for d in [
            Vec3::new(0.3, 0.2, -0.9),
            Vec3::new(-0.7, -0.1, 0.2),
            Vec3::new(0.5, 0.5, 0.5),
        ] {
            let d = d.normalize();
            let env = d.x.atan2(-d.z) / (2.0 * PI);
            let env = if env < 0.0 { env + 1.0 } else { env };
            assert!(
                (sphere_uv(Vec3::new(-d.x, d.y, d.z)).x - env).abs() < 1e-6,
                "{d}"
            );
        }
    }
}
