//! Leaf kernels that test [`LANES`] primitives at once, reading them straight from the SoA
//! field arrays.
//!
//! Portable code: a lane vector is a `[f32; LANES]` whose element-wise operations the optimiser
//! turns into SIMD instructions (one SSE register on a baseline x86-64 build; checked in the
//! generated code: `movups`, `mulps`, `cmpleps`, `movmskps`). No `unsafe`, no target features,
//! no nightly. The SoA/AoS benchmark (BENCHMARKS.md) measures what this buys: 1.5–1.8× on the
//! triangle leaf kernel, much less on a whole render. A leaf of `n` slots is loaded as whole
//! lane vectors from `cx[first..first + LANES]` and so on; lanes past `n` (other primitives, or
//! padding copied in at the end of the arrays) are masked off.
//!
//! Each lane performs exactly the operations of the scalar kernel ([`intersect_sphere`],
//! [`intersect_triangle`]) in the same order, and IEEE arithmetic is deterministic, so a lane
//! computes the same bits as the scalar kernel. The closest hit is then chosen by replaying the
//! scalar loop's acceptance test over the lanes that hit, in slot order, against the shrinking
//! `t_max`; that reproduces the scalar loop exactly, ties included. A triangle lane with an edge
//! function of exactly zero (the watertight test then recomputes in `f64`) sends its whole chunk
//! to the scalar kernel.
//!
//! [`intersect_sphere`]: super::sphere::intersect_sphere
//! [`intersect_triangle`]: super::triangle::intersect_triangle

use std::ops::{Add, Div, Mul, Neg, Range, Sub};

use super::aabb::RayQuery;
use super::layout::{SphereSoa, TriangleSoa, closest_triangle_scalar};
use super::ray::{Ray, gamma};
use super::triangle::TriangleHit;

/// Primitives tested at once: one SSE register of `f32`. The BVH's leaves hold 1 to 8
/// primitives, about 3.7 on average for the benchmark scenes, so 8 lanes would leave most of
/// them idle; a leaf of 5 to 8 primitives takes two chunks.
pub const LANES: usize = 4;

/// `LANES` floats, operated on element-wise.
#[derive(Clone, Copy, Debug)]
struct F([f32; LANES]);

/// `LANES` booleans.
#[derive(Clone, Copy, Debug)]
struct M([bool; LANES]);

impl F {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        F([x; LANES])
    }

    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        F(self.0.map(f))
    }

    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        F(std::array::from_fn(|i| f(self.0[i], o.0[i])))
    }

    #[inline(always)]
    fn cmp(self, o: Self, f: impl Fn(f32, f32) -> bool) -> M {
        M(std::array::from_fn(|i| f(self.0[i], o.0[i])))
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }

    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f32::abs)
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        self.zip(sign, f32::copysign)
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.zip(o, f32::max)
    }

    #[inline(always)]
    fn lt(self, o: Self) -> M {
        self.cmp(o, |a, b| a < b)
    }

    #[inline(always)]
    fn le(self, o: Self) -> M {
        self.cmp(o, |a, b| a <= b)
    }

    #[inline(always)]
    fn gt(self, o: Self) -> M {
        self.cmp(o, |a, b| a > b)
    }

    #[inline(always)]
    fn ge(self, o: Self) -> M {
        self.cmp(o, |a, b| a >= b)
    }

    #[inline(always)]
    fn eq(self, o: Self) -> M {
        self.cmp(o, |a, b| a == b)
    }

    /// `a` where `m`, else `b`.
    #[inline(always)]
    fn select(m: M, a: Self, b: Self) -> Self {
        F(std::array::from_fn(
            |i| if m.0[i] { a.0[i] } else { b.0[i] },
        ))
    }
}

impl M {
    #[inline(always)]
    fn first(n: usize) -> Self {
        M(std::array::from_fn(|i| i < n))
    }

    #[inline(always)]
    fn and(self, o: Self) -> Self {
        M(std::array::from_fn(|i| self.0[i] & o.0[i]))
    }

    #[inline(always)]
    fn or(self, o: Self) -> Self {
        M(std::array::from_fn(|i| self.0[i] | o.0[i]))
    }

    #[inline(always)]
    fn not(self) -> Self {
        M(self.0.map(|b| !b))
    }

    #[inline(always)]
    fn any(self) -> bool {
        self.0.iter().fold(false, |a, &b| a | b)
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F {
            type Output = F;
            #[inline(always)]
            fn $method(self, o: F) -> F {
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        self.map(|a| -a)
    }
}

/// Lanes `first..first + LANES` of `field`: one unaligned vector load.
#[inline(always)]
fn load(field: &[f32], first: usize) -> F {
    match field.get(first..).and_then(|s| s.first_chunk::<LANES>()) {
        Some(lanes) => F(*lanes),
        None => load_tail(field, first),
    }
}

/// [`load`] past the end of the array: the missing lanes repeat the last element (any finite
/// value would do: they are masked off). Out of line, so the common path stays one load.
#[cold]
#[inline(never)]
fn load_tail(field: &[f32], first: usize) -> F {
    let tail = field.get(first..).unwrap_or_default();
    let last = tail.last().copied().unwrap_or(0.0);
    F(std::array::from_fn(|i| {
        tail.get(i).copied().unwrap_or(last)
    }))
}

/// The chunks of at most `LANES` slots that cover `slots`: `(first slot, live lanes)`.
#[inline(always)]
fn chunks(slots: Range<usize>) -> impl Iterator<Item = (usize, usize)> {
    slots
        .clone()
        .step_by(LANES)
        .map(move |first| (first, (slots.end - first).min(LANES)))
}

/// Both roots of the sphere quadratic per lane, smaller first, in the exact operations of
/// [`super::sphere::intersect_sphere`]; `None` when no live lane's discriminant is
/// non-negative (the scalar kernel's early return, taken by the whole chunk). Lanes that miss
/// get NaN roots (the square root of a negative discriminant), which no `t > 0` test accepts.
#[inline(always)]
fn sphere_roots(ray: &Ray, spheres: &SphereSoa, first: usize, live: usize) -> Option<(F, F)> {
    let (o, d) = (ray.origin, ray.direction);
    let fx = F::splat(o.x) - load(&spheres.cx, first);
    let fy = F::splat(o.y) - load(&spheres.cy, first);
    let fz = F::splat(o.z) - load(&spheres.cz, first);
    let r = load(&spheres.r, first);
    let (dx, dy, dz) = (F::splat(d.x), F::splat(d.y), F::splat(d.z));
    let b = -(fx * dx + fy * dy + fz * dz);
    let (lx, ly, lz) = (fx + b * dx, fy + b * dy, fz + b * dz);
    let r2 = r * r;
    let disc = r2 - (lx * lx + ly * ly + lz * lz);
    if !disc.ge(F::splat(0.0)).and(M::first(live)).any() {
        return None;
    }
    let c = (fx * fx + fy * fy + fz * fz) - r2;
    let q = b + disc.sqrt().copysign(b);
    let (t0, t1) = (c / q, q);
    let swap = t0.gt(t1);
    Some((F::select(swap, t1, t0), F::select(swap, t0, t1)))
}

/// Lanes whose sphere has a root in `(0, t_max)`.
#[inline(always)]
fn sphere_hits(t0: F, t1: F, t_max: f32) -> M {
    let (zero, t_max) = (F::splat(0.0), F::splat(t_max));
    let in_range = |t: F| t.gt(zero).and(t.lt(t_max));
    in_range(t0).or(in_range(t1))
}

/// [`crate::geometry::layout::closest_sphere_scalar`], [`LANES`] spheres at a time.
#[inline(always)]
pub fn closest_sphere(
    spheres: &SphereSoa,
    ray: &Ray,
    slots: Range<usize>,
    t_max: &mut f32,
) -> Option<usize> {
    let mut best = None;
    for (first, live) in chunks(slots) {
        let Some((t0, t1)) = sphere_roots(ray, spheres, first, live) else {
            continue;
        };
        let hits = sphere_hits(t0, t1, *t_max).and(M::first(live));
        if !hits.any() {
            continue;
        }
        // Replay the scalar loop over the lanes that hit, in slot order.
        for i in (0..live).filter(|&i| hits.0[i]) {
            let (t0, t1) = (t0.0[i], t1.0[i]);
            let t = if t0 > 0.0 && t0 < *t_max {
                t0
            } else if t1 > 0.0 && t1 < *t_max {
                t1
            } else {
                continue;
            };
            *t_max = t;
            best = Some(first + i);
        }
    }
    best
}

/// Whether `ray` hits any sphere in `slots` before `t_max`, [`LANES`] at a time.
#[inline(always)]
pub fn any_sphere(spheres: &SphereSoa, ray: &Ray, slots: Range<usize>, t_max: f32) -> bool {
    chunks(slots).any(|(first, live)| {
        sphere_roots(ray, spheres, first, live)
            .is_some_and(|(t0, t1)| sphere_hits(t0, t1, t_max).and(M::first(live)).any())
    })
}

/// The watertight test per lane, up to the point where `t_max` enters.
struct TriangleLanes {
    /// Lanes that pass every test but the `t_max` one.
    candidate: M,
    det: F,
    t_scaled: F,
    inv_det: F,
    e1: F,
    e2: F,
}

/// What the first, cheap stage of the lane test found.
enum Chunk {
    /// No live lane can hit: the scalar kernel's early returns, taken by the whole chunk.
    Miss,
    /// A live lane has an edge function of exactly zero: the scalar kernel must decide.
    Degenerate,
    /// Some lanes may hit.
    Lanes(TriangleLanes),
}

/// Vertex `k` of the lanes' triangles in the ray frame: `RayQuery::to_ray_frame` on lanes.
#[inline(always)]
fn ray_frame(q: &RayQuery, tris: &TriangleSoa, first: usize, k: usize) -> (F, F, F) {
    let (o, s) = (q.ray.origin, q.shear());
    let rx = load(&tris.v[3 * k], first) - F::splat(o.x);
    let ry = load(&tris.v[3 * k + 1], first) - F::splat(o.y);
    let rz = load(&tris.v[3 * k + 2], first) - F::splat(o.z);
    let x = F::splat(s.x_axis.x) * rx + F::splat(s.x_axis.y) * ry + F::splat(s.x_axis.z) * rz;
    let y = F::splat(s.y_axis.x) * rx + F::splat(s.y_axis.y) * ry + F::splat(s.y_axis.z) * rz;
    let z = rx * F::splat(s.z_axis.x) + ry * F::splat(s.z_axis.y) + rz * F::splat(s.z_axis.z);
    (x, y, z)
}

/// [`super::triangle::intersect_triangle`] on lanes, in the same operations.
#[inline(always)]
fn triangle_lanes(q: &RayQuery, tris: &TriangleSoa, first: usize, live: usize) -> Chunk {
    let (ax, ay, az) = ray_frame(q, tris, first, 0);
    let (bx, by, bz) = ray_frame(q, tris, first, 1);
    let (cx, cy, cz) = ray_frame(q, tris, first, 2);
    let e0 = bx * cy - by * cx;
    let e1 = cx * ay - cy * ax;
    let e2 = ax * by - ay * bx;
    let zero = F::splat(0.0);
    let live = M::first(live);
    if e0.eq(zero).or(e1.eq(zero)).or(e2.eq(zero)).and(live).any() {
        return Chunk::Degenerate;
    }
    let some_negative = e0.lt(zero).or(e1.lt(zero)).or(e2.lt(zero));
    let some_positive = e0.gt(zero).or(e1.gt(zero)).or(e2.gt(zero));
    let det = e0 + e1 + e2;
    let mut candidate = some_negative
        .and(some_positive)
        .not()
        .and(det.eq(zero).not())
        .and(live);
    if !candidate.any() {
        return Chunk::Miss;
    }
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    candidate = candidate.and(det.lt(zero).and(t_scaled.ge(zero)).not());
    candidate = candidate.and(det.gt(zero).and(t_scaled.le(zero)).not());
    let inv_det = F::splat(1.0) / det;
    let t = t_scaled * inv_det;

    // Conservative bound on the error of t (pbrt-v4, Section 6.8.4), as in the scalar kernel.
    let (g2, g3, g5) = (F::splat(GAMMA2), F::splat(GAMMA3), F::splat(GAMMA5));
    let max_zt = az.abs().max(bz.abs()).max(cz.abs());
    let delta_z = g3 * max_zt;
    let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
    let max_yt = ay.abs().max(by.abs()).max(cy.abs());
    let delta_x = g5 * (max_xt + max_zt);
    let delta_y = g5 * (max_yt + max_zt);
    let delta_e = F::splat(2.0) * (g2 * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t =
        F::splat(3.0) * (g3 * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    candidate = candidate.and(t.le(delta_t).not());
    Chunk::Lanes(TriangleLanes {
        candidate,
        det,
        t_scaled,
        inv_det,
        e1,
        e2,
    })
}

/// pbrt's `gamma(n)` for the `n` the watertight test uses, as the scalar kernel computes them.
const GAMMA2: f32 = gamma(2.0);
const GAMMA3: f32 = gamma(3.0);
const GAMMA5: f32 = gamma(5.0);

/// Whether lane `i` passes the scalar kernel's `t_max` test.
#[inline(always)]
fn within(l: &TriangleLanes, i: usize, t_max: f32) -> bool {
    let (det, t_scaled) = (l.det.0[i], l.t_scaled.0[i]);
    let bound = t_max * det;
    !((det < 0.0 && t_scaled < bound) || (det > 0.0 && t_scaled > bound))
}

/// [`crate::geometry::layout::closest_triangle_scalar`], [`LANES`] triangles at a time.
#[inline(always)]
pub fn closest_triangle(
    tris: &TriangleSoa,
    q: &RayQuery,
    slots: Range<usize>,
    t_max: &mut f32,
) -> Option<(usize, TriangleHit)> {
    let mut best = None;
    for (first, live) in chunks(slots) {
        let l = match triangle_lanes(q, tris, first, live) {
            Chunk::Miss => continue,
            Chunk::Degenerate => {
                let chunk = first..first + live;
                if let Some(hit) = closest_triangle_scalar(tris, q, chunk, t_max) {
                    best = Some(hit);
                }
                continue;
            }
            Chunk::Lanes(l) => l,
        };
        // Replay the scalar loop's t_max test over the candidates, in slot order.
        for i in (0..live).filter(|&i| l.candidate.0[i]) {
            if within(&l, i, *t_max) {
                let inv_det = l.inv_det.0[i];
                let t = l.t_scaled.0[i] * inv_det;
                *t_max = t;
                best = Some((
                    first + i,
                    TriangleHit {
                        t,
                        b1: l.e1.0[i] * inv_det,
                        b2: l.e2.0[i] * inv_det,
                    },
                ));
            }
        }
    }
    best
}

/// Whether the ray of `q` hits any triangle in `slots` before `t_max`, [`LANES`] at a time.
#[inline(always)]
pub fn any_triangle(tris: &TriangleSoa, q: &RayQuery, slots: Range<usize>, t_max: f32) -> bool {
    chunks(slots).any(|(first, live)| match triangle_lanes(q, tris, first, live) {
        Chunk::Miss => false,
        Chunk::Degenerate => {
            let mut t = t_max;
            closest_triangle_scalar(tris, q, first..first + live, &mut t).is_some()
        }
        Chunk::Lanes(l) => (0..live).any(|i| l.candidate.0[i] && within(&l, i, t_max)),
    })
}
