//! The sphere: ray intersection, surface parameterisation, and the sampling of points on it that
//! light sampling uses (uniformly by area, or in the cone it subtends).

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::ray::{Ray, gamma};
use crate::shading::sampling::{Frame, unit_circle};

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
/// from inside) with x mirrored, because a sphere is seen from outside (the 2020 ray-tracing thesis
/// in `../shared/seed/` puts the pole on +z and shows the image mirrored).
#[inline]
pub fn sphere_uv(unit: Vec3) -> Vec2 {
    let u = (-unit.x).atan2(-unit.z) / (2.0 * PI);
    let u = if u < 0.0 { u + 1.0 } else { u };
    // atan2 of (−0, −1) is −π: u + 1 then rounds to 1, the same seam as 0.
    let u = if u >= 1.0 { 0.0 } else { u };
    Vec2::new(u, 1.0 - unit.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The outward unit normal of a point uniformly distributed by area on a sphere (the point is
/// `centre + radius · normal`), from the uniform pair `u`.
#[inline]
pub fn sample_sphere_area(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let phi = unit_circle(u.y);
    Vec3::new(s * phi.x, s * phi.y, z)
}

/// Absolute error bound, per component, of a point computed on the sphere of centre `c` and
/// radius `r` (pbrt-v4, Section 6.8.5).
#[inline(always)]
pub fn sphere_point_error(c: Vec3, r: f32) -> Vec3 {
    gamma(6.0) * (c.abs() + Vec3::splat(r))
}

/// `1 − cos θmax` of the cone that a sphere subtends from a point outside it, given
/// `sin² θmax = r² / d²`. Small cones use the Taylor form `sin² θmax / 2`, which keeps its
/// precision where `1 − √(1 − s)` would cancel (pbrt-v4, `Sphere::Sample`). The cone's solid
/// angle is `2π` times this; [`sample_sphere_cone`] uses the same value.
#[inline]
pub fn cone_one_minus_cos(sin2_max: f32) -> f32 {
    if sin2_max < SMALL_CONE_SIN2 {
        0.5 * sin2_max
    } else {
        1.0 - (1.0 - sin2_max).max(0.0).sqrt()
    }
}

/// sin² of 1.5°: below it the cone is sampled by its Taylor expansion.
const SMALL_CONE_SIN2: f32 = 0.000_685_23;

/// A point on the part of the sphere (centre `c`, radius `r`) visible from `p`, which must lie
/// outside it, chosen uniformly in the solid angle of the cone the sphere subtends (pbrt-v4,
/// `Sphere::Sample`): density `1 / (2π · cone_one_minus_cos(r²/|c − p|²))` per steradian.
/// Returns the point and the sphere's outward unit normal there.
///
/// pbrt-v4's construction with fewer divisions and roots (this was a tenth of Veach's scene):
/// `sin²θ / sin θmax` and `sin²θ / sin²θmax` from one quotient `x = sin²θ / sin²θmax` (which is
/// `u.x` itself for a small cone), `cos θ` of a wide cone taken as sampled rather than
/// recomputed from `sin²θ`, the axis scaled by one reciprocal, and the normal left as the
/// orthonormal frame builds it (unit to rounding, as a normalised vector is). Always inlined,
/// so that the light sample shares the distance and `sin²θmax` its strategy computed.
#[inline(always)]
pub fn sample_sphere_cone(c: Vec3, r: f32, p: Vec3, u: Vec2) -> (Vec3, Vec3) {
    let to_centre = c - p;
    let dc2 = to_centre.length_squared();
    let sin2_max = r * r / dc2;
    let sin_max = sin2_max.sqrt();
    // cos θ of the sampled direction, and x = sin²θ / sin²θmax.
    let (cos_t, x) = if sin2_max < SMALL_CONE_SIN2 {
        ((1.0 - sin2_max * u.x).max(0.0).sqrt(), u.x)
    } else {
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let cos_t = (cos_max - 1.0) * u.x + 1.0;
        (cos_t, (1.0 - cos_t * cos_t) / sin2_max)
    };
    // Angle at the centre between the axis and the sampled point: cos α = sin²θ / sin θmax +
    // cos θ √(1 − sin²θ / sin²θmax), with sin²θ / sin θmax = x · sin θmax.
    let cos_alpha = x * sin_max + cos_t * (1.0 - x).max(0.0).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = unit_circle(u.y);
    let frame = Frame::from_normal(to_centre * (1.0 / dc2.sqrt()));
    let n = frame.to_world(-Vec3::new(sin_alpha * phi.x, sin_alpha * phi.y, cos_alpha));
    (c + r * n, n)
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

    /// Sampled density = evaluated density for the cone: seen from `p`, the sampled points'
    /// directions have `(1 − cos θ) / (1 − cos θmax)` and the azimuth about the axis uniform
    /// and independent (what a uniform density in the cone's solid angle means), by Pearson's
    /// χ² over a 10 × 10 grid, with θ measured in `f64` from the returned points. Far and
    /// near spheres, the Taylor branch of small cones included.
    #[test]
    fn cone_samples_are_uniform_in_the_cones_solid_angle() {
        let (c, r) = (Vec3::new(0.3, -0.2, 0.5), 0.7f32);
        let mut rng = crate::shading::rng::Rng::new(11, 3);
        for d in [0.75f32, 1.5, 8.0, 200.0] {
            let p = c + d * Vec3::new(0.48, 0.6, 0.64);
            let axis = (c - p).as_dvec3().normalize();
            let one_minus_cos_max = f64::from(cone_one_minus_cos(r * r / (d * d)));
            let s_axis = axis.any_orthonormal_vector();
            let t_axis = axis.cross(s_axis);
            let (bins, n) = (10usize, 100_000usize);
            let mut counts = vec![0usize; bins * bins];
            for _ in 0..n {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let (q, normal) = sample_sphere_cone(c, r, p, u);
                assert!(
                    ((q - c).length() - r).abs() < 1e-5 * r.max(1.0),
                    "d = {d}: {q}"
                );
                assert!((normal - (q - c) / r).length() < 1e-4, "d = {d}");
                let w = (q - p).as_dvec3().normalize();
                let cos = w.dot(axis);
                // 1 − cos θ = sin²θ / (1 + cos θ), without the cancellation near the axis.
                let x = w.cross(axis).length_squared() / (1.0 + cos) / one_minus_cos_max;
                let phi = w
                    .dot(t_axis)
                    .atan2(w.dot(s_axis))
                    .rem_euclid(std::f64::consts::TAU);
                let i = ((x * bins as f64) as usize).min(bins - 1);
                let j = ((phi / std::f64::consts::TAU * bins as f64) as usize).min(bins - 1);
                assert!(x < 1.0 + 1e-3, "d = {d}: outside the cone, x = {x}");
                counts[i * bins + j] += 1;
            }
            let expected = n as f64 / (bins * bins) as f64;
            let chi2: f64 = counts
                .iter()
                .map(|&o| (o as f64 - expected).powi(2) / expected)
                .sum();
            // The 99.9th percentile of χ² with 99 degrees of freedom is 148.2.
            assert!(chi2 < 148.2, "d = {d}: χ² = {chi2}");
        }
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
