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

/// Moves a surface point `p` off its surface along `n`, so that a ray starting there cannot hit
/// the surface it leaves.
///
/// `n` is the geometric normal, flipped to the side the new ray goes to. The step is a fixed number
/// of ulps of each coordinate, so it scales with the floating-point error of `p` whatever its
/// magnitude; near the origin, where ulps vanish, a small absolute step is used instead.
/// Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems,
/// ch. 6 (2019).
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let offset = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            let ulps = (INT_SCALE * n) as i32;
            let ulps = if p < 0.0 { -ulps } else { ulps };
            f32::from_bits((p.to_bits() as i32).wrapping_add(ulps) as u32)
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}

/// pbrt's `gamma(n)`: bound on the relative error of `n` floating-point operations.
#[inline(always)]
pub const fn gamma(n: f32) -> f32 {
    let u = f32::EPSILON * 0.5;
    n * u / (1.0 - n * u)
}

/// Where a ray leaving surface point `p` must start: first past the point's absolute error
/// bound `err` along the normal (pbrt-v4's `OffsetRayOrigin`), then a few ulps further
/// ([`offset_ray_origin`]). `n` is the geometric normal on the side the ray leaves to.
///
/// The error bound matters when `p` is small but was computed from large numbers (a point near
/// the origin on a sphere of radius 1000 centred at (0, −1000, 0)): ulps of `p` alone are then
/// far smaller than its real error, and the new ray would start inside the surface.
#[inline]
pub fn spawn_origin(p: Vec3, n: Vec3, err: Vec3) -> Vec3 {
    let d = n.abs().dot(err);
    offset_ray_origin(p + d * n, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_point_to_the_normal_side() {
        for &scale in &[1e-3f32, 1.0, 1e3, 1e6] {
            let p = Vec3::new(scale, -scale, 0.5 * scale);
            let n = Vec3::new(0.3, -0.8, 0.52).normalize();
            let q = offset_ray_origin(p, n);
            assert!((q - p).dot(n) > 0.0, "scale {scale}: {p} -> {q}");
        }
    }
}
