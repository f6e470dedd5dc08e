//! Sampling routines: directions on hemispheres, points in disks and balls, orthonormal frames,
//! and the mirror reflection. Points on shapes are sampled beside the shapes
//! ([`crate::geometry::sphere`], [`crate::geometry::triangle`]).

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

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

/// `(cos 2πu, sin 2πu)`, a point on the unit circle at the fraction `u` ∈ [0, 1) of a turn,
/// without calling the library's `sin` and `cos`: `4u` is split exactly into the nearest
/// quarter turn `q` and a remainder of at most an eighth of a turn (`4u − q` is exact), whose
/// sine and cosine [`sin_cos_quarter`] gives; the quarter turns are exact swaps and sign
/// changes. As exact as `f32` allows (tested against `f64` within 2·10⁻⁷), and more exact than
/// `(2πu).cos()`, whose angle is rounded before the cosine is taken.
#[inline(always)]
pub fn unit_circle(u: f32) -> Vec2 {
    let t = 4.0 * u;
    // `t + 0.5` is positive for u ≥ 0, so the cast rounds `t` to the nearest quarter turn.
    let q = (t + 0.5) as i32;
    let (sin, cos) = sin_cos_quarter((t - q as f32) * FRAC_PI_2);
    match q & 3 {
        0 => Vec2::new(cos, sin),
        1 => Vec2::new(-sin, cos),
        2 => Vec2::new(-cos, -sin),
        _ => Vec2::new(sin, -cos),
    }
}

/// A cosine-distributed direction about +z (pdf cos θ / π), by Malley's method. Its z is always
/// ≥ 0 and its length 1, so it is never the zero vector that `N + random` can produce.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// A uniformly distributed direction about +z (pdf 1/2π): z = u.x, so z ≥ 0.
#[inline]
pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x.clamp(0.0, 1.0);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let d = r * unit_circle(u.y);
    Vec3::new(d.x, d.y, z)
}

/// The unit normal `n` or its opposite, whichever faces the side a ray along `d` arrives from
/// (`-n` for a ray along a surface, `d · n = 0`): the one rule every lobe and the BSDF use.
#[inline(always)]
pub fn facing(d: Vec3, n: Vec3) -> Vec3 {
    if d.dot(n) < 0.0 { n } else { -n }
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
    let phi = unit_circle(u.y);
    u.z.cbrt() * Vec3::new(r * phi.x, r * phi.y, z)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;
    use std::f32::consts::PI;

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
    fn the_unit_circle_matches_f64_within_f32_precision() {
        // Every multiple of 2⁻²⁰ of a turn (the sampler's numbers are multiples of 2⁻²⁴), the
        // quarter and eighth turns among them, and the largest value below 1.
        let n = 1u32 << 20;
        let worst = (0..n)
            .map(|k| k as f32 / n as f32)
            .chain([1.0 - f32::EPSILON / 2.0])
            .map(|u| {
                let p = unit_circle(u);
                let (s, c) = (2.0 * std::f64::consts::PI * f64::from(u)).sin_cos();
                (f64::from(p.x) - c).abs().max((f64::from(p.y) - s).abs())
            })
            .fold(0.0, f64::max);
        assert!(worst < 2e-7, "worst error {worst}");
        assert_eq!(unit_circle(0.0), Vec2::new(1.0, 0.0));
        assert_eq!(unit_circle(0.25), Vec2::new(-0.0, 1.0));
        assert_eq!(unit_circle(0.5), Vec2::new(-1.0, -0.0));
        assert_eq!(unit_circle(0.75), Vec2::new(0.0, -1.0));
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
