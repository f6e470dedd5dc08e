//! Leaf kernels that test [`LANES`] primitives at once, reading them straight from the SoA
//! field arrays.
//!
//! A lane vector is glam's `Vec4` and a lane mask its `BVec4A`: one SSE register each on
//! x86-64 (SSE2 is part of the baseline, so no runtime detection is needed; plain arrays on other
//! targets). No `unsafe`, no target features, no nightly. Lanes are explicit vectors because
//! `[f32; 4]` arrays and `[bool; 4]` masks, left to the optimiser to vectorise, stay largely
//! scalar: the Cornell box takes 541 M instructions that way against 441 M with these (callgrind,
//! 64×64, 8 spp, one thread). The SoA/AoS benchmark (BENCHMARKS.md) measures what the lanes buy.
//! A leaf of `n` slots is loaded as whole lane vectors from `cx[first..first + LANES]` and so
//! on; lanes past `n` (other primitives, or padding copied in at the end of the arrays) are
//! masked off.
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

use glam::{BVec4A, Vec4};

use super::aabb::RayQuery;
use super::ray::{Ray, gamma};
use super::store::{SOA_PADDING, SphereSoa, TriangleSoa, closest_triangle_scalar};
use super::triangle::TriangleHit;

/// Primitives tested at once: one SSE register of `f32`. The BVH's leaves hold 1 to 8
/// primitives, about 3.7 on average for the benchmark scenes, so 8 lanes would leave most of
/// them idle; a leaf of 5 to 8 primitives takes two chunks.
pub const LANES: usize = 4;

// A sphere chunk starting at any sphere loads whole vectors from the padded fields.
const _: () = assert!(SOA_PADDING + 1 >= LANES);

/// `LANES` floats, operated on element-wise: glam's `Vec4`, one SSE register on x86-64
/// (SSE2 is part of the baseline, so no runtime detection is needed) and plain arrays elsewhere.
#[derive(Clone, Copy, Debug)]
struct F(Vec4);

/// `LANES` booleans: glam's `BVec4A`, an SSE mask register on x86-64.
#[derive(Clone, Copy, Debug)]
struct M(BVec4A);

impl F {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        F(Vec4::splat(x))
    }

    /// Lane `i`.
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.0[i]
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        F(self.0.sqrt())
    }

    #[inline(always)]
    fn abs(self) -> Self {
        F(self.0.abs())
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        F(self.0.copysign(sign.0))
    }

    /// `f32::max` per lane, NaN handling included (IEEE maxNum: a NaN operand loses). SSE's
    /// `maxps` returns its second operand when either is NaN, so a NaN `o` is replaced.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F(Vec4::select(o.0.is_nan_mask(), self.0, self.0.max(o.0)))
    }

    #[inline(always)]
    fn lt(self, o: Self) -> M {
        M(self.0.cmplt(o.0))
    }

    #[inline(always)]
    fn le(self, o: Self) -> M {
        M(self.0.cmple(o.0))
    }

    #[inline(always)]
    fn gt(self, o: Self) -> M {
        M(self.0.cmpgt(o.0))
    }

    #[inline(always)]
    fn ge(self, o: Self) -> M {
        M(self.0.cmpge(o.0))
    }

    #[inline(always)]
    fn eq(self, o: Self) -> M {
        M(self.0.cmpeq(o.0))
    }

    /// `a` where `m`, else `b`.
    #[inline(always)]
    fn select(m: M, a: Self, b: Self) -> Self {
        F(Vec4::select(m.0, a.0, b.0))
    }
}

impl M {
    #[inline(always)]
    fn first(n: usize) -> Self {
        M(BVec4A::new(n > 0, n > 1, n > 2, n > 3))
    }

    /// The set lanes, in lane order.
    #[inline(always)]
    fn lanes(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0.bitmask();
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                i
            })
        })
    }

    #[inline(always)]
    fn and(self, o: Self) -> Self {
        M(self.0 & o.0)
    }

    #[inline(always)]
    fn or(self, o: Self) -> Self {
        M(self.0 | o.0)
    }

    #[inline(always)]
    fn not(self) -> Self {
        M(!self.0)
    }

    #[inline(always)]
    fn any(self) -> bool {
        self.0.any()
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F {
            type Output = F;
            #[inline(always)]
            fn $method(self, o: F) -> F {
                F(self.0 $op o.0)
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
        F(-self.0)
    }
}

/// Lanes `first..first + LANES` of `field`: one unaligned vector load.
#[inline(always)]
fn load(field: &[f32], first: usize) -> F {
    match field.get(first..).and_then(|s| s.first_chunk::<LANES>()) {
        Some(lanes) => F(Vec4::from_array(*lanes)),
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
    F(Vec4::from_array(std::array::from_fn(|i| {
        tail.get(i).copied().unwrap_or(last)
    })))
}

/// The chunks of at most `LANES` slots that cover `slots`: `(first slot, live lanes)`.
#[inline(always)]
fn chunks(slots: Range<usize>) -> impl Iterator<Item = (usize, usize)> {
    (0..slots.len().div_ceil(LANES)).map(move |c| {
        let first = slots.start + c * LANES;
        (first, (slots.end - first).min(LANES))
    })
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

/// [`crate::geometry::store::closest_sphere_scalar`], [`LANES`] spheres at a time.
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
        for i in hits.lanes() {
            let (t0, t1) = (t0.lane(i), t1.lane(i));
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

/// Whether `ray` hits any sphere in `slots` before `t_max`, [`LANES`] at a time. A `for` loop
/// rather than `Iterator::any`: `any` goes through `try_fold`, which the compiler keeps out of
/// line, compiled for the baseline instead of inlined into the dispatched render loop.
#[inline(always)]
pub fn any_sphere(spheres: &SphereSoa, ray: &Ray, slots: Range<usize>, t_max: f32) -> bool {
    for (first, live) in chunks(slots) {
        if let Some((t0, t1)) = sphere_roots(ray, spheres, first, live)
            && sphere_hits(t0, t1, t_max).and(M::first(live)).any()
        {
            return true;
        }
    }
    false
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
    let o = q.ray.origin.to_array();
    let [kx, ky, kz] = q.axes();
    let s = q.shear();
    let rel = |axis: usize| load(&tris.v[3 * k + axis], first) - F::splat(o[axis]);
    let (x, y, z) = (rel(kx), rel(ky), rel(kz));
    (
        x + F::splat(s.x) * z,
        y + F::splat(s.y) * z,
        F::splat(s.z) * z,
    )
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
    let (det, t_scaled) = (l.det.lane(i), l.t_scaled.lane(i));
    let bound = t_max * det;
    !((det < 0.0 && t_scaled < bound) || (det > 0.0 && t_scaled > bound))
}

/// [`crate::geometry::store::closest_triangle_scalar`], [`LANES`] triangles at a time.
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
        for i in l.candidate.lanes() {
            if within(&l, i, *t_max) {
                let inv_det = l.inv_det.lane(i);
                let t = l.t_scaled.lane(i) * inv_det;
                *t_max = t;
                best = Some((
                    first + i,
                    TriangleHit {
                        t,
                        b1: l.e1.lane(i) * inv_det,
                        b2: l.e2.lane(i) * inv_det,
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
        Chunk::Lanes(l) => l.candidate.lanes().any(|i| within(&l, i, t_max)),
    })
}
