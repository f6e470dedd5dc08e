//! Rays, and the spawn offset that keeps a new ray off the surface it leaves.

use glam::Vec3;

/// A ray `origin + t * direction`; `direction` is unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along the unit vector `direction`.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        debug_assert!(origin.is_finite() && direction.is_finite());
        debug_assert!((direction.length_squared() - 1.0).abs() < 1e-3);
        Self { origin, direction }
    }

    /// The point at distance `t` along the ray.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// pbrt's `gamma(n)`: bound on the relative error of `n` floating-point operations.
#[inline(always)]
pub const fn gamma(n: f32) -> f32 {
    let u = f32::EPSILON * 0.5;
    n * u / (1.0 - n * u)
}

/// Where a ray leaving surface point `p` must start: past the point's absolute error bound `err`
/// along the normal, then one more ulp away on every axis the normal moves it along. `n` is the
/// unit geometric normal on the side the ray leaves to.
///
/// pbrt-v4's `OffsetRayOrigin` (Pharr, Jakob & Humphreys, *Physically Based Rendering*, 4th ed.,
/// Section 6.8.6): the offset `d = |n|·err` puts the origin outside the box of points the true
/// hit point may be, so the new ray cannot re-hit the surface; the final ulp keeps the rounding of
/// `p + d·n` from undoing part of the offset. The step is as small as the error bound allows,
/// which matters for a second surface close behind the first (two quads 5·10⁻⁴ apart at
/// |p| ≈ 555 stay separate: the step is ≈ 2.3·10⁻⁴).
///
/// Wächter & Binder's fixed integer offset (Ray Tracing Gems, ch. 6, 256 ulps) was used here
/// before, on top of the error bound: 256 ulps are 9.8·10⁻⁴ at |p| ≈ 60 (a sphere of radius
/// 10⁻³ was jumped over) and 0.016 at |p| ≈ 555 (rays leaked through a quad 5·10⁻⁴ away); see
/// `tests/stability.rs`.
#[inline(always)]
pub fn spawn_origin(p: Vec3, n: Vec3, err: Vec3) -> Vec3 {
    let d = n.abs().dot(err);
    let po = p + d * n;
    Vec3::new(away(po.x, n.x), away(po.y, n.y), away(po.z, n.z))
}

/// Below this magnitude a spawned coordinate becomes ±`TINY`: one ulp further out, but never into
/// the subnormal range. A coordinate of exactly 0 (a floor at y = 0) would otherwise become
/// 1.4e-45, and arithmetic on subnormals runs through microcode assists — measured: the Cornell
/// box renders 40 % slower with such origins.
const TINY: f32 = 1e-20;

/// Finite `x` one ulp towards the side `n` points to (unchanged where `n` is 0 or NaN), and
/// ±[`TINY`] instead of anything smaller: `x.next_up()` / `x.next_down()` with that floor,
/// computed with selects on the bits instead of branches, which the normals of random bounces
/// make unpredictable. (A ray origin is finite; the standard library's steps also handle ±∞ and
/// NaN, which only cost here.)
#[inline(always)]
fn away(x: f32, n: f32) -> f32 {
    let up = n > 0.0;
    // One ulp towards +∞ is one more in the bits when x is positive, one less when negative.
    let bits = x.to_bits();
    let stepped = f32::from_bits(if (x > 0.0) == up {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    });
    let floor = if up { TINY } else { -TINY };
    // Near zero every step lands inside ±TINY (the one that reaches it is TINY itself).
    let y = if (x.abs() < TINY) | (stepped.abs() < TINY) {
        floor
    } else {
        stepped
    };
    if up | (n < 0.0) { y } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::rng::Rng;

    /// [`away`] by its definition, with the standard library's steps.
    fn away_by_definition(x: f32, n: f32) -> f32 {
        if n > 0.0 {
            let y = x.next_up();
            if y.abs() < TINY { TINY } else { y }
        } else if n < 0.0 {
            let y = x.next_down();
            if y.abs() < TINY { -TINY } else { y }
        } else {
            x
        }
    }

    #[test]
    fn the_branch_free_step_is_the_definition() {
        let below_tiny = f32::from_bits(TINY.to_bits() - 1);
        let special = [
            0.0,
            -0.0,
            TINY,
            -TINY,
            below_tiny,
            -below_tiny,
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            1.0,
            -1.0,
            555.0,
            f32::MAX,
            f32::MIN,
        ];
        let mut rng = Rng::new(4, 9);
        let random = (0..100_000)
            .map(|_| f32::from_bits(rng.next_u32()))
            .filter(|x| x.is_finite());
        for x in special.into_iter().chain(random) {
            for n in [1.0, 0.3, 0.0, -0.0, -0.7, f32::NAN] {
                let (got, want) = (away(x, n), away_by_definition(x, n));
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "x {x:e} n {n}: {got:e} vs {want:e}"
                );
            }
        }
    }

    #[test]
    fn spawn_origin_lies_past_the_error_bound_on_the_normal_side() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        for &scale in &[0.0f32, 1e-3, 1.0, 1e3, 1e6] {
            let p = Vec3::new(scale, -scale, 0.5 * scale);
            let err = gamma(7.0) * p.abs();
            let q = spawn_origin(p, n, err);
            // Every component moved towards the normal's side, by at least its share of
            // |n|·err (and by at least one ulp where the bound is zero).
            let d = n.abs().dot(err);
            for i in 0..3 {
                let moved = (q[i] - p[i]) * n[i].signum();
                assert!(
                    moved > 0.0 && moved >= d * n[i].abs(),
                    "{scale}: {p} -> {q}"
                );
            }
        }
    }
}
