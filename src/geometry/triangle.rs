//! The triangle: watertight ray intersection (the scalar reference kernel), and the sampling of
//! points on it that light sampling uses (uniformly by area, or in the solid angle it subtends).

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::aabb::RayQuery;
use super::ray::gamma;

/// Where a ray crosses a triangle: distance and the barycentric weights of its vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Distance along the ray.
    pub t: f32,
    /// Weight of the second vertex (`b`).
    pub b1: f32,
    /// Weight of the third vertex (`c`); the first vertex's weight is `1 − b1 − b2`.
    pub b2: f32,
}

/// Intersects the ray of `q` with triangle `(p0, p1, p2)` in `(0, t_max)`.
///
/// Woop, Benthin & Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013, in the form of
/// pbrt-v4 (`Triangle::Intersect`): the vertices are moved into a frame where the ray is the +z axis,
/// and the 2D edge functions decide the hit. An edge shared by two triangles evaluates to the same
/// value with opposite sign in both, so a ray can never slip between them. Edge values of exactly
/// zero are recomputed in double precision. The final `t > δt` test rejects hits that rounding
/// could have put behind the origin. Surfaces are two-sided.
#[inline(always)]
pub fn intersect_triangle(
    q: &RayQuery,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_max: f32,
) -> Option<TriangleHit> {
    let (a, b, c) = (q.to_ray_frame(p0), q.to_ray_frame(p1), q.to_ray_frame(p2));
    let mut e0 = b.x * c.y - b.y * c.x;
    let mut e1 = c.x * a.y - c.y * a.x;
    let mut e2 = a.x * b.y - a.y * b.x;
    // Non-short-circuit `|` and `&` throughout: one branch per test instead of one per
    // comparison, whose outcomes a ray's triangles make unpredictable.
    if (e0 == 0.0) | (e1 == 0.0) | (e2 == 0.0) {
        let dop = |px: f32, py: f32, qx: f32, qy: f32| {
            (f64::from(px) * f64::from(qy) - f64::from(py) * f64::from(qx)) as f32
        };
        e0 = dop(b.x, b.y, c.x, c.y);
        e1 = dop(c.x, c.y, a.x, a.y);
        e2 = dop(a.x, a.y, b.x, b.y);
    }
    if ((e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0)) & ((e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0)) {
        return None;
    }
    let det = e0 + e1 + e2;
    let t_scaled = e0 * a.z + e1 * b.z + e2 * c.z;
    let behind_or_beyond = if det < 0.0 {
        (t_scaled >= 0.0) | (t_scaled < t_max * det)
    } else {
        (t_scaled <= 0.0) | (t_scaled > t_max * det)
    };
    if (det == 0.0) | behind_or_beyond {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;

    // Conservative bound on the error of t (pbrt-v4, Section 6.8.4).
    let max_zt = a.z.abs().max(b.z.abs()).max(c.z.abs());
    let delta_z = gamma(3.0) * max_zt;
    let max_xt = a.x.abs().max(b.x.abs()).max(c.x.abs());
    let max_yt = a.y.abs().max(b.y.abs()).max(c.y.abs());
    let delta_x = gamma(5.0) * (max_xt + max_zt);
    let delta_y = gamma(5.0) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t =
        3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t <= delta_t {
        return None;
    }
    Some(TriangleHit {
        t,
        b1: e1 * inv_det,
        b2: e2 * inv_det,
    })
}

/// Area of triangle `[a, b, c]`.
#[inline]
pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

/// Barycentric coordinates of a point uniformly distributed by area on a triangle, from the
/// uniform pair `u`.
#[inline]
pub fn sample_triangle_area(u: Vec2) -> [f32; 3] {
    let su = u.x.sqrt();
    let (b0, b1) = (1.0 - su, u.y * su);
    [b0, b1, 1.0 - b0 - b1]
}

/// Absolute error bound, per component, of the point `b0·a + b1·b + b2·c` of triangle
/// `[a, b, c]` (pbrt-v4, Section 6.8.5).
#[inline(always)]
pub fn triangle_point_error([a, b, c]: [Vec3; 3], [b0, b1, b2]: [f32; 3]) -> Vec3 {
    gamma(7.0) * ((b0 * a).abs() + (b1 * b).abs() + (b2 * c).abs())
}

/// The angle between unit vectors, accurate at both ends of its range (pbrt-v4).
#[inline]
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * (0.5 * (a + b).length()).min(1.0).asin()
    } else {
        2.0 * (0.5 * (b - a).length()).min(1.0).asin()
    }
}

/// The part of `v` orthogonal to unit `w`.
#[inline]
fn gram_schmidt(v: Vec3, w: Vec3) -> Vec3 {
    v - v.dot(w) * w
}

/// Solid angle of triangle `v` seen from `p` (Van Oosterom & Strackee, 1983).
#[inline]
pub fn triangle_solid_angle(v: [Vec3; 3], p: Vec3) -> f32 {
    let [a, b, c] = v.map(|x| (x - p).normalize_or_zero());
    2.0 * a
        .dot(b.cross(c))
        .abs()
        .atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c))
        .abs()
}

/// Barycentric coordinates of a point of triangle `v` chosen uniformly in the solid angle it
/// subtends from `p` (Arvo, "Stratified Sampling of Spherical Triangles", 1995; as in pbrt-v4's
/// `SampleSphericalTriangle`). `solid_angle` must be `triangle_solid_angle(v, p)`: the sub-triangle
/// areas are fractions of it, so the density is exactly `1 / solid_angle` per steradian, the
/// value the light's pdf reports (pbrt-v4 recomputes the area from the angles instead, a second
/// formula for the same quantity). `None` when the triangle is degenerate as seen from `p`.
#[inline]
pub fn sample_spherical_triangle(
    v: [Vec3; 3],
    p: Vec3,
    solid_angle: f32,
    u: Vec2,
) -> Option<[f32; 3]> {
    let [a, b, c] = v.map(|x| (x - p).normalize_or_zero());
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    if [n_ab, n_bc, n_ca].iter().any(|n| n.length_squared() == 0.0) {
        return None;
    }
    let (n_ab, n_ca) = (n_ab.normalize(), n_ca.normalize());
    // The spherical triangle's angle at a. The sub-triangle (a, b, c') of area u.x times the
    // whole fixes c' on the arc a–c; its angles sum to π plus that area.
    let alpha = angle_between(n_ab, -n_ca);
    let area_pi = PI + u.x * solid_angle;
    let (sin_alpha, cos_alpha) = alpha.sin_cos();
    let (sin_area, cos_area) = area_pi.sin_cos();
    let sin_phi = sin_area * cos_alpha - cos_area * sin_alpha;
    let cos_phi = cos_area * cos_alpha + sin_area * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    if cos_bp.is_nan() {
        return None;
    }
    let cos_bp = cos_bp.clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = cos_bp * a + sin_bp * gram_schmidt(c, a).normalize();
    // Then a direction on the arc b–c', uniform in the sub-triangle's area.
    let cos_t = 1.0 - u.y * (1.0 - cp.dot(b));
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let w = cos_t * b + sin_t * gram_schmidt(cp, b).normalize_or_zero();
    // Where the direction meets the triangle's plane, in barycentrics.
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 || !divisor.is_finite() {
        return None;
    }
    let s = p - v[0];
    let b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    let (b1, b2) = if b1 + b2 > 1.0 {
        (b1 / (b1 + b2), b2 / (b1 + b2))
    } else {
        (b1, b2)
    };
    Some([1.0 - b1 - b2, b1, b2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ray::Ray;

    fn q(o: Vec3, d: Vec3) -> RayQuery {
        RayQuery::new(Ray::new(o, d.normalize()))
    }

    const A: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    const B: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    const C: Vec3 = Vec3::new(0.0, 1.0, 0.0);

    #[test]
    fn hit_reports_distance_and_barycentrics() {
        let h = intersect_triangle(
            &q(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z),
            A,
            B,
            C,
            f32::INFINITY,
        )
        .expect("hit");
        assert_eq!(
            h,
            TriangleHit {
                t: 2.0,
                b1: 0.25,
                b2: 0.5
            }
        );
    }

    #[test]
    fn both_sides_are_hit() {
        let h = intersect_triangle(
            &q(Vec3::new(0.25, 0.25, -3.0), Vec3::Z),
            A,
            B,
            C,
            f32::INFINITY,
        );
        assert_eq!(h.map(|h| h.t), Some(3.0));
    }

    #[test]
    fn outside_behind_and_beyond_t_max_miss() {
        let inf = f32::INFINITY;
        assert!(intersect_triangle(&q(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z), A, B, C, inf).is_none());
        assert!(intersect_triangle(&q(Vec3::new(0.2, 0.2, 1.0), Vec3::Z), A, B, C, inf).is_none());
        assert!(intersect_triangle(&q(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), A, B, C, 0.5).is_none());
    }

    #[test]
    fn ray_parallel_to_the_triangle_misses() {
        let h = intersect_triangle(
            &q(Vec3::new(-1.0, 0.2, 0.0), Vec3::X),
            A,
            B,
            C,
            f32::INFINITY,
        );
        assert!(h.is_none());
    }

    #[test]
    fn ray_through_a_vertex_or_an_edge_hits() {
        let inf = f32::INFINITY;
        let h = intersect_triangle(&q(Vec3::new(1.0, 0.0, 1.0), -Vec3::Z), A, B, C, inf);
        assert_eq!(
            h,
            Some(TriangleHit {
                t: 1.0,
                b1: 1.0,
                b2: 0.0
            })
        );
        let h = intersect_triangle(&q(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z), A, B, C, inf);
        assert_eq!(
            h,
            Some(TriangleHit {
                t: 1.0,
                b1: 0.5,
                b2: 0.5
            })
        );
    }

    #[test]
    fn shared_edge_is_watertight_for_random_points_on_it() {
        // Two triangles sharing the diagonal (p, r) of a planar, obliquely oriented quad; rays
        // aimed at points of that diagonal from random origins must hit at least one of them.
        let p = Vec3::new(0.1, 0.2, 0.3);
        let qv = Vec3::new(3.7, 0.4, -1.1);
        let r = Vec3::new(2.9, 2.3, 0.7);
        let s = p + (r - qv);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..20_000 {
            let target = p.lerp(r, next());
            let origin = Vec3::new(next() * 8.0 - 4.0, next() * 8.0 - 4.0, next() * 8.0 + 3.0);
            let query = q(origin, target - origin);
            let hit = intersect_triangle(&query, p, qv, r, f32::INFINITY).is_some()
                || intersect_triangle(&query, p, r, s, f32::INFINITY).is_some();
            assert!(
                hit,
                "ray from {origin} to {target} slipped through the shared edge"
            );
        }
    }
}
