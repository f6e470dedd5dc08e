//! Ray queries and the robust ray–box slab test.

use glam::{Vec3, Vec3A};

use super::ray::Ray;
use crate::cpu::Lanes;

/// Bound on the relative error of three floating-point operations, `3u / (1 - 3u)` (pbrt's
/// `gamma(3)`), used to widen the far slab distance.
const GAMMA3: f32 = 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// The watertight test's axes `[x, y, z]` by the index of the axis that becomes z (entry 3 is
/// never chosen; it pads the table to a power of two).
const FRAME_AXES: [[usize; 3]; 4] = [[1, 2, 0], [2, 0, 1], [0, 1, 2], [0, 1, 2]];

/// A ray with the per-ray constants every box and triangle test needs, computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    /// The ray.
    pub ray: Ray,
    /// Origin as a SIMD vector.
    origin: Vec3A,
    /// `1 / direction` (±∞ where a component is ±0).
    inv_dir: Vec3A,
    /// Whether `1 / direction` is infinite on some axis (a zero component, or a subnormal one
    /// whose reciprocal overflows): then `0 · ∞` can occur and the slab test takes its NaN-aware
    /// path.
    axis_parallel: bool,
    /// The watertight test's permutation: the axes that become x, y and z (z the axis of the
    /// largest |direction| component).
    axes: [usize; 3],
    /// Its shear: a vertex `p` relative to the origin maps to
    /// `(p[kx] + s.x·p[kz], p[ky] + s.y·p[kz], s.z·p[kz])`.
    shear: Vec3,
}

impl RayQuery {
    /// Precomputes the constants for `ray`.
    #[inline]
    pub fn new(ray: Ray) -> Self {
        let d = ray.direction;
        let a = d.abs();
        // z is the axis of the largest |d| component (x before y before z on ties); x and y
        // follow it cyclically. Chosen without branches: ray directions make them unpredictable.
        let x_over_y = a.x > a.y;
        let x_largest = x_over_y & (a.x > a.z);
        let y_largest = !x_over_y & (a.y > a.z);
        let kz = 2 - 2 * usize::from(x_largest) - usize::from(y_largest);
        let [kx, ky, kz] = FRAME_AXES[kz & 3];
        // Indices masked to the array's length index without bounds checks.
        let d4 = [d.x, d.y, d.z, 0.0];
        let (dx, dy, dz) = (d4[kx & 3], d4[ky & 3], d4[kz & 3]);
        let shear = Vec3::new(-dx / dz, -dy / dz, 1.0 / dz);
        let inv_dir = Vec3A::ONE / Vec3A::from(d);
        Self {
            ray,
            origin: ray.origin.into(),
            inv_dir,
            axis_parallel: !inv_dir.is_finite(),
            axes: [kx, ky, kz],
            shear,
        }
    }

    /// A vertex in the ray's sheared frame, where the ray is the +z axis from the origin
    /// (z not yet scaled by 1/d_z, as the watertight test needs): Woop et al.'s permutation
    /// then shear, one multiply and one add per coordinate.
    #[inline(always)]
    pub fn to_ray_frame(&self, p: Vec3) -> Vec3 {
        let r = p - self.ray.origin;
        let rel = [r.x, r.y, r.z, 0.0];
        let [kx, ky, kz] = self.axes;
        let (x, y, z) = (rel[kx & 3], rel[ky & 3], rel[kz & 3]);
        let s = self.shear;
        Vec3::new(x + s.x * z, y + s.y * z, s.z * z)
    }

    /// The watertight test's permutation (see [`RayQuery::to_ray_frame`]): the axes that become
    /// x, y and z, for kernels that move several vertices into the ray frame at once.
    #[inline(always)]
    pub fn axes(&self) -> [usize; 3] {
        self.axes
    }

    /// The watertight test's shear (see [`RayQuery::to_ray_frame`]), for kernels that move
    /// several vertices into the ray frame at once with the same operations.
    #[inline(always)]
    pub fn shear(&self) -> Vec3 {
        self.shear
    }

    /// Entry distance of the ray into the box `[min, max]` if it enters before `t_max`.
    ///
    /// Robust in the sense of pbrt-v4's `Bounds3::IntersectP` (Ize, "Robust BVH Ray Traversal",
    /// JCGT 2013): the far distance is widened by `1 + 2·gamma(3)` so rounding never culls a box
    /// the ray grazes. Flat boxes (min == max on an axis) work.
    #[inline(always)]
    pub fn enter_box(&self, min: Vec3A, max: Vec3A, t_max: f32) -> Option<f32> {
        if self.axis_parallel {
            return self.enter_box_axis_parallel(min, max, t_max);
        }
        let t0 = (min - self.origin) * self.inv_dir;
        let t1 = (max - self.origin) * self.inv_dir;
        let near = t0.min(t1).max_element().max(0.0);
        let far = (t0.max(t1).min_element() * (1.0 + 2.0 * GAMMA3)).min(t_max);
        (near <= far).then_some(near)
    }

    /// [`RayQuery::enter_box`] for eight boxes at once, given lane by lane as `[min_x, min_y,
    /// min_z, max_x, max_y, max_z]`: bit `k` of the returned mask is set if the ray enters box `k`
    /// before `t_max`, and lane `k` of the array is then its entry distance. Each lane performs
    /// exactly the operations of `enter_box`, so the answers are the same bits, whatever `lanes`.
    #[inline(always)]
    pub fn enter_boxes<W: Lanes>(
        &self,
        lanes: W,
        b: &[[f32; 8]; 6],
        t_max: f32,
    ) -> (u32, [f32; 8]) {
        if self.axis_parallel {
            return self.enter_boxes_axis_parallel(b, t_max);
        }
        let l = lanes;
        let (nx, fx) = self.slab(l, b, 0);
        let (ny, fy) = self.slab(l, b, 1);
        let (nz, fz) = self.slab(l, b, 2);
        let near = l.max(l.max(l.max(nx, ny), nz), l.splat(0.0));
        let far = l.min(
            l.mul(l.min(l.min(fx, fy), fz), l.splat(1.0 + 2.0 * GAMMA3)),
            l.splat(t_max),
        );
        (l.le_mask(near, far), l.to_array(near))
    }

    /// The near and far distances of the eight boxes' slabs on `axis`. Always inlined, not a
    /// closure: the AVX copy's intrinsics are inlined only where every call above them is.
    #[inline(always)]
    fn slab<W: Lanes>(&self, l: W, b: &[[f32; 8]; 6], axis: usize) -> (W::F8, W::F8) {
        let (o, inv) = (l.splat(self.origin[axis]), l.splat(self.inv_dir[axis]));
        let t0 = l.mul(l.sub(l.load(&b[axis]), o), inv);
        let t1 = l.mul(l.sub(l.load(&b[3 + axis]), o), inv);
        (l.min(t0, t1), l.max(t0, t1))
    }

    /// [`RayQuery::enter_boxes`] for rays with a zero direction component: box by box.
    #[cold]
    fn enter_boxes_axis_parallel(&self, b: &[[f32; 8]; 6], t_max: f32) -> (u32, [f32; 8]) {
        let mut mask = 0;
        let mut near = [0.0f32; 8];
        for (k, t) in near.iter_mut().enumerate() {
            let min = Vec3A::new(b[0][k], b[1][k], b[2][k]);
            let max = Vec3A::new(b[3][k], b[4][k], b[5][k]);
            if let Some(t_enter) = self.enter_box_axis_parallel(min, max, t_max) {
                mask |= 1 << k;
                *t = t_enter;
            }
        }
        (mask, near)
    }

    /// The slab test for rays with a zero direction component. A ray lying in a slab plane makes
    /// `0 · ∞ = NaN`; the comparisons are written so a NaN bound is ignored (the ray is inside
    /// that slab), as pbrt does.
    ///
    /// Near and far planes are chosen by the sign of `1 / d`, not by comparing the two
    /// distances as pbrt does: for `d = −0.0` and an origin in the `min` plane the distances are
    /// `NaN` and `−∞`, the comparison never swaps them, and the box was missed (a ray along
    /// `(1, −0, 0)` from `(−1, 0, 0)` missed the unit box; `tests/stability.rs`).
    #[cold]
    fn enter_box_axis_parallel(&self, min: Vec3A, max: Vec3A, t_max: f32) -> Option<f32> {
        let mut t0 = 0.0f32;
        let mut t1 = t_max;
        for axis in 0..3 {
            let o = self.origin[axis];
            let inv = self.inv_dir[axis];
            let (lo, hi) = if inv.is_sign_negative() {
                (max[axis], min[axis])
            } else {
                (min[axis], max[axis])
            };
            let near = (lo - o) * inv;
            let far = (hi - o) * inv * (1.0 + 2.0 * GAMMA3);
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
    use crate::cpu::{Isa, Kernel};

    fn query(o: Vec3, d: Vec3) -> RayQuery {
        RayQuery::new(Ray::new(o, d.normalize()))
    }

    #[test]
    fn axis_aligned_rays_with_signed_zeros_hit_and_miss_exactly() {
        let (min, max) = (Vec3::ZERO, Vec3::ONE);
        for dz in [0.0f32, -0.0] {
            let q = query(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, dz, dz));
            assert_eq!(
                q.enter_box(min.into(), max.into(), f32::INFINITY),
                Some(1.0)
            );
            let q = query(Vec3::new(-1.0, 1.5, 0.5), Vec3::new(1.0, dz, dz));
            assert_eq!(q.enter_box(min.into(), max.into(), f32::INFINITY), None);
        }
    }

    #[test]
    fn ray_lying_in_a_box_face_hits_without_nan() {
        // Origin on the y = 0 face plane, moving along x: 0 · ∞ = NaN on the y axis.
        let q = query(Vec3::new(-1.0, 0.0, 0.5), Vec3::X);
        assert_eq!(
            q.enter_box(Vec3A::ZERO, Vec3A::ONE, f32::INFINITY),
            Some(1.0)
        );
        let q = query(Vec3::new(-1.0, 1.0, 0.5), Vec3::X);
        assert_eq!(
            q.enter_box(Vec3A::ZERO, Vec3A::ONE, f32::INFINITY),
            Some(1.0)
        );
    }

    /// Eight random boxes (one of them flat) per random ray, some rays axis-parallel, tested at
    /// once with `lanes` and one by one.
    struct EightBoxes;

    impl Kernel for EightBoxes {
        type Output = ();

        #[inline(always)]
        fn run<W: Lanes>(self, lanes: W) {
            let mut rng = crate::shading::rng::Rng::new(3, 8);
            let mut f = || rng.next_f32() * 4.0 - 2.0;
            for k in 0..4000 {
                let mut d = Vec3::new(f(), f(), f());
                if k % 7 == 0 {
                    d.x = 0.0;
                }
                let q = query(Vec3::new(f(), f(), f()), d);
                let mut rows = [[0.0f32; 8]; 6];
                let mut boxes = [(Vec3A::ZERO, Vec3A::ZERO); 8];
                for (j, bx) in boxes.iter_mut().enumerate() {
                    let a = Vec3A::new(f(), f(), f());
                    let flat = if j == 3 { 0.0 } else { 1.0 };
                    let b = a + Vec3A::new(f(), f(), f()).abs() * flat;
                    *bx = (a, b);
                    for axis in 0..3 {
                        rows[axis][j] = a[axis];
                        rows[3 + axis][j] = b[axis];
                    }
                }
                let t_max = if k % 3 == 0 {
                    f32::INFINITY
                } else {
                    f().abs() * 2.0
                };
                let (mask, near) = q.enter_boxes(lanes, &rows, t_max);
                for (j, &(a, b)) in boxes.iter().enumerate() {
                    let single = q.enter_box(a, b, t_max);
                    assert_eq!(mask & (1 << j) != 0, single.is_some(), "ray {k} box {j}");
                    if let Some(t) = single {
                        assert_eq!(near[j].to_bits(), t.to_bits());
                    }
                }
            }
        }
    }

    #[test]
    fn eight_boxes_at_once_give_the_single_box_answers_in_every_copy() {
        // The baseline copy (4 lanes), then the best this CPU has (8 lanes with AVX).
        Isa::BASELINE.run(EightBoxes);
        Isa::detect().run(EightBoxes);
    }

    #[test]
    fn flat_box_is_hit_by_a_crossing_ray() {
        let q = query(Vec3::new(0.5, 2.0, 0.5), -Vec3::Y);
        let hit = q.enter_box(Vec3A::ZERO, Vec3A::new(1.0, 0.0, 1.0), f32::INFINITY);
        assert_eq!(hit, Some(2.0));
    }

    #[test]
    fn box_behind_or_beyond_t_max_is_missed() {
        let q = query(Vec3::new(0.5, 0.5, 3.0), Vec3::Z);
        assert_eq!(q.enter_box(Vec3A::ZERO, Vec3A::ONE, f32::INFINITY), None);
        let q = query(Vec3::new(0.5, 0.5, -3.0), Vec3::Z);
        assert_eq!(q.enter_box(Vec3A::ZERO, Vec3A::ONE, 2.0), None);
    }
}
