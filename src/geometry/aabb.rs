//! Ray queries and the robust ray–box slab test.

use glam::Vec3;

use super::ray::Ray;

/// Bound on the relative error of three floating-point operations, `3u / (1 - 3u)` (pbrt's
/// `gamma(3)`), used to widen the far slab distance.
const GAMMA3: f32 = 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A ray with the per-ray constants every box and triangle test needs, computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    /// The ray.
    pub ray: Ray,
    /// `1 / direction`, exactly (±∞ where a component is ±0).
    pub inv_dir: Vec3,
    /// Axis of the largest |direction| component (the triangle test's z after permutation).
    pub kz: usize,
    /// The axis after `kz`.
    pub kx: usize,
    /// The axis after `kx`.
    pub ky: usize,
    /// Shear constants of the watertight triangle test: `-d_x/d_z`, `-d_y/d_z`, `1/d_z`.
    pub shear: Vec3,
}

impl RayQuery {
    /// Precomputes the constants for `ray`.
    #[inline]
    pub fn new(ray: Ray) -> Self {
        let d = ray.direction;
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let shear = Vec3::new(-d[kx] / d[kz], -d[ky] / d[kz], 1.0 / d[kz]);
        Self {
            ray,
            inv_dir: Vec3::ONE / d,
            kz,
            kx,
            ky,
            shear,
        }
    }

    /// Entry distance of the ray into the box `[min, max]` if it enters before `t_max`.
    ///
    /// Robust in the sense of pbrt-v4's `Bounds3::IntersectP` (Ize, "Robust BVH Ray Traversal",
    /// JCGT 2013): the far distance is widened by `1 + 2·gamma(3)` so rounding never culls a box
    /// the ray grazes, and a NaN from `0 · ∞` (a ray lying in a slab plane) is ignored by the
    /// comparisons instead of poisoning the result. Flat boxes (min == max on an axis) work.
    #[inline(always)]
    pub fn enter_box(&self, min: Vec3, max: Vec3, t_max: f32) -> Option<f32> {
        let mut t0 = 0.0f32;
        let mut t1 = t_max;
        for axis in 0..3 {
            let o = self.ray.origin[axis];
            let inv = self.inv_dir[axis];
            let mut near = (min[axis] - o) * inv;
            let mut far = (max[axis] - o) * inv;
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            far *= 1.0 + 2.0 * GAMMA3;
            // Written so that a NaN `near`/`far` leaves t0/t1 unchanged.
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
            if t0 > t1 {
                return None;
            }
        }
        Some(t0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn query(o: Vec3, d: Vec3) -> RayQuery {
        RayQuery::new(Ray::new(o, d.normalize()))
    }

    #[test]
    fn axis_aligned_rays_with_signed_zeros_hit_and_miss_exactly() {
        let (min, max) = (Vec3::ZERO, Vec3::ONE);
        for dz in [0.0f32, -0.0] {
            let q = query(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, dz, dz));
            assert_eq!(q.enter_box(min, max, f32::INFINITY), Some(1.0));
            let q = query(Vec3::new(-1.0, 1.5, 0.5), Vec3::new(1.0, dz, dz));
            assert_eq!(q.enter_box(min, max, f32::INFINITY), None);
        }
    }

    #[test]
    fn ray_lying_in_a_box_face_hits_without_nan() {
        // Origin on the y = 0 face plane, moving along x: 0 · ∞ = NaN on the y axis.
        let q = query(Vec3::new(-1.0, 0.0, 0.5), Vec3::X);
        assert_eq!(q.enter_box(Vec3::ZERO, Vec3::ONE, f32::INFINITY), Some(1.0));
        let q = query(Vec3::new(-1.0, 1.0, 0.5), Vec3::X);
        assert_eq!(q.enter_box(Vec3::ZERO, Vec3::ONE, f32::INFINITY), Some(1.0));
    }

    #[test]
    fn flat_box_is_hit_by_a_crossing_ray() {
        let q = query(Vec3::new(0.5, 2.0, 0.5), -Vec3::Y);
        let hit = q.enter_box(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), f32::INFINITY);
        assert_eq!(hit, Some(2.0));
    }

    #[test]
    fn box_behind_or_beyond_t_max_is_missed() {
        let q = query(Vec3::new(0.5, 0.5, 3.0), Vec3::Z);
        assert_eq!(q.enter_box(Vec3::ZERO, Vec3::ONE, f32::INFINITY), None);
        let q = query(Vec3::new(0.5, 0.5, -3.0), Vec3::Z);
        assert_eq!(q.enter_box(Vec3::ZERO, Vec3::ONE, 2.0), None);
    }
}
