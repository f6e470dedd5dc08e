//! Sampling routines: directions on hemispheres and spheres, orthonormal frames, and the
//! solid-angle samplers of lights (the cone a sphere subtends, spherical triangles).

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_4, PI};

/// Maps the unit square to the unit disk preserving relative areas (Shirley & Chiu, "A Low
/// Distortion Map Between Disk and Square", 1997).
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // θ = φ in the first wedge and π/2 − φ in the second, with |φ| ≤ π/4, whose cosine and
    // sine are short polynomials; cos(π/2 − φ) = sin φ and sin(π/2 − φ) = cos φ.
    if o.x.abs() > o.y.abs() {
        let (sin, cos) = sin_cos_quarter(FRAC_PI_4 * (o.y / o.x));
        o.x * Vec2::new(cos, sin)
    } else {
        let (sin, cos) = sin_cos_quarter(FRAC_PI_4 * (o.x / o.y));
        o.y * Vec2::new(sin, cos)
    }
}

/// `(sin φ, cos φ)` for |φ| ≤ π/4 by their Taylor polynomials to degree 9 and 10, evaluated by
/// Horner: the truncation error is below φ¹¹/11! ≈ 1.7·10⁻⁹ and 2·10⁻¹⁰, so the result is as
/// exact as `f32` allows (within 2 ulp of the correctly rounded value, tested) at a fraction of
/// the cost of `f32::sin_cos`.
#[inline]
pub fn sin_cos_quarter(phi: f32) -> (f32, f32) {
    let x2 = phi * phi;
    let sin = phi
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let cos = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))));
    (sin, cos)
}

/// A cosine-distributed direction about +z (pdf cos θ / π), by Malley's method. Its z is always
/// ≥ 0 and its length 1, so it is never the zero vector the thesis's `N + random` can produce.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Mirror reflection of `d` about `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// A uniformly distributed point inside the unit ball.
#[inline]
pub fn uniform_ball(u: Vec3) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    u.z.cbrt() * Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// An orthonormal frame around a unit normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// The normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame with `n` as its z axis (Duff et al., "Building an Orthonormal Basis, Revisited",
    /// JCGT 2017, as implemented by glam).
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = n.any_orthonormal_pair();
        Self { s, t, n }
    }

    /// A local direction expressed in world space.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.s + v.y * self.t + v.z * self.n
    }
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
#[inline]
pub fn sample_sphere_cone(c: Vec3, r: f32, p: Vec3, u: Vec2) -> (Vec3, Vec3) {
    let to_centre = c - p;
    let dc2 = to_centre.length_squared();
    let sin2_max = r * r / dc2;
    let sin_max = sin2_max.sqrt();
    let sin2_t = if sin2_max < SMALL_CONE_SIN2 {
        sin2_max * u.x
    } else {
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let cos_t = (cos_max - 1.0) * u.x + 1.0;
        1.0 - cos_t * cos_t
    };
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    // Angle at the centre between the axis and the sampled point.
    let cos_alpha = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let frame = Frame::from_normal(to_centre / dc2.sqrt());
    let n = frame
        .to_world(-Vec3::new(
            sin_alpha * phi.cos(),
            sin_alpha * phi.sin(),
            cos_alpha,
        ))
        .normalize();
    (c + r * n, n)
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
    use crate::shading::rng::Rng;

    #[test]
    fn quarter_sin_cos_matches_the_library_within_two_ulp() {
        let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).abs();
        for k in -100_000..=100_000 {
            let phi = std::f32::consts::FRAC_PI_4 * k as f32 / 100_000.0;
            let (s, c) = sin_cos_quarter(phi);
            let (es, ec) = f64::from(phi).sin_cos();
            let (es, ec) = (es as f32, ec as f32);
            assert!(
                ulps(s, es) <= 2 && ulps(c, ec) <= 2,
                "φ = {phi}: {s} {c} against {es} {ec}"
            );
        }
    }

    #[test]
    fn cosine_directions_are_unit_and_never_below_the_surface() {
        let mut rng = Rng::new(7, 7);
        for _ in 0..100_000 {
            let d = cosine_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
        }
        // The corners and centre of the square.
        for u in [Vec2::ZERO, Vec2::splat(0.5), Vec2::ONE, Vec2::new(0.0, 1.0)] {
            let d = cosine_hemisphere(u);
            assert!(
                d.is_finite() && (d.length() - 1.0).abs() < 1e-5,
                "{u} -> {d}"
            );
        }
    }

    #[test]
    fn cosine_directions_pass_a_chi_square_test() {
        // Under pdf cos θ/π, cos²θ is uniform on [0,1] and φ uniform on [0,2π), independently:
        // a 10×10 grid over (cos²θ, φ) has equal expected counts.
        let (bins, n) = (10usize, 200_000usize);
        let mut counts = vec![0usize; bins * bins];
        let mut rng = Rng::new(3, 5);
        for _ in 0..n {
            let d = cosine_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let a = ((d.z * d.z) * bins as f32).min(bins as f32 - 1.0) as usize;
            let phi = d.y.atan2(d.x).rem_euclid(2.0 * PI);
            let b = (phi / (2.0 * PI) * bins as f32).min(bins as f32 - 1.0) as usize;
            counts[a * bins + b] += 1;
        }
        let expected = n as f64 / (bins * bins) as f64;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        // 99 degrees of freedom: the 99.9th percentile is 148.2.
        assert!(chi2 < 148.2, "chi2 = {chi2}");
    }

    #[test]
    fn ball_points_are_inside_with_the_right_mean_radius() {
        let mut rng = Rng::new(1, 9);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let p = uniform_ball(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()));
            assert!(p.length() <= 1.0 + 1e-6);
            sum += f64::from(p.length());
        }
        // E|p| = 3/4 for the uniform ball; sd of |p| = sqrt(3/5 − 9/16) ≈ 0.194.
        assert!((sum / n as f64 - 0.75).abs() < 5.0 * 0.194 / (n as f64).sqrt());
    }
}
